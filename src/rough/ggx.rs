//! The GGX (Trowbridge–Reitz) microfacet distribution and its
//! height-correlated Smith masking-shadowing, isotropic, in double
//! precision: the definition every rough figure of irid is computed from.
//! (The renderer has its own single-precision copy, `render::microfacet`,
//! tested against these.)
//!
//! References: B. Walter, S. Marschner, H. Li, K. Torrance, "Microfacet
//! models for refraction through rough surfaces", EGSR 2007 (D and Λ of
//! GGX); E. Heitz, "Understanding the masking-shadowing function in
//! microfacet-based BRDFs", JCGT 3(2), 2014 (the height-correlated G2).
//! The forms below are rearranged so that they stay accurate where the
//! textbook ones cancel or divide 0 by 0: Λ near the normal and at the
//! horizon, D near the normal at small α.

use std::f64::consts::PI;

/// GGX α from the artist's roughness in [0, 1]: α = roughness² (the
/// convention of Disney's principled BRDF, Blender and glTF).
#[inline]
pub fn alpha(roughness: f64) -> f64 {
    roughness * roughness
}

/// The GGX normal distribution D(h) for a microfacet normal at cos θ_h =
/// `cos_h` > 0 from the macro normal, given also 1 − cos² θ_h (which the
/// caller can often form without cancellation), and α².
///
/// D = α² / (π (cos²θ_h (α² − 1) + 1)²), written with 1 − cos² θ_h so
/// that it is accurate for microfacets near the normal at small α.
#[inline]
pub fn ndf(cos_h: f64, sin2_h: f64, alpha2: f64) -> f64 {
    let d = sin2_h + cos_h * cos_h * alpha2;
    alpha2 / (PI * d * d)
}

/// Λ(ω) · cos θ_ω for a direction at cos θ = `cos` ≥ 0 from the normal:
/// Λ = (√(1 + α² tan² θ) − 1) / 2, multiplied through by cos θ and
/// rationalized, so that it is finite at the horizon (α/2 there) and
/// loses nothing to cancellation near the normal.
#[inline]
pub fn lambda_cos(cos: f64, alpha2: f64) -> f64 {
    let sin2 = (1.0 - cos * cos).max(0.0);
    alpha2 * sin2 / (2.0 * ((cos * cos + alpha2 * sin2).sqrt() + cos))
}

/// Smith's masking of one direction, G1 = 1 / (1 + Λ); 0 at or below the
/// horizon.
#[inline]
pub fn g1(cos: f64, alpha2: f64) -> f64 {
    if cos <= 0.0 {
        return 0.0;
    }
    cos / (cos + lambda_cos(cos, alpha2))
}

/// The height-correlated masking-shadowing G2 = 1 / (1 + Λ(v) + Λ(l)) of a
/// view at cos θ_v > 0 and a light at cos θ_l (0 when the light is at or
/// below the horizon), with Λ(v)·cos θ_v given (it is fixed for a whole
/// lobe). Written as cos θ_v cos θ_l / (cos θ_v cos θ_l + cos θ_l Λ_v cos θ_v
/// + cos θ_v Λ_l cos θ_l), which goes smoothly to 0 at the horizon.
#[inline]
pub fn g2(cos_v: f64, lambda_cos_v: f64, cos_l: f64, alpha2: f64) -> f64 {
    if cos_l <= 0.0 {
        return 0.0;
    }
    let vl = cos_v * cos_l;
    vl / (vl + cos_l * lambda_cos_v + cos_v * lambda_cos(cos_l, alpha2))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rearranged forms agree with the textbook ones where those are
    /// accurate, and D integrates to 1 over projected area.
    #[test]
    fn forms_agree_with_the_textbook() {
        for &a in &[0.01, 0.1, 0.5, 1.0] {
            let a2: f64 = a * a;
            for &c in &[0.05, 0.3, 0.7, 0.99] {
                let tan2 = (1.0 - c * c) / (c * c);
                let lambda = ((1.0 + a2 * tan2).sqrt() - 1.0) / 2.0;
                let got = lambda_cos(c, a2) / c;
                assert!((got - lambda).abs() <= 1e-13 * (1.0 + lambda), "{a} {c}");
                let d = a2 / (PI * (c * c * (a2 - 1.0) + 1.0).powi(2));
                let got = ndf(c, 1.0 - c * c, a2);
                assert!((got - d).abs() <= 1e-12 * d, "{a} {c}: {got} vs {d}");
                let g = 1.0 / (1.0 + lambda + lambda);
                assert!((g2(c, lambda_cos(c, a2), c, a2) - g).abs() < 1e-13);
                assert!((g1(c, a2) - 1.0 / (1.0 + lambda)).abs() < 1e-13);
            }
            // ∫ D cos θ_h dω = 1, on a fine midpoint rule in tan θ_h.
            let n = 200_000;
            let (mut sum, t_max) = (0.0, 2000.0 * a);
            for i in 0..n {
                let t = (i as f64 + 0.5) / n as f64 * t_max;
                let c = 1.0 / (1.0 + t * t).sqrt();
                // dω = sin θ dθ dφ, dθ = c² dt, sin θ = t c.
                sum += ndf(c, t * t * c * c, a2) * c * (t * c) * c * c * (t_max / n as f64);
            }
            sum *= 2.0 * PI;
            assert!((sum - 1.0).abs() < 1e-5, "α {a}: {sum}");
        }
        assert_eq!(g1(0.0, 0.25), 0.0);
        assert_eq!(g2(0.5, 0.1, -0.1, 0.25), 0.0);
        // Finite and small just above the horizon.
        let g = g2(0.5, lambda_cos(0.5, 0.25), 1e-12, 0.25);
        assert!(g > 0.0 && g < 1e-10, "{g}");
    }
}
