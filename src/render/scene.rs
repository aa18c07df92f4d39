//! A scene in memory: camera, environment, lights, objects and materials,
//! and the film stacks its film materials shade with.

use std::sync::Arc;

use glam::Vec3;

use super::environment::Environment;
use super::geometry::{Aabb, Plane, Ray, Sphere, SurfaceHit};
use super::material::Material;
use super::mesh::Mesh;
use crate::optics::Stack;

#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub settings: Settings,
    pub camera: CameraSpec,
    pub environment: Environment,
    pub lights: Vec<Light>,
    pub materials: Vec<Material>,
    pub objects: Vec<Object>,
    pub films: Vec<Film>,
}

/// Image settings a scene file carries; the command line may override them.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// Reflection and refraction bounces after the camera ray.
    pub max_depth: u32,
    /// Multiplies radiance before output.
    pub exposure: f32,
}

#[derive(Clone, Copy, Debug)]
pub struct CameraSpec {
    pub position: Vec3,
    pub look_at: Vec3,
    pub up: Vec3,
    pub vfov_deg: f32,
}

#[derive(Clone, Copy, Debug)]
pub enum Light {
    /// Radiance scale `color` arriving from unit `direction` (toward the light).
    Directional { direction: Vec3, color: Vec3 },
    /// Intensity `color` at `position`, falling off as 1/r².
    Point { position: Vec3, color: Vec3 },
}

#[derive(Clone, Debug)]
pub enum Shape {
    Sphere(Sphere),
    Plane(Plane),
    Mesh(Arc<Mesh>),
}

impl Shape {
    /// The box around the shape; `None` for an unbounded plane.
    pub fn bounds(&self) -> Option<Aabb> {
        match self {
            Shape::Sphere(s) => Some(s.bounds()),
            Shape::Plane(_) => None,
            Shape::Mesh(m) => Some(m.bounds()),
        }
    }

    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<SurfaceHit> {
        match self {
            Shape::Sphere(s) => s.intersect(ray, t_min, t_max),
            Shape::Plane(p) => p.intersect(ray, t_min, t_max),
            Shape::Mesh(m) => m.intersect(ray, t_min, t_max),
        }
    }
}

#[derive(Clone, Debug)]
pub struct Object {
    pub shape: Shape,
    pub material: usize,
}

/// A film stack used by the scene: which layer varies and over what range,
/// and whether light also meets it from the substrate side.
#[derive(Clone, Debug)]
pub struct Film {
    /// The material name it came from, for messages and cache names.
    pub name: String,
    pub stack: Stack,
    /// 0-based index of the layer whose thickness the field sets.
    pub layer: usize,
    pub thickness_range_nm: (f32, f32),
    /// True when the substrate is transparent, so rays inside meet the
    /// reversed stack.
    pub back_side: bool,
}

impl Scene {
    /// Nearest hit over all objects: the hit and the object's index.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(SurfaceHit, usize)> {
        let mut best = None;
        let mut t_max = t_max;
        for (i, o) in self.objects.iter().enumerate() {
            if let Some(h) = o.shape.intersect(ray, t_min, t_max) {
                t_max = h.t;
                best = Some((h, i));
            }
        }
        best
    }

    /// Whether any shadow-casting object lies on the ray before `t_max`.
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.objects.iter().any(|o| {
            self.materials[o.material].casts_shadow()
                && o.shape.intersect(ray, t_min, t_max).is_some()
        })
    }

    /// The same scene with every film removed: each film material becomes
    /// its bare substrate (a plain dielectric, or the uncoated metal given by
    /// `bare_metal`). Measures what iridescence costs.
    pub fn without_films(&self, mut bare_metal: impl FnMut(&Film) -> Material) -> Scene {
        let mut s = self.clone();
        for m in s.materials.iter_mut() {
            if let Material::Film(f) = m {
                *m = match f.inside {
                    Some(inside) => Material::Dielectric {
                        ior: inside.ior / f.outside_ior,
                        absorption: inside.absorption,
                    },
                    None => bare_metal(&self.films[f.film]),
                };
            }
        }
        s.films.clear();
        s
    }
}
