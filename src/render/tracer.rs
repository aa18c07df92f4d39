//! The Whitted-style integrator: camera rays, mirror reflection and
//! refraction to a fixed depth, direct light with shadows on diffuse
//! surfaces, the environment everywhere else.

use glam::Vec3;

use super::environment::checker_even;
use super::film::{FilmShading, Side};
use super::geometry::{reflect, refract, Ray};
use super::material::{dielectric_reflectance, FilmMaterial, Material};
use super::microfacet;
use super::random::SampleRng;
use super::scene::{Light, Scene};
use super::thickness::ThicknessGrid;

/// Generic over the film shader rather than holding trait objects: a film
/// hit is frequent enough that an indirect call, which cannot be inlined,
/// is a measurable part of what film shading costs in LUT mode. `ROUGH`
/// compiles in the rough-film path (see [`Tracer::trace`]): with it, a
/// smooth scene's renders took 1.2 % more instructions (callgrind).
pub struct Tracer<'a, F: FilmShading, const ROUGH: bool = false> {
    /// The scene traced: objects, materials, lights and environment.
    pub scene: &'a Scene,
    /// One shader per entry of `scene.films`.
    pub films: &'a [F],
    /// Per object, its film's thickness field baked to a grid, where one
    /// was (LUT mode); other objects evaluate their field exactly. May be
    /// empty.
    pub thickness_grids: &'a [Option<ThicknessGrid>],
    /// Reflection and refraction bounces followed after the camera ray;
    /// a ray past this depth takes the environment's radiance in its
    /// direction instead of being traced.
    pub max_depth: u32,
}

/// What a rough film hit needs besides the ray.
struct FilmHit<'a> {
    film: &'a FilmMaterial,
    thickness_nm: f32,
    /// The ray arrives from the film's ambient side.
    front: bool,
    /// The shading normal, facing the incoming ray.
    n: Vec3,
    /// Where reflected and refracted rays start, off the surface.
    above: Vec3,
    below: Vec3,
}

impl FilmHit<'_> {
    /// n_from / n_to for a ray refracting into the film's other side;
    /// `None` when the substrate is opaque.
    #[inline]
    fn eta(&self) -> Option<f32> {
        self.film.inside.map(|inside| {
            if self.front {
                self.film.outside_ior / inside.ior
            } else {
                inside.ior / self.film.outside_ior
            }
        })
    }

    #[inline]
    fn side(&self) -> Side {
        if self.front {
            Side::Front
        } else {
            Side::Back
        }
    }
}

impl<F: FilmShading, const ROUGH: bool> Tracer<'_, F, ROUGH> {
    /// Radiance arriving along `ray`.
    ///
    /// Every branch is followed to the fixed depth whatever its weight
    /// (Whitted's rule), so the ray tree, and with it the cost, does not
    /// depend on the film's colours. A surface's reflectance and
    /// transmittance are looked up after its children are traced: nothing
    /// in the children depends on them, and a film's lookup (thickness,
    /// then table) is a long chain of dependent instructions that, placed
    /// before the children, stalls them; placed after, it overlaps with them.
    ///
    /// A rough film draws its microfacet normal from the camera sample's
    /// generator ([`SampleRng`]); with `ROUGH` false (a scene without rough
    /// films) that path is not compiled in, and the tracer is the mirror
    /// tracer instruction for instruction.
    pub fn trace(&self, ray: &Ray, depth: u32) -> Vec3 {
        let Some((hit, obj)) = self.scene.intersect(ray, 0.0, f32::INFINITY) else {
            return self.scene.environment.radiance(ray.dir);
        };
        let material = &self.scene.materials[self.scene.objects[obj].material];
        let p = ray.at(hit.t);
        let front = ray.dir.dot(hit.normal) < 0.0;
        // Both normals turned to face the incoming ray.
        let (n_geo, n) = if front {
            (hit.normal, hit.shading_normal)
        } else {
            (-hit.normal, -hit.shading_normal)
        };
        // Beer–Lambert along the segment just travelled inside the object.
        let absorbed = if front {
            Vec3::ONE
        } else {
            let a = material.absorption();
            if a == Vec3::ZERO {
                Vec3::ONE
            } else {
                (-a * hit.t).exp()
            }
        };
        let cos_i = (-ray.dir.dot(n)).clamp(1e-6, 1.0);
        let eps = 1e-4 * (1.0 + p.abs().max_element());
        let above = p + eps * n_geo;
        let below = p - eps * n_geo;

        let radiance = match material {
            Material::Diffuse { albedo, checker } => {
                let albedo = match checker {
                    Some(c) => {
                        if checker_even(p.x / c.size, p.z / c.size) {
                            *albedo
                        } else {
                            c.albedo
                        }
                    }
                    None => *albedo,
                };
                albedo * (self.direct_light(above, n) + self.scene.environment.ambient())
            }
            Material::Metal { reflectance } => {
                let reflected = self.reflected(ray, above, n, depth);
                reflectance.at(cos_i) * reflected
            }
            Material::Dielectric { ior, .. } => {
                let eta = if front { 1.0 / ior } else { *ior };
                let reflected = self.reflected(ray, above, n, depth);
                let refracted = self.refracted(ray, below, n, eta, depth);
                let r = dielectric_reflectance(cos_i, eta);
                r * reflected + (1.0 - r) * refracted
            }
            Material::Film(f) => {
                // The thickness is found before the children are traced: a
                // grid lookup is short enough not to stall them, and its
                // latency then overlaps with them instead of lengthening
                // the table lookup's chain at the end.
                let thickness_nm = match self.thickness_grids.get(obj) {
                    Some(Some(grid)) => grid.at(p),
                    _ => f.thickness.at(p),
                };
                if ROUGH && f.alpha > 0.0 {
                    let hit = FilmHit {
                        film: f,
                        thickness_nm,
                        front,
                        n,
                        above,
                        below,
                    };
                    return absorbed * self.rough_film(ray, &hit, depth);
                }
                let reflected = self.reflected(ray, above, n, depth);
                let refracted = match f.inside {
                    Some(inside) => {
                        let eta = if front {
                            f.outside_ior / inside.ior
                        } else {
                            inside.ior / f.outside_ior
                        };
                        self.refracted(ray, below, n, eta, depth)
                    }
                    None => Vec3::ZERO,
                };
                let side = if front { Side::Front } else { Side::Back };
                let rgb = self.films[f.film].shade(thickness_nm, cos_i, side);
                Vec3::from(rgb.reflectance) * reflected + Vec3::from(rgb.transmittance) * refracted
            }
        };
        absorbed * radiance
    }

    /// A film on a rough surface (docs/rough.md): one microfacet normal h
    /// drawn from GGX's visible normals, the rays reflected and refracted
    /// about it, each weighted by G2 / G1 and by the film's reflectance or
    /// transmittance at v·h. Averaged over a pixel's samples this is the
    /// single-scattering GGX lobe with the film's Fresnel per microfacet,
    /// scaled for multiple scattering ([`super::compensation`]).
    /// Never inlined: inside [`Self::trace`] its code lengthened every
    /// call's prologue, smooth scenes' too.
    #[inline(never)]
    fn rough_film(&self, ray: &Ray, hit: &FilmHit, depth: u32) -> Vec3 {
        let (u1, u2) = SampleRng::pair();
        let alpha = hit.film.alpha;
        let alpha2 = alpha * alpha;
        let v = -ray.dir;
        let (t, b) = microfacet::basis(hit.n);
        let cos_v = v.dot(hit.n).clamp(1e-6, 1.0);
        let local = Vec3::new(v.dot(t), v.dot(b), cos_v);
        let h_local = microfacet::sample_visible_normal(local, alpha, u1, u2);
        let h = t * h_local.x + b * h_local.y + hit.n * h_local.z;
        let lambda_v = microfacet::lambda_cos(cos_v, alpha2);
        let mirror = reflect(ray.dir, h);
        let reflect_weight = microfacet::masking_weight(cos_v, lambda_v, mirror.dot(hit.n), alpha2);
        let reflected = if reflect_weight > 0.0 {
            reflect_weight * self.follow(hit.above, mirror, depth)
        } else {
            Vec3::ZERO
        };
        let refracted = match hit.eta().and_then(|eta| refract(ray.dir, h, eta)) {
            Some(dir) => {
                let w = microfacet::masking_weight(cos_v, lambda_v, -dir.dot(hit.n), alpha2);
                if w > 0.0 {
                    w * self.follow(hit.below, dir, depth)
                } else {
                    Vec3::ZERO
                }
            }
            None => Vec3::ZERO,
        };
        let cos_vh = v.dot(h).clamp(1e-6, 1.0);
        let rgb = self.films[hit.film.film].shade(hit.thickness_nm, cos_vh, hit.side());
        let (r, t) = (Vec3::from(rgb.reflectance), Vec3::from(rgb.transmittance));
        // What the lobe's single scattering loses to further bounces.
        let scale = hit.film.compensation.scale(cos_v, hit.front, r, t);
        scale * (r * reflected + t * refracted)
    }

    /// Radiance along the mirror direction: traced below the depth limit,
    /// the environment at it.
    #[inline]
    fn reflected(&self, ray: &Ray, origin: Vec3, n: Vec3, depth: u32) -> Vec3 {
        self.follow(origin, reflect(ray.dir, n), depth)
    }

    /// Radiance along the refracted direction; none under total internal
    /// reflection.
    #[inline]
    fn refracted(&self, ray: &Ray, origin: Vec3, n: Vec3, eta: f32, depth: u32) -> Vec3 {
        match refract(ray.dir, n, eta) {
            Some(dir) => self.follow(origin, dir, depth),
            None => Vec3::ZERO,
        }
    }

    #[inline]
    fn follow(&self, origin: Vec3, dir: Vec3, depth: u32) -> Vec3 {
        if depth < self.max_depth {
            self.trace(&Ray::new(origin, dir), depth + 1)
        } else {
            self.scene.environment.radiance(dir)
        }
    }

    /// Irradiance-weighted light from every unshadowed light, over π.
    fn direct_light(&self, origin: Vec3, n: Vec3) -> Vec3 {
        let mut sum = Vec3::ZERO;
        for light in &self.scene.lights {
            let (dir, dist, color) = match *light {
                Light::Directional { direction, color } => (direction, f32::INFINITY, color),
                Light::Point { position, color } => {
                    let d = position - origin;
                    let dist = d.length();
                    (d / dist, dist, color / (dist * dist))
                }
            };
            let cos = n.dot(dir);
            if cos <= 0.0 || self.scene.occluded(&Ray::new(origin, dir), 0.0, dist) {
                continue;
            }
            sum += color * cos;
        }
        sum * std::f32::consts::FRAC_1_PI
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::render::LutFilm;

    /// A white floor lit by one point light, under a black sky; `blocker`
    /// optionally puts an opaque sphere between the light and the floor.
    fn floor_scene(blocker: &str) -> Scene {
        let text = format!(
            r#"
            [camera]
            position = [0.0, 5.0, 0.1]
            look_at = [0.0, 0.0, 0.0]
            fov_deg = 30.0
            [environment]
            kind = "sky"
            zenith = [0.0, 0.0, 0.0]
            horizon = [0.0, 0.0, 0.0]
            ground = [0.0, 0.0, 0.0]
            [[lights]]
            kind = "point"
            position = [0.0, 2.0, 0.0]
            color = [4.0, 4.0, 4.0]
            [materials.white]
            kind = "diffuse"
            albedo = [1.0, 1.0, 1.0]
            [materials.mirror]
            kind = "dielectric"
            ior = 1.5
            [[objects]]
            shape = "plane"
            material = "white"
            point = [0.0, 0.0, 0.0]
            normal = [0.0, 1.0, 0.0]
            {blocker}
            "#
        );
        Scene::from_toml_str(&text, Path::new("."), "test").unwrap()
    }

    #[test]
    fn point_light_falls_off_and_casts_shadows() {
        let scene = floor_scene("");
        let tracer: Tracer<LutFilm> = Tracer {
            scene: &scene,
            films: &[],
            thickness_grids: &[],
            max_depth: 2,
        };
        let down = |x: f32| {
            let ray = Ray::new(Vec3::new(x, 1.0, 0.0), Vec3::NEG_Y);
            tracer.trace(&ray, 0).x
        };
        // E = I cos / r² over π for albedo 1: directly below at r = 2.
        let below = down(0.0);
        assert!(
            (below - 4.0 / 4.0 / std::f32::consts::PI).abs() < 1e-4,
            "{below}"
        );
        // At x = 2: r² = 8, cos = 2 / √8.
        let aside = down(2.0);
        let want = 4.0 * (2.0 / 8f32.sqrt()) / 8.0 / std::f32::consts::PI;
        assert!((aside - want).abs() < 1e-4, "{aside} vs {want}");

        let shadowed = floor_scene(
            "[[objects]]\nshape = \"sphere\"\nmaterial = \"mirror\"\ncenter = [0.0, 1.0, 0.0]\nradius = 0.5",
        );
        let tracer: Tracer<LutFilm> = Tracer {
            scene: &shadowed,
            films: &[],
            thickness_grids: &[],
            max_depth: 2,
        };
        // Seen from just above the floor, beside the sphere's shadow and in it.
        let ray = Ray::new(Vec3::new(0.0, 0.3, 0.0), Vec3::NEG_Y);
        assert_eq!(tracer.trace(&ray, 0), Vec3::ZERO);
        let ray = Ray::new(Vec3::new(2.0, 0.3, 0.0), Vec3::NEG_Y);
        assert!((tracer.trace(&ray, 0).x - want).abs() < 1e-4);
    }
}
