//! The renderer's GGX lobe in single precision: sampling of visible
//! normals and the masking-shadowing weights, for the definition in
//! [`crate::rough::ggx`] (tested against it).
//!
//! Sampling follows E. Heitz, "Sampling the GGX Distribution of Visible
//! Normals", JCGT 7(4), 2018: stretch the view to the configuration where
//! α = 1, pick a point uniformly on the disc the visible half of the
//! hemisphere projects to (its lower half squashed onto the part that the
//! view sees), lift it onto the hemisphere and unstretch. The normal h then
//! has density G1(v) max(0, v·h) D(h) / (n·v), so a path through the
//! mirror direction of v about h carries F(v·h) G2(v, l) / G1(v).

use glam::Vec3;

/// An orthonormal basis (t, b) completing unit `n`, continuous except on a
/// measure-zero set (Duff et al., "Building an orthonormal basis,
/// revisited", JCGT 6(1), 2017).
#[inline]
pub fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// A microfacet normal for the view `v` (unit, in the frame whose z is the
/// macro normal, v.z > 0) drawn from GGX's distribution of visible normals
/// of roughness α, from two uniform numbers in [0, 1).
#[inline]
pub fn sample_visible_normal(v: Vec3, alpha: f32, u1: f32, u2: f32) -> Vec3 {
    // The view in the stretched configuration, where GGX is a hemisphere.
    let vs = Vec3::new(alpha * v.x, alpha * v.y, v.z).normalize();
    let across2 = vs.x * vs.x + vs.y * vs.y;
    let t1 = if across2 > 0.0 {
        Vec3::new(-vs.y, vs.x, 0.0) / across2.sqrt()
    } else {
        Vec3::X
    };
    let t2 = vs.cross(t1);
    // A uniform point on the unit disc, its lower half moved up by the
    // share of the disc the hemisphere's visible projection leaves out.
    let r = u1.sqrt();
    let (sin_phi, cos_phi) = (std::f32::consts::TAU * u2).sin_cos();
    let p1 = r * cos_phi;
    let s = 0.5 * (1.0 + vs.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * sin_phi;
    let lift = (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    let nh = p1 * t1 + p2 * t2 + lift * vs;
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(1e-6)).normalize()
}

/// Λ(ω) cos θ_ω for a direction at cos θ = `cos` ≥ 0 (see
/// [`crate::rough::ggx::lambda_cos`]): finite at the horizon.
#[inline]
pub fn lambda_cos(cos: f32, alpha2: f32) -> f32 {
    let sin2 = (1.0 - cos * cos).max(0.0);
    alpha2 * sin2 / (2.0 * ((cos * cos + alpha2 * sin2).sqrt() + cos))
}

/// G2(v, l) / G1(v), the weight of a path through a visible normal drawn by
/// [`sample_visible_normal`], for a view at cos θ_v > 0 (with its
/// Λ(v) cos θ_v) and a light at |cos θ_l| (0 for none). The same
/// height-correlated form serves transmission, as in Cycles.
#[inline]
pub fn masking_weight(cos_v: f32, lambda_cos_v: f32, cos_l: f32, alpha2: f32) -> f32 {
    if cos_l <= 0.0 {
        return 0.0;
    }
    // G2 / G1 = (1 + Λv) / (1 + Λv + Λl), multiplied through by cos_v cos_l.
    let g1_denominator = cos_v + lambda_cos_v;
    g1_denominator * cos_l / (cos_l * g1_denominator + cos_v * lambda_cos(cos_l, alpha2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::random::SplitMix;
    use crate::rough::{ggx, Kernel, MuGrid, Quadrature};

    #[test]
    fn bases_are_orthonormal() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.5, 0.8).normalize(),
        ] {
            let (t, b) = basis(n);
            for (x, y) in [(t, b), (t, n), (b, n)] {
                assert!(x.dot(y).abs() < 1e-6);
            }
            assert!((t.length() - 1.0).abs() < 1e-6 && (b.length() - 1.0).abs() < 1e-6);
            assert!((t.cross(b) - n).length() < 1e-5, "{n}");
        }
    }

    #[test]
    fn weights_match_the_definition() {
        for &a in &[0.04f64, 0.25, 1.0] {
            let a2 = a * a;
            for &cv in &[0.1f64, 0.5, 0.95] {
                for &cl in &[0.02f64, 0.4, 1.0] {
                    let want = ggx::g2(cv, ggx::lambda_cos(cv, a2), cl, a2) / ggx::g1(cv, a2);
                    let lv = lambda_cos(cv as f32, a2 as f32);
                    let got = masking_weight(cv as f32, lv, cl as f32, a2 as f32);
                    assert!((f64::from(got) - want).abs() < 2e-6 * want, "{a} {cv} {cl}");
                }
            }
        }
    }

    /// The renderer's lobe, sampled, is the definition: the mean weight
    /// G2/G1 is the lobe's albedo and the weighted mean of F(v·h) is F_eff,
    /// both as the library's quadrature computes them.
    #[test]
    fn sampled_lobe_reproduces_the_quadrature() {
        let grid = MuGrid::new(128, None);
        let f = |mu: f64| 0.3 + 0.25 * (7.0 * mu).sin();
        let values: Vec<[f64; 3]> = grid.nodes().iter().map(|&m| [f(m); 3]).collect();
        let mut rng = SplitMix::new(7);
        for &(cv, roughness) in &[(0.95f64, 0.2f64), (0.6, 0.5), (0.25, 0.8), (0.5, 1.0)] {
            let alpha = (roughness * roughness) as f32;
            let v = Vec3::new((1.0 - cv * cv).sqrt() as f32, 0.0, cv as f32);
            let lv = lambda_cos(v.z, alpha * alpha);
            let (n, mut sum_w, mut sum_wf) = (400_000, 0.0f64, 0.0f64);
            for _ in 0..n {
                let h = sample_visible_normal(v, alpha, rng.next_f32(), rng.next_f32());
                let l = 2.0 * v.dot(h) * h - v;
                let w = f64::from(masking_weight(v.z, lv, l.z, alpha * alpha));
                sum_w += w;
                sum_wf += w * f(f64::from(v.dot(h)));
            }
            let kernel = Kernel::new(&grid, cv, roughness, &Quadrature::default());
            let (albedo, feff) = (sum_w / n as f64, sum_wf / sum_w);
            assert!(
                (albedo - kernel.albedo()).abs() < 2e-3,
                "{cv} {roughness}: {albedo} vs {}",
                kernel.albedo()
            );
            assert!(
                (feff - kernel.apply(&values)[0]).abs() < 2e-3,
                "{cv} {roughness}: {feff}"
            );
        }
    }
}
