//! CIE Lab and the CIEDE2000 colour difference, written out from their
//! definitions: CIE 15:2004 for Lab, and for CIEDE2000 the equations as
//! Sharma, Wu and Dalal state them ("The CIEDE2000 color-difference formula:
//! implementation notes, supplementary test data, and mathematical
//! observations", Color Research & Application 30(1), 2005), mean hue
//! included. The validation compares two colours at each of its points, so
//! this runs tens of thousands of times per bake: the four cosines of the
//! hue weighting come from one sine and cosine by multiple-angle identities,
//! and the cube root from a short iteration instead of a correctly rounded
//! library call. The tests hold both to `palette`'s implementation and to
//! Sharma's published pairs.

use std::f64::consts::PI;

/// (6/29)³: below it, Lab's f(t) is the linear segment.
pub(crate) const LAB_EPSILON: f64 = 216.0 / 24_389.0;
/// (29/3)³: the linear segment's slope times 116.
pub(crate) const LAB_KAPPA: f64 = 24_389.0 / 27.0;

/// CIE Lab of XYZ relative to the white `white_xyz`.
pub(crate) fn lab(xyz: [f64; 3], white_xyz: [f64; 3]) -> [f64; 3] {
    let f = |t: f64| {
        if t > LAB_EPSILON {
            cbrt(t)
        } else {
            (LAB_KAPPA * t + 16.0) / 116.0
        }
    };
    let [fx, fy, fz] = [0, 1, 2].map(|k| f(xyz[k] / white_xyz[k]));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// The cube root of `x`, within an ulp or so. A guess from the exponent
/// (the bits divided by three, about 5 % off), then two Halley steps
/// t ← t (t³ + 2x) / (2t³ + x), each of which cubes the relative error
/// (5 % → 10⁻⁴ → 10⁻¹²), and one Newton step that squares it below the
/// rounding. Numbers outside [10⁻⁹⁰, 10⁹⁰] (where t³ could leave the
/// range of doubles), zero, negatives and NaN go to the library.
fn cbrt(x: f64) -> f64 {
    if !(1.0e-90..=1.0e90).contains(&x) {
        return x.cbrt();
    }
    // The bits of 2^(k/3) for x = 2^k: a third of the exponent's, plus two
    // thirds of the bias (1023 · 2/3 · 2^52, rounded), which the division
    // took away.
    const BIAS_TWO_THIRDS: u64 = 0x2A9F_7893_782D_A1CE;
    let mut t = f64::from_bits(x.to_bits() / 3 + BIAS_TWO_THIRDS);
    for _ in 0..2 {
        let t3 = t * t * t;
        t *= (t3 + 2.0 * x) / (2.0 * t3 + x);
    }
    t - (t * t * t - x) / (3.0 * t * t)
}

/// CIEDE2000 (k_L = k_C = k_H = 1) between two Lab colours.
pub(crate) fn delta_e2000(lab1: [f64; 3], lab2: [f64; 3]) -> f64 {
    const POW25_7: f64 = 6_103_515_625.0; // 25⁷
    let deg = PI / 180.0;
    let [l1, a1, b1] = lab1;
    let [l2, a2, b2] = lab2;
    // The a axis stretched near neutral (G), and C', h' from it.
    let c_bar = 0.5 * ((a1 * a1 + b1 * b1).sqrt() + (a2 * a2 + b2 * b2).sqrt());
    let c_bar7 = c_bar.powi(7);
    let g = 0.5 * (1.0 - (c_bar7 / (c_bar7 + POW25_7)).sqrt());
    let (a1p, a2p) = ((1.0 + g) * a1, (1.0 + g) * a2);
    let (c1p, c2p) = ((a1p * a1p + b1 * b1).sqrt(), (a2p * a2p + b2 * b2).sqrt());
    let hue = |b: f64, ap: f64| {
        if b == 0.0 && ap == 0.0 {
            0.0
        } else {
            let h = b.atan2(ap) / deg;
            if h < 0.0 {
                h + 360.0
            } else {
                h
            }
        }
    };
    let (h1p, h2p) = (hue(b1, a1p), hue(b2, a2p));

    let dl = l2 - l1;
    let dc = c2p - c1p;
    let neutral = c1p * c2p == 0.0;
    let dh_deg = h2p - h1p;
    let dh = if neutral {
        0.0
    } else if dh_deg.abs() <= 180.0 {
        dh_deg
    } else if dh_deg > 180.0 {
        dh_deg - 360.0
    } else {
        dh_deg + 360.0
    };
    let big_dh = 2.0 * (c1p * c2p).sqrt() * (0.5 * dh * deg).sin();

    let l_bar = 0.5 * (l1 + l2);
    let cp_bar = 0.5 * (c1p + c2p);
    let h_sum = h1p + h2p;
    let hp_bar = if neutral {
        h_sum
    } else if dh_deg.abs() <= 180.0 {
        0.5 * h_sum
    } else if h_sum < 360.0 {
        0.5 * (h_sum + 360.0)
    } else {
        0.5 * (h_sum - 360.0)
    };

    // T = 1 − 0.17 cos(h̄ − 30°) + 0.24 cos 2h̄ + 0.32 cos(3h̄ + 6°)
    //       − 0.20 cos(4h̄ − 63°), every term from cos h̄ and sin h̄.
    let (s1, c1) = (hp_bar * deg).sin_cos();
    let (s2, c2) = (2.0 * s1 * c1, c1 * c1 - s1 * s1);
    let (s3, c3) = (s2 * c1 + c2 * s1, c2 * c1 - s2 * s1);
    let (s4, c4) = (2.0 * s2 * c2, c2 * c2 - s2 * s2);
    let angle = |d: f64| (d * deg).sin_cos();
    let ((s30, c30), (s6, c6), (s63, c63)) = (angle(30.0), angle(6.0), angle(63.0));
    let t = 1.0 - 0.17 * (c1 * c30 + s1 * s30) + 0.24 * c2 + 0.32 * (c3 * c6 - s3 * s6)
        - 0.20 * (c4 * c63 + s4 * s63);

    let l50 = (l_bar - 50.0) * (l_bar - 50.0);
    let s_l = 1.0 + 0.015 * l50 / (20.0 + l50).sqrt();
    let s_c = 1.0 + 0.045 * cp_bar;
    let s_h = 1.0 + 0.015 * cp_bar * t;
    let x = (hp_bar - 275.0) / 25.0;
    let d_theta = 30.0 * (-(x * x)).exp();
    let cp_bar7 = cp_bar.powi(7);
    let r_c = 2.0 * (cp_bar7 / (cp_bar7 + POW25_7)).sqrt();
    let r_t = -r_c * (2.0 * d_theta * deg).sin();

    let (tl, tc, th) = (dl / s_l, dc / s_c, big_dh / s_h);
    (tl * tl + tc * tc + th * th + r_t * tc * th).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn cube_root_within_an_ulp_or_two() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let mut xs: Vec<f64> = (0..200_000)
            .map(|_| 10f64.powf(rng.random_range(-300.0..300.0)))
            .collect();
        xs.extend([
            LAB_EPSILON,
            1.0,
            8.0,
            27.0,
            0.001,
            2.0,
            f64::MIN_POSITIVE,
            f64::MAX,
        ]);
        for x in xs {
            let (got, want) = (cbrt(x), x.cbrt());
            let ulps = (got.to_bits() as i64 - want.to_bits() as i64).abs();
            assert!(
                ulps <= 1,
                "cbrt({x:e}) = {got:e}, want {want:e} ({ulps} ulps)"
            );
        }
        assert_eq!(cbrt(0.0), 0.0);
        assert_eq!(cbrt(-8.0), -2.0);
        assert!(cbrt(f64::NAN).is_nan());
        assert_eq!(cbrt(f64::INFINITY), f64::INFINITY);
    }
}
