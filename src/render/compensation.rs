//! Multiple scattering for the renderer's rough films: Turquin's energy
//! compensation (see [`crate::rough::energy`], docs/rough.md "Multiple
//! scattering") with the single-scattering escape of the bare interface
//! tabulated over the view angle at the material's own roughness.
//!
//! At a rough hit the renderer draws one microfacet and weights its
//! reflected and refracted rays by the film's R and T there; the lobe's
//! single scattering keeps, on average, E(θ_v) of the light a lossless
//! microsurface would keep. Scaling the hit by k = 1 + ρ (1 − E) / E, ρ
//! the library's [`kept_share`] of the drawn microfacet (R + T on a
//! transparent substrate, R on an opaque one), returns a lossless surface
//! to 1 and gives a film on a metal Turquin's conductor form with the
//! film's own reflectance.

use glam::Vec3;

use crate::rough::energy::{albedos, kept_share, AlbedoQuadrature};

/// View-angle nodes of the escape tables, evenly over cos θ ∈ [0, 1].
const NODES: usize = 65;

/// The bare interface's single-scattering escape E over cos θ_v, seen from
/// each side, at one roughness; empty for a smooth surface.
#[derive(Clone, Debug, Default)]
pub struct Compensation {
    front: Vec<f32>,
    back: Vec<f32>,
}

impl Compensation {
    /// The tables of a surface of `roughness` between the film's ambient
    /// and a transparent substrate of relative index `eta` = n_substrate /
    /// n_ambient, or an opaque one (`None`: the white reflection lobe).
    pub fn new(roughness: f64, eta: Option<f64>) -> Compensation {
        if roughness <= 0.0 {
            return Compensation::default();
        }
        let q = AlbedoQuadrature::default();
        let table = |eta: Option<f64>| -> Vec<f32> {
            (0..NODES)
                .map(|i| {
                    let cv = i as f64 / (NODES - 1) as f64;
                    albedos(cv, roughness, eta, &q).energy() as f32
                })
                .collect()
        };
        Compensation {
            front: table(eta),
            back: eta.map_or_else(Vec::new, |e| table(Some(1.0 / e))),
        }
    }

    /// The scale of a rough hit seen at cos θ_v from the `front` (ambient)
    /// side or the back, whose drawn microfacet reflects `r` and transmits
    /// `t` per channel (`t` ignored on an opaque substrate, which absorbs
    /// it); 1 where no table is.
    #[inline]
    pub fn scale(&self, cos_view: f32, front: bool, r: Vec3, t: Vec3) -> Vec3 {
        let table = if front { &self.front } else { &self.back };
        if table.is_empty() {
            return Vec3::ONE;
        }
        let transmits = !self.back.is_empty();
        let share =
            |r: f32, t: f32| kept_share(f64::from(r), transmits.then_some(f64::from(t))) as f32;
        let keep = Vec3::new(share(r.x, t.x), share(r.y, t.y), share(r.z, t.z));
        let x = cos_view.clamp(0.0, 1.0) * (NODES - 1) as f32;
        let i = (x as usize).min(NODES - 2);
        let f = x - i as f32;
        let escape = (table[i] + f * (table[i + 1] - table[i])).max(1e-3);
        Vec3::ONE + keep * ((1.0 - escape) / escape)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_follow_the_quadrature() {
        let c = Compensation::new(0.6, Some(1.5));
        let q = AlbedoQuadrature::default();
        for &cv in &[0.03f64, 0.37, 0.81] {
            for (front, eta) in [(true, 1.5), (false, 1.0 / 1.5)] {
                let e = albedos(cv, 0.6, Some(eta), &q).energy();
                let k = c
                    .scale(cv as f32, front, Vec3::splat(0.3), Vec3::splat(0.7))
                    .x;
                assert!(
                    (f64::from(k) * e - 1.0).abs() < 2e-3,
                    "{cv} {front}: {k} {e}"
                );
            }
        }
        assert_eq!(
            Compensation::new(0.0, Some(1.5)).scale(0.5, true, Vec3::ONE, Vec3::ZERO),
            Vec3::ONE
        );
        let opaque = Compensation::new(0.8, None);
        assert_eq!(opaque.scale(0.5, false, Vec3::ONE, Vec3::ZERO), Vec3::ONE);
        let e = albedos(0.5, 0.8, None, &q).reflect_white;
        // What enters an opaque substrate is absorbed: ρ = R.
        let k = opaque
            .scale(0.5, true, Vec3::splat(0.5), Vec3::splat(0.3))
            .x;
        assert!((f64::from(k) - (1.0 + 0.5 * (1.0 - e) / e)).abs() < 1e-3);
    }
}
