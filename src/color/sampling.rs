//! Wavelength-sampling strategies and the precomputed weight tables that turn
//! a sampled spectrum into XYZ or linear sRGB with one dot product per channel.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::cie_tables::{CMF_1931_2DEG, CMF_START_NM, D65_5NM, D65_START_NM};
use super::space::{mat_vec, srgb};
use crate::error::{Error, Result};
use crate::optics::lanes::SpectralWeights;

/// The paper's three wavelengths, taken directly as R, G and B.
pub const RGB3_WAVELENGTHS_NM: [f64; 3] = [650.0, 510.0, 475.0];

/// The visible range the paper's uniform sampling spans.
pub const UNIFORM_RANGE_NM: (f64, f64) = (380.0, 780.0);

/// Largest N accepted by `uniform:N` (0.01 nm spacing): beyond that the
/// result no longer changes and the tables only cost memory.
pub const UNIFORM_MAX_SAMPLES: usize = 40_001;

/// How a spectrum is sampled and reduced to a colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum Sampling {
    /// Reflectance at 650, 510 and 475 nm taken directly as R, G, B.
    Rgb3,
    /// N samples uniformly over 380–780 nm, integrated against CMF × D65.
    Uniform(usize),
    /// 1 nm integration over the full CMF range 360–830 nm: the reference.
    Exact,
}

impl FromStr for Sampling {
    type Err = Error;

    fn from_str(spec: &str) -> Result<Self> {
        let bad = |why: String| Error::invalid(format!("sampling '{spec}'"), why);
        match spec.trim() {
            "rgb3" => Ok(Sampling::Rgb3),
            "exact" => Ok(Sampling::Exact),
            s => {
                let Some(n) = s.strip_prefix("uniform:") else {
                    return Err(bad("expected rgb3, exact or uniform:N".into()));
                };
                let n: usize = n
                    .trim()
                    .parse()
                    .map_err(|_| bad(format!("'{n}' is not a whole number")))?;
                if !(2..=UNIFORM_MAX_SAMPLES).contains(&n) {
                    return Err(bad(format!(
                        "N must be between 2 and {UNIFORM_MAX_SAMPLES}, got {n}"
                    )));
                }
                Ok(Sampling::Uniform(n))
            }
        }
    }
}

impl fmt::Display for Sampling {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Sampling::Rgb3 => f.write_str("rgb3"),
            Sampling::Uniform(n) => write!(f, "uniform:{n}"),
            Sampling::Exact => f.write_str("exact"),
        }
    }
}

impl TryFrom<String> for Sampling {
    type Error = Error;
    fn try_from(s: String) -> Result<Self> {
        s.parse()
    }
}

impl From<Sampling> for String {
    fn from(s: Sampling) -> String {
        s.to_string()
    }
}

impl Sampling {
    /// The wavelengths at which a spectrum must be supplied, ascending.
    pub fn wavelengths_nm(&self) -> Vec<f64> {
        match *self {
            Sampling::Rgb3 => {
                let mut w = RGB3_WAVELENGTHS_NM.to_vec();
                w.sort_by(f64::total_cmp);
                w
            }
            Sampling::Uniform(n) => {
                let (lo, hi) = UNIFORM_RANGE_NM;
                // i·(hi−lo)/(n−1) rather than repeated steps: the ends are exact.
                (0..n)
                    .map(|i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
                    .collect()
            }
            Sampling::Exact => (0..CMF_1931_2DEG.len())
                .map(|i| CMF_START_NM + i as f64)
                .collect(),
        }
    }
}

/// What a perfect reflector's colour is made of, and so what (1, 1, 1) means
/// in the linear sRGB a stack's colour is given in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum White {
    /// The spectrum under CIE D65, taken to linear sRGB through XYZ with the
    /// tables' own D65 white: a perfect reflector is (1, 1, 1). irid's
    /// default and its tracer's convention.
    #[default]
    D65,
    /// The spectrum as it is (the equal-energy illuminant E), against the
    /// CIE 1931 observer's linear-sRGB colour-matching functions, each
    /// channel scaled so that a flat spectrum gives (1, 1, 1): the
    /// convention of Blender Cycles and the glTF sample viewer.
    E,
}

impl White {
    /// How the white is named in headers and film.json.
    pub fn name(self) -> &'static str {
        match self {
            White::D65 => "d65",
            White::E => "e",
        }
    }

    /// The illuminant, as a table header's `color.illuminant` spells it.
    pub fn illuminant(self) -> &'static str {
        match self {
            White::D65 => "CIE D65",
            White::E => "CIE E (equal energy), each sRGB channel normalized to a flat spectrum",
        }
    }

    /// Whether this is the default D65 white (serde uses it to leave the
    /// white out of headers and specs, keeping D65 files unchanged).
    pub fn is_d65(&self) -> bool {
        *self == White::D65
    }
}

impl FromStr for White {
    type Err = Error;
    fn from_str(s: &str) -> Result<White> {
        match s.trim() {
            "d65" | "D65" => Ok(White::D65),
            "e" | "E" => Ok(White::E),
            _ => Err(Error::invalid(format!("white '{s}'"), "expected d65 or e")),
        }
    }
}

impl fmt::Display for White {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Turns spectra sampled at [`SpectralIntegrator::wavelengths_nm`] into XYZ or
/// linear sRGB. All weights are computed once here; `xyz` and `rgb` are dot
/// products with no allocation or interpolation.
#[derive(Clone, Debug)]
pub struct SpectralIntegrator {
    sampling: Sampling,
    white: White,
    wavelengths_nm: Vec<f64>,
    /// Per channel (structure of arrays, so each dot product vectorizes).
    xyz_weights: [Vec<f64>; 3],
    rgb_weights: [Vec<f64>; 3],
}

impl SpectralIntegrator {
    /// The integrator of irid's default white, D65.
    pub fn new(sampling: Sampling) -> SpectralIntegrator {
        SpectralIntegrator::with_white(sampling, White::D65)
    }

    /// The integrator for a white convention. `rgb3` takes R, G and B at its
    /// three wavelengths whatever the white.
    pub fn with_white(sampling: Sampling, white: White) -> SpectralIntegrator {
        let wavelengths_nm = sampling.wavelengths_nm();
        let m = srgb();
        if white == White::E && sampling != Sampling::Rgb3 {
            // CMF to linear sRGB at each sample, each channel scaled so
            // its weights sum to 1: a flat spectrum v gives (v, v, v).
            let raw: Vec<[f64; 3]> = wavelengths_nm
                .iter()
                .map(|&w| mat_vec(&m.xyz_to_rgb, cmf_at(w)))
                .collect();
            let rgb = normalized_channels(&raw);
            let xyz: Vec<[f64; 3]> = rgb.iter().map(|w| mat_vec(&m.rgb_to_xyz, *w)).collect();
            return SpectralIntegrator {
                sampling,
                white,
                wavelengths_nm,
                xyz_weights: split_channels(&xyz),
                rgb_weights: split_channels(&rgb),
            };
        }
        // Per-sample weight triples in both spaces.
        let (xyz, rgb): (Vec<[f64; 3]>, Vec<[f64; 3]>) = match sampling {
            Sampling::Rgb3 => wavelengths_nm
                .iter()
                .map(|&w| {
                    let channel = RGB3_WAVELENGTHS_NM
                        .iter()
                        .position(|&c| c == w)
                        .expect("rgb3 wavelengths come from RGB3_WAVELENGTHS_NM");
                    let mut rgb = [0.0; 3];
                    rgb[channel] = 1.0;
                    (mat_vec(&m.rgb_to_xyz, rgb), rgb)
                })
                .unzip(),
            Sampling::Exact => {
                // Σ S D65 x̄ Δλ / Σ D65 ȳ Δλ (Δλ cancels): a perfect reflector has
                // Y = 1 and the XYZ of the table's own D65 white, which the sRGB
                // matrix maps to exactly (1, 1, 1).
                let xyz = exact_xyz_weights();
                let rgb = xyz.iter().map(|w| mat_vec(&m.xyz_to_rgb, *w)).collect();
                (xyz, rgb)
            }
            Sampling::Uniform(_) => {
                // CMF × D65 at the samples, taken to linear sRGB, then each RGB
                // channel scaled so its weights sum to 1: a flat spectrum maps to
                // exactly its value in R, G and B. In XYZ this is the same
                // diagonal scaling applied in sRGB (a white balance of the sparse
                // sum onto the D65 white), so a flat spectrum v gives v × white
                // and Y = v, while a coloured spectrum's XYZ is not the plain
                // CMF sum renormalized per XYZ channel.
                let raw: Vec<[f64; 3]> = wavelengths_nm
                    .iter()
                    .map(|&w| {
                        let d = d65_at(w);
                        let c = cmf_at(w);
                        mat_vec(&m.xyz_to_rgb, [c[0] * d, c[1] * d, c[2] * d])
                    })
                    .collect();
                let rgb = normalized_channels(&raw);
                let xyz = rgb.iter().map(|w| mat_vec(&m.rgb_to_xyz, *w)).collect();
                (xyz, rgb)
            }
        };
        SpectralIntegrator {
            sampling,
            white: White::D65,
            wavelengths_nm,
            xyz_weights: split_channels(&xyz),
            rgb_weights: split_channels(&rgb),
        }
    }

    /// The same integral with `m` points per step of the exact sampling.
    /// Each 1 nm weight stands for the spectrum averaged under a hat of
    /// unit area around its wavelength (half a hat, rescaled to unit area,
    /// at the two ends of the range); the refined sum samples those hats at
    /// `m` points per step, so a point between two wavelengths gets the
    /// linear interpolation of their weights, divided by `m`. A spectrum
    /// smooth on the scale of a step integrates as the 1 nm sum does (a flat
    /// one exactly, to rounding), and one with features narrower than a
    /// step converges as `m` grows. `m` = 1 and other samplings are
    /// returned as they are.
    pub fn refined(&self, m: usize) -> SpectralIntegrator {
        if m <= 1 || self.sampling != Sampling::Exact || self.wavelengths_nm.len() < 2 {
            return self.clone();
        }
        let n = self.wavelengths_nm.len();
        let step = self.wavelengths_nm[1] - self.wavelengths_nm[0];
        let points = (n - 1) * m + 1;
        let wavelengths_nm = (0..points)
            .map(|k| self.wavelengths_nm[0] + step * k as f64 / m as f64)
            .collect();
        let mf = m as f64;
        // Sum over one hat of its samples' heights: m inside, (m + 1) / 2
        // for the half hats at the ends.
        let area = |i: usize| {
            if i == 0 || i == n - 1 {
                0.5 * (mf + 1.0)
            } else {
                mf
            }
        };
        let spread = |w: &Vec<f64>| -> Vec<f64> {
            (0..points)
                .map(|k| {
                    let (i, j) = (k / m, k % m);
                    let t = j as f64 / mf;
                    if j == 0 {
                        w[i] / area(i)
                    } else {
                        w[i] * (1.0 - t) / area(i) + w[i + 1] * t / area(i + 1)
                    }
                })
                .collect()
        };
        SpectralIntegrator {
            sampling: self.sampling,
            white: self.white,
            wavelengths_nm,
            xyz_weights: std::array::from_fn(|c| spread(&self.xyz_weights[c])),
            rgb_weights: std::array::from_fn(|c| spread(&self.rgb_weights[c])),
        }
    }

    /// The wavelength sampling strategy this integrator was built for.
    pub fn sampling(&self) -> Sampling {
        self.sampling
    }

    /// The white convention: which spectrum integrates to (1, 1, 1). D65
    /// for `rgb3`, which takes R, G and B at three wavelengths whatever
    /// white was asked for.
    pub fn white(&self) -> White {
        self.white
    }

    /// Where the spectrum must be sampled, ascending; `xyz`/`rgb` expect one
    /// value per entry, in this order.
    pub fn wavelengths_nm(&self) -> &[f64] {
        &self.wavelengths_nm
    }

    /// The linear-sRGB weight of each sample, per channel (R, G, B), for
    /// callers that fold the integration into their own loops.
    pub fn rgb_weights(&self) -> &[Vec<f64>; 3] {
        &self.rgb_weights
    }

    /// [`Self::rgb_weights`] laid out for the batched solver, which then
    /// integrates a spectrum to linear sRGB as it solves it
    /// ([`StackGrid::weighted_spectrum`](crate::optics::StackGrid::weighted_spectrum)),
    /// with the same bits as [`Self::rgb`] on the stored spectrum.
    pub fn rgb_lane_weights(&self) -> SpectralWeights {
        let [r, g, b] = &self.rgb_weights;
        SpectralWeights::new([r, g, b])
    }

    /// CIE XYZ (Y = 1 for a perfect reflector) of a spectrum sampled at
    /// [`Self::wavelengths_nm`].
    ///
    /// # Panics
    /// If `spectrum` does not have one value per wavelength.
    #[inline]
    pub fn xyz(&self, spectrum: &[f64]) -> [f64; 3] {
        apply(&self.xyz_weights, spectrum)
    }

    /// Linear sRGB ((1, 1, 1) for a perfect reflector) of a spectrum sampled
    /// at [`Self::wavelengths_nm`].
    ///
    /// # Panics
    /// If `spectrum` does not have one value per wavelength.
    #[inline]
    pub fn rgb(&self, spectrum: &[f64]) -> [f64; 3] {
        apply(&self.rgb_weights, spectrum)
    }
}

/// Weight triples with each channel scaled so that it sums to 1.
fn normalized_channels(raw: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut sums = [0.0; 3];
    for w in raw {
        for c in 0..3 {
            sums[c] += w[c];
        }
    }
    raw.iter()
        .map(|w| [w[0] / sums[0], w[1] / sums[1], w[2] / sums[2]])
        .collect()
}

fn split_channels(w: &[[f64; 3]]) -> [Vec<f64>; 3] {
    std::array::from_fn(|c| w.iter().map(|t| t[c]).collect())
}

#[inline]
fn apply(weights: &[Vec<f64>; 3], spectrum: &[f64]) -> [f64; 3] {
    assert_eq!(
        spectrum.len(),
        weights[0].len(),
        "spectrum length must match the integrator's wavelengths"
    );
    [
        dot(&weights[0], spectrum),
        dot(&weights[1], spectrum),
        dot(&weights[2], spectrum),
    ]
}

/// Dot product with eight independent partial sums (sum k takes the terms
/// i ≡ k mod 8), so the additions do not form one serial dependency chain and
/// the loop vectorizes. The lane kernels' colour sink adds in this same order
/// (one AVX-512 register of sums per channel), so a colour folded in as the
/// spectrum is solved has the bits of this one.
#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0; 8];
    let (a8, b8) = (a.chunks_exact(8), b.chunks_exact(8));
    let tail: f64 = a8
        .remainder()
        .iter()
        .zip(b8.remainder())
        .map(|(x, y)| x * y)
        .sum();
    for (x, y) in a8.zip(b8) {
        for k in 0..8 {
            acc[k] += x[k] * y[k];
        }
    }
    ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7])) + tail
}

/// Exact-strategy XYZ weights, D65 × CMF at 1 nm over 360–830 nm, normalized by
/// Σ D65 ȳ.
pub(crate) fn exact_xyz_weights() -> Vec<[f64; 3]> {
    let raw: Vec<[f64; 3]> = CMF_1931_2DEG
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let d = d65_at(CMF_START_NM + i as f64);
            [c[0] * d, c[1] * d, c[2] * d]
        })
        .collect();
    let k: f64 = raw.iter().map(|w| w[1]).sum();
    raw.iter().map(|w| [w[0] / k, w[1] / k, w[2] / k]).collect()
}

/// Linear interpolation in a uniformly spaced table; zero outside it.
fn lerp_table<const N: usize, T: Copy>(
    table: &[T; N],
    start_nm: f64,
    step_nm: f64,
    wavelength_nm: f64,
    get: impl Fn(T) -> f64,
) -> f64 {
    let pos = (wavelength_nm - start_nm) / step_nm;
    if !(pos >= 0.0 && pos <= (N - 1) as f64) {
        return 0.0;
    }
    let i = (pos.floor() as usize).min(N - 2);
    let t = pos - i as f64;
    let (a, b) = (get(table[i]), get(table[i + 1]));
    // Exactly the node value when t = 0, so integer wavelengths reproduce the
    // 1 nm table bit for bit.
    if t == 0.0 {
        a
    } else {
        a + (b - a) * t
    }
}

/// CIE D65 relative power, linearly interpolated from the 5 nm table (the
/// interpolation CIE 015 recommends for daylight illuminants).
pub(crate) fn d65_at(wavelength_nm: f64) -> f64 {
    lerp_table(&D65_5NM, D65_START_NM, 5.0, wavelength_nm, |v| v)
}

/// CIE 1931 2° x̄, ȳ, z̄, linearly interpolated from the 1 nm table.
pub(crate) fn cmf_at(wavelength_nm: f64) -> [f64; 3] {
    std::array::from_fn(|c| lerp_table(&CMF_1931_2DEG, CMF_START_NM, 1.0, wavelength_nm, |v| v[c]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_prints() {
        for (s, v) in [
            ("rgb3", Sampling::Rgb3),
            ("exact", Sampling::Exact),
            ("uniform:41", Sampling::Uniform(41)),
            ("uniform:2", Sampling::Uniform(2)),
        ] {
            assert_eq!(s.parse::<Sampling>().unwrap(), v);
            assert_eq!(v.to_string(), s);
        }
        for bad in [
            "",
            "rgb",
            "uniform",
            "uniform:",
            "uniform:1",
            "uniform:0",
            "uniform:-3",
            "uniform:4.5",
            "uniform:40002",
            "Exact2",
        ] {
            let e = bad.parse::<Sampling>().unwrap_err().to_string();
            assert!(e.contains("sampling"), "{bad}: {e}");
        }
        let json = serde_json::to_string(&Sampling::Uniform(9)).unwrap();
        assert_eq!(json, "\"uniform:9\"");
        assert_eq!(
            serde_json::from_str::<Sampling>(&json).unwrap(),
            Sampling::Uniform(9)
        );
        assert!(serde_json::from_str::<Sampling>("\"uniform:1\"").is_err());
    }

    #[test]
    fn wavelength_grids() {
        assert_eq!(Sampling::Rgb3.wavelengths_nm(), vec![475.0, 510.0, 650.0]);
        let u9 = Sampling::Uniform(9).wavelengths_nm();
        assert_eq!(
            u9,
            (0..9).map(|i| 380.0 + 50.0 * i as f64).collect::<Vec<_>>()
        );
        let ex = Sampling::Exact.wavelengths_nm();
        assert_eq!((ex.len(), ex[0], ex[470]), (471, 360.0, 830.0));
    }

    #[test]
    fn interpolation_hits_table_nodes() {
        assert_eq!(d65_at(560.0), 100.0);
        assert_eq!(d65_at(300.0), 0.0341);
        assert_eq!(d65_at(830.0), 60.3125);
        assert!((d65_at(562.0) - (100.0 + (98.1671 - 100.0) * 0.4)).abs() < 1e-12);
        assert_eq!(cmf_at(360.0), CMF_1931_2DEG[0]);
        assert_eq!(cmf_at(830.0), CMF_1931_2DEG[470]);
        assert_eq!(cmf_at(555.0), CMF_1931_2DEG[195]);
        assert_eq!(cmf_at(359.0), [0.0; 3]);
        assert_eq!(d65_at(831.0), 0.0);
    }

    #[test]
    fn dot_matches_naive_sum() {
        let a: Vec<f64> = (0..11).map(|i| i as f64 * 0.5).collect();
        let b: Vec<f64> = (0..11).map(|i| 1.0 + i as f64).collect();
        let naive: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
        assert!((dot(&a, &b) - naive).abs() < 1e-12);
    }
}
