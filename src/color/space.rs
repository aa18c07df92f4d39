//! Colour spaces: linear sRGB ↔ XYZ, CIE Lab and CIEDE2000 (see
//! [`super::ciede2000`]), and 8-bit sRGB encoding (through the `palette`
//! crate).

use std::sync::LazyLock;

use palette::{LinSrgb, Srgb};

use super::sampling::exact_xyz_weights;

/// IEC 61966-2-1 (sRGB) primaries, CIE 1931 xy chromaticities.
const SRGB_PRIMARIES_XY: [[f64; 2]; 3] = [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]];

pub(crate) struct SrgbMatrices {
    pub white_xyz: [f64; 3],
    pub rgb_to_xyz: [[f64; 3]; 3],
    pub xyz_to_rgb: [[f64; 3]; 3],
}

/// The sRGB matrices built from the IEC primaries and the white of our own
/// D65 and CMF tables, rather than the standard's printed matrix (which uses
/// the rounded white xy = 0.3127, 0.3290). The two differ by ~1e-4; building
/// from the tables' white makes a perfect reflector integrate to exactly
/// (1, 1, 1) up to rounding, so "white" is white in every strategy, and Lab's
/// reference white is the same XYZ the integration produces.
static SRGB: LazyLock<SrgbMatrices> = LazyLock::new(|| {
    let white_xyz = exact_xyz_weights().iter().fold([0.0; 3], |acc, w| {
        [acc[0] + w[0], acc[1] + w[1], acc[2] + w[2]]
    });
    // Columns: XYZ of each primary at Y = 1, then scaled so they sum to white.
    let p: [[f64; 3]; 3] = {
        let col = |[x, y]: [f64; 2]| [x / y, 1.0, (1.0 - x - y) / y];
        let (r, g, b) = (
            col(SRGB_PRIMARIES_XY[0]),
            col(SRGB_PRIMARIES_XY[1]),
            col(SRGB_PRIMARIES_XY[2]),
        );
        [[r[0], g[0], b[0]], [r[1], g[1], b[1]], [r[2], g[2], b[2]]]
    };
    let s = mat_vec(&invert(&p), white_xyz);
    let rgb_to_xyz = std::array::from_fn(|i| std::array::from_fn(|j| p[i][j] * s[j]));
    SrgbMatrices {
        white_xyz,
        rgb_to_xyz,
        xyz_to_rgb: invert(&rgb_to_xyz),
    }
});

pub(crate) fn srgb() -> &'static SrgbMatrices {
    &SRGB
}

#[inline]
pub(crate) fn mat_vec(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

/// 3×3 inverse by cofactors (the matrices here are well conditioned).
fn invert(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let c = |i: usize, j: usize| {
        let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
        let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
        m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    // Transposed cofactors over the determinant.
    std::array::from_fn(|i| std::array::from_fn(|j| c(j, i) / det))
}

/// XYZ of the D65 white the tables integrate to (a perfect reflector), Y = 1.
pub fn white_xyz() -> [f64; 3] {
    SRGB.white_xyz
}

/// CIE XYZ to linear sRGB (BT.709 primaries), with the matrix built from
/// the tables' own D65 white so [`white_xyz`] maps to exactly (1, 1, 1) up
/// to rounding. No clamping: out-of-gamut colours get negative components.
#[inline]
pub fn xyz_to_linear_srgb(xyz: [f64; 3]) -> [f64; 3] {
    mat_vec(&SRGB.xyz_to_rgb, xyz)
}

/// Linear sRGB (BT.709 primaries) to CIE XYZ, the exact inverse of
/// [`xyz_to_linear_srgb`]: (1, 1, 1) maps to [`white_xyz`], Y = 1.
#[inline]
pub fn linear_srgb_to_xyz(rgb: [f64; 3]) -> [f64; 3] {
    mat_vec(&SRGB.rgb_to_xyz, rgb)
}

/// CIE Lab (D65 white, Y_white = 1) of an XYZ colour: the white is the
/// tables' own, so Lab of a perfect reflector is (100, 0, 0). Not clamped:
/// a colour brighter than the white has L above 100.
pub fn xyz_to_lab(xyz: [f64; 3]) -> [f64; 3] {
    super::ciede2000::lab(xyz, SRGB.white_xyz)
}

/// CIEDE2000 colour difference (k_L = k_C = k_H = 1) between two Lab colours.
pub fn delta_e2000(lab_a: [f64; 3], lab_b: [f64; 3]) -> f64 {
    super::ciede2000::delta_e2000(lab_a, lab_b)
}

/// CIEDE2000 between two linear-sRGB colours.
pub fn delta_e2000_rgb(a: [f64; 3], b: [f64; 3]) -> f64 {
    delta_e2000(
        xyz_to_lab(linear_srgb_to_xyz(a)),
        xyz_to_lab(linear_srgb_to_xyz(b)),
    )
}

/// 8-bit sRGB (IEC 61966-2-1 transfer curve) of a linear-sRGB colour, each
/// channel clamped to [0, 1] first (NaN becomes 0).
pub fn linear_to_srgb8(rgb: [f64; 3]) -> [u8; 3] {
    let c = |v: f64| if v > 0.0 { v.min(1.0) } else { 0.0 };
    let encoded: Srgb<u8> = Srgb::from_linear(LinSrgb::new(c(rgb[0]), c(rgb[1]), c(rgb[2])));
    [encoded.red, encoded.green, encoded.blue]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matrices_invert_and_map_white() {
        let m = srgb();
        let id = std::array::from_fn::<_, 3, _>(|i| {
            mat_vec(
                &m.xyz_to_rgb,
                [m.rgb_to_xyz[0][i], m.rgb_to_xyz[1][i], m.rgb_to_xyz[2][i]],
            )
        });
        for (i, row) in id.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((v - want).abs() < 1e-14, "{id:?}");
            }
        }
        let w = xyz_to_linear_srgb(white_xyz());
        assert!(w.iter().all(|c| (c - 1.0).abs() < 1e-14), "{w:?}");
        // Close to the standard's printed matrix (white xy rounded to 4 digits).
        let iec = [
            [3.2406, -1.5372, -0.4986],
            [-0.9689, 1.8758, 0.0415],
            [0.0557, -0.2040, 1.0570],
        ];
        for (got, want) in m.xyz_to_rgb.iter().flatten().zip(iec.iter().flatten()) {
            assert!((got - want).abs() < 2e-3, "{got} vs {want}");
        }
    }

    /// palette's white point set to the tables' D65 white.
    struct TableD65;

    impl palette::white_point::WhitePoint<f64> for TableD65 {
        fn get_xyz() -> palette::Xyz<palette::white_point::Any, f64> {
            let [x, y, z] = SRGB.white_xyz;
            palette::Xyz::new(x, y, z)
        }
    }

    /// Lab and CIEDE2000 against `palette`'s implementation, over random
    /// colours of every lightness and chroma, neutral ones, and pairs as
    /// close as the validation's (a table's colour against the exact one).
    #[test]
    fn lab_and_ciede2000_match_palette() {
        use palette::color_difference::Ciede2000;
        use palette::convert::FromColorUnclamped;
        use palette::{Lab, Xyz};
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        let palette_lab = |xyz: [f64; 3]| {
            let lab = Lab::<TableD65, f64>::from_color_unclamped(Xyz::<TableD65, f64>::new(
                xyz[0], xyz[1], xyz[2],
            ));
            [lab.l, lab.a, lab.b]
        };
        let palette_de = |a: [f64; 3], b: [f64; 3]| {
            Lab::<TableD65, f64>::new(a[0], a[1], a[2])
                .difference(Lab::<TableD65, f64>::new(b[0], b[1], b[2]))
        };
        let mut worst_lab = 0.0f64;
        let mut worst_de = 0.0f64;
        let (mut worst_other_mean, mut other_mean) = (0.0f64, 0);
        for i in 0..100_000 {
            let rgb: [f64; 3] = std::array::from_fn(|_| rng.random_range(-0.2..1.5));
            let near = match i % 3 {
                0 => std::array::from_fn(|_| rng.random_range(-0.2..1.5)),
                1 => rgb.map(|c| c + rng.random_range(-1e-3..1e-3)),
                _ => {
                    let grey = rng.random_range(0.0..1.0);
                    [grey; 3]
                }
            };
            for c in [rgb, near] {
                let xyz = linear_srgb_to_xyz(c);
                let (got, want) = (xyz_to_lab(xyz), palette_lab(xyz));
                for k in 0..3 {
                    worst_lab = worst_lab.max((got[k] - want[k]).abs());
                }
            }
            let (a, b) = (
                palette_lab(linear_srgb_to_xyz(rgb)),
                palette_lab(linear_srgb_to_xyz(near)),
            );
            let (got, want) = (delta_e2000(a, b), palette_de(a, b));
            let diff = (got - want).abs() / want.max(1e-3);
            if mean_hues_differ(a, b) {
                worst_other_mean = worst_other_mean.max(diff);
                other_mean += 1;
            } else {
                worst_de = worst_de.max(diff);
            }
        }
        assert!(
            worst_lab < 1e-12,
            "Lab differs from palette's by {worst_lab:e}"
        );
        assert!(
            worst_de < 1e-9,
            "CIEDE2000 differs from palette's by {worst_de:e} (relative)"
        );
        // Where the hues are more than 180° apart and sum to 360° or more,
        // Sharma et al. take their mean as (h₁ + h₂ − 360°)/2 and palette as
        // (h₁ + h₂ + 360°)/2: the hue weighting T agrees (it is periodic),
        // the rotation term's Δθ does not, by a little.
        assert!(
            other_mean > 1000,
            "{other_mean} pairs take the other mean hue"
        );
        assert!(worst_other_mean < 1e-5, "{worst_other_mean:e}");
    }

    /// Whether the pair's mean hue is where Sharma's rule and palette's part
    /// (h' as CIEDE2000 defines it, from the chroma-adjusted a').
    fn mean_hues_differ(lab1: [f64; 3], lab2: [f64; 3]) -> bool {
        let chroma = |l: [f64; 3]| l[1].hypot(l[2]);
        let c_bar = 0.5 * (chroma(lab1) + chroma(lab2));
        let g = 0.5 * (1.0 - (c_bar.powi(7) / (c_bar.powi(7) + 25f64.powi(7))).sqrt());
        let hue = |l: [f64; 3]| {
            let h = l[2].atan2((1.0 + g) * l[1]).to_degrees();
            if h < 0.0 {
                h + 360.0
            } else {
                h
            }
        };
        let (h1, h2) = (hue(lab1), hue(lab2));
        chroma(lab1) > 0.0 && chroma(lab2) > 0.0 && (h2 - h1).abs() > 180.0 && h1 + h2 >= 360.0
    }

    #[test]
    fn srgb8_encoding() {
        assert_eq!(linear_to_srgb8([0.0, 1.0, 0.5]), [0, 255, 188]);
        assert_eq!(linear_to_srgb8([-1.0, 2.0, f64::NAN]), [0, 255, 0]);
        // 0.0031308 is where the curve turns from linear to the power law.
        assert_eq!(linear_to_srgb8([0.0031308, 0.18, 0.002])[1], 118);
    }
}
