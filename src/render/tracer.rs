//! The Whitted-style integrator: camera rays, mirror reflection and
//! refraction to a fixed depth, direct light with shadows on diffuse
//! surfaces, the environment everywhere else.

use glam::Vec3;

use super::environment::checker_even;
use super::film::{FilmShading, Side};
use super::geometry::{reflect, refract, Ray};
use super::material::{dielectric_reflectance, Material};
use super::scene::{Light, Scene};

pub struct Tracer<'a> {
    pub scene: &'a Scene,
    /// One shader per entry of `scene.films`.
    pub films: &'a [Box<dyn FilmShading + 'a>],
    pub max_depth: u32,
}

impl Tracer<'_> {
    /// Radiance arriving along `ray`; `weight` is the path's throughput so far.
    pub fn trace(&self, ray: &Ray, depth: u32, weight: Vec3) -> Vec3 {
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
        let can_recurse = depth < self.max_depth;

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
                let r = reflectance.at(cos_i);
                self.reflected(ray, above, n, r, depth, weight, can_recurse)
            }
            Material::Dielectric { ior, .. } => {
                let eta = if front { 1.0 / ior } else { *ior };
                let r = dielectric_reflectance(cos_i, eta);
                let rv = Vec3::splat(r);
                let tv = Vec3::splat(1.0 - r);
                self.reflected(ray, above, n, rv, depth, weight, can_recurse)
                    + self.refracted(ray, below, n, eta, tv, depth, weight, can_recurse)
            }
            Material::Film(f) => {
                let side = if front { Side::Front } else { Side::Back };
                let rgb = self.films[f.film].shade(f.thickness.at(p), cos_i, side);
                let r = Vec3::from(rgb.reflectance);
                let mut l = self.reflected(ray, above, n, r, depth, weight, can_recurse);
                if let Some(inside) = f.inside {
                    let eta = if front {
                        f.outside_ior / inside.ior
                    } else {
                        inside.ior / f.outside_ior
                    };
                    let t = Vec3::from(rgb.transmittance);
                    l += self.refracted(ray, below, n, eta, t, depth, weight, can_recurse);
                }
                l
            }
        };
        absorbed * radiance
    }

    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn reflected(
        &self,
        ray: &Ray,
        origin: Vec3,
        n: Vec3,
        r: Vec3,
        depth: u32,
        weight: Vec3,
        recurse: bool,
    ) -> Vec3 {
        // Every branch is followed to the fixed depth whatever its weight
        // (Whitted's rule): pruning light paths would make the ray tree, and
        // so the cost, depend on the film's colours, which would confound
        // the comparison of film and plain shading.
        let w = weight * r;
        if w.max_element() <= 0.0 {
            return Vec3::ZERO;
        }
        let dir = reflect(ray.dir, n);
        if !recurse {
            return r * self.scene.environment.radiance(dir);
        }
        r * self.trace(&Ray::new(origin, dir), depth + 1, w)
    }

    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn refracted(
        &self,
        ray: &Ray,
        origin: Vec3,
        n: Vec3,
        eta: f32,
        t: Vec3,
        depth: u32,
        weight: Vec3,
        recurse: bool,
    ) -> Vec3 {
        let w = weight * t;
        if w.max_element() <= 0.0 {
            return Vec3::ZERO;
        }
        let Some(dir) = refract(ray.dir, n, eta) else {
            return Vec3::ZERO;
        };
        if !recurse {
            return t * self.scene.environment.radiance(dir);
        }
        t * self.trace(&Ray::new(origin, dir), depth + 1, w)
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
        let tracer = Tracer {
            scene: &scene,
            films: &[],
            max_depth: 2,
        };
        let down = |x: f32| {
            let ray = Ray::new(Vec3::new(x, 1.0, 0.0), Vec3::NEG_Y);
            tracer.trace(&ray, 0, Vec3::ONE).x
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
        let tracer = Tracer {
            scene: &shadowed,
            films: &[],
            max_depth: 2,
        };
        // Seen from just above the floor, beside the sphere's shadow and in it.
        let ray = Ray::new(Vec3::new(0.0, 0.3, 0.0), Vec3::NEG_Y);
        assert_eq!(tracer.trace(&ray, 0, Vec3::ONE), Vec3::ZERO);
        let ray = Ray::new(Vec3::new(2.0, 0.3, 0.0), Vec3::NEG_Y);
        assert!((tracer.trace(&ray, 0, Vec3::ONE).x - want).abs() < 1e-4);
    }
}
