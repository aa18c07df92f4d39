//! Surface materials as the tracer sees them, with everything spectral
//! already reduced to linear-sRGB weights.

use glam::Vec3;

use super::thickness::ThicknessField;

/// How a surface scatters light, in the tracer's terms.
#[derive(Clone, Debug)]
pub enum Material {
    /// Lambertian, lit by the lights (with shadows) plus the environment's
    /// mean radiance as the ambient term; optionally a checkerboard.
    Diffuse {
        /// Linear-sRGB reflectance (fraction of light scattered per
        /// channel); the even squares' colour when there is a checker.
        albedo: Vec3,
        /// A checkerboard in the x–z plane alternating `albedo` with its
        /// own colour.
        checker: Option<Checker>,
    },
    /// An opaque mirror whose reflectance depends on the incidence angle
    /// (exact Fresnel of a library metal, integrated over the spectrum).
    Metal {
        /// Linear-sRGB reflectance over cos θ of the incident ray.
        reflectance: AngleTable,
    },
    /// A smooth uncoated dielectric of real index `ior` in a medium of index
    /// 1; light inside is absorbed per unit length (Beer–Lambert).
    Dielectric {
        /// Real refractive index of the object (the outside being 1).
        ior: f32,
        /// Beer–Lambert absorption coefficient per scene unit, per linear
        /// sRGB channel; zero for a clear object.
        absorption: Vec3,
    },
    /// A thin-film stack over a substrate, shaded through a [`super::film::FilmShading`].
    Film(FilmMaterial),
}

/// The second colour and square size of a diffuse checkerboard, laid out
/// on the hit point's x and z world coordinates.
#[derive(Clone, Debug)]
pub struct Checker {
    /// Linear-sRGB albedo of the odd squares.
    pub albedo: Vec3,
    /// Side of a square in scene units.
    pub size: f32,
}

/// A thin-film coated surface: which film stack, how thick its varying
/// layer is where, and what lies on either side.
#[derive(Clone, Debug)]
pub struct FilmMaterial {
    /// Index into the scene's films (and the renderer's film shaders).
    pub film: usize,
    /// The varying layer's thickness in nm over the surface.
    pub thickness: ThicknessField,
    /// Real index of the stack's ambient, at 550 nm.
    pub outside_ior: f32,
    /// The substrate when light passes into it (a dielectric, or air for a
    /// bubble); `None` for an opaque (metal) substrate.
    pub inside: Option<Interior>,
    /// GGX α = roughness² of the surface under the film (docs/rough.md);
    /// 0 for a mirror-smooth film.
    pub alpha: f32,
    /// The rough lobe's multiple-scattering compensation (empty when
    /// smooth).
    pub compensation: super::compensation::Compensation,
}

/// The medium inside a film-coated object that light can enter.
#[derive(Clone, Copy, Debug)]
pub struct Interior {
    /// Real index at 550 nm, used to bend the transmitted ray.
    pub ior: f32,
    /// Beer–Lambert absorption coefficient per scene unit, per channel.
    pub absorption: Vec3,
}

impl Material {
    /// Absorption inside the object, per scene unit.
    pub fn absorption(&self) -> Vec3 {
        match self {
            Material::Dielectric { absorption, .. } => *absorption,
            Material::Film(f) => f.inside.map_or(Vec3::ZERO, |i| i.absorption),
            _ => Vec3::ZERO,
        }
    }

    /// Whether the object blocks shadow rays. A film with the same medium on
    /// both sides (a bubble) passes light straight through, so it does not;
    /// anything that bends light or is opaque does (Whitted's convention).
    pub fn casts_shadow(&self) -> bool {
        match self {
            Material::Film(f) => match f.inside {
                Some(i) => (i.ior - f.outside_ior).abs() > 1e-3 || i.absorption != Vec3::ZERO,
                None => true,
            },
            _ => true,
        }
    }
}

/// RGB weights tabulated over cos θ ∈ [0, 1], linearly interpolated.
#[derive(Clone, Debug)]
pub struct AngleTable {
    values: Vec<[f32; 3]>,
}

impl AngleTable {
    /// Tabulates `f` at `nodes` evenly spaced cos θ from 0 to 1 inclusive
    /// (at least 2 nodes).
    pub fn from_fn(nodes: usize, mut f: impl FnMut(f64) -> [f32; 3]) -> AngleTable {
        let nodes = nodes.max(2);
        let values = (0..nodes)
            .map(|i| f(i as f64 / (nodes - 1) as f64))
            .collect();
        AngleTable { values }
    }

    /// The weights at `cos_theta`, clamped to [0, 1], linearly
    /// interpolated between the two nearest nodes.
    #[inline]
    pub fn at(&self, cos_theta: f32) -> Vec3 {
        let x = cos_theta.clamp(0.0, 1.0) * (self.values.len() - 1) as f32;
        let i = (x as usize).min(self.values.len() - 2);
        let f = x - i as f32;
        let a = Vec3::from(self.values[i]);
        let b = Vec3::from(self.values[i + 1]);
        a.lerp(b, f)
    }
}

/// Unpolarized Fresnel reflectance of a smooth interface between real
/// indices, `eta` = n_from / n_to; 1 under total internal reflection.
#[inline]
pub fn dielectric_reflectance(cos_i: f32, eta: f32) -> f32 {
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (rs * rs + rp * rp)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_matches_the_solver() {
        use num_complex::Complex64 as C64;
        for (eta, n_from, n_to) in [
            (1.0 / 1.5, 1.0, 1.5),
            (1.5, 1.5, 1.0),
            (1.0 / 1.76, 1.0, 1.76),
        ] {
            for k in 0..=20 {
                let cos = k as f64 / 20.0;
                let want = crate::optics::solve(
                    &[C64::new(n_from, 0.0), C64::new(n_to, 0.0)],
                    &[],
                    550.0,
                    cos,
                )
                .r();
                let got = dielectric_reflectance(cos as f32, eta as f32);
                assert!(
                    (want as f32 - got).abs() < 1e-5,
                    "eta {eta} cos {cos}: {want} vs {got}"
                );
            }
        }
    }

    #[test]
    fn angle_table_interpolates_linearly() {
        let t = AngleTable::from_fn(11, |c| [c as f32, 1.0, 2.0 * c as f32]);
        let v = t.at(0.55);
        assert!((v - Vec3::new(0.55, 1.0, 1.1)).length() < 1e-6);
        assert_eq!(t.at(-1.0), Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(t.at(2.0), Vec3::new(1.0, 1.0, 2.0));
    }
}
