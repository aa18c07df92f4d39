//! A scene in memory: camera, environment, lights, objects and materials,
//! and the film stacks its film materials shade with.

use std::sync::Arc;

use glam::Vec3;

use super::environment::Environment;
use super::geometry::{Aabb, Plane, Ray, Sphere, SurfaceHit};
use super::material::Material;
use super::mesh::Mesh;
use crate::optics::Stack;

/// Everything a render needs, as loaded from a scene file (see
/// `docs/scene-format.md`) or a built-in scene ([`Scene::load_named`]).
/// Scene units are arbitrary but shared by every position and size; film
/// thicknesses are in nanometres.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene's name (from the file, else its path): titles and file names.
    pub name: String,
    /// Image size, samples, bounces and exposure.
    pub settings: Settings,
    /// Where the camera is and what it looks at.
    pub camera: CameraSpec,
    /// What a ray that leaves the scene sees: sky or environment map.
    pub environment: Environment,
    /// Directional and point lights, added to the environment's light.
    pub lights: Vec<Light>,
    /// The materials, in name order; objects refer to them by index.
    pub materials: Vec<Material>,
    /// The shapes, each with the index of its material.
    pub objects: Vec<Object>,
    /// One film per film material, in material order: what the renderer
    /// bakes a table for (or solves directly).
    pub films: Vec<Film>,
}

/// Image settings a scene file carries; the command line may override them.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel (stratified; 1 goes through the pixel centre).
    pub spp: u32,
    /// Reflection and refraction bounces after the camera ray.
    pub max_depth: u32,
    /// Multiplies radiance before output.
    pub exposure: f32,
}

/// A pinhole camera at `position` looking at `look_at`.
#[derive(Clone, Copy, Debug)]
pub struct CameraSpec {
    /// The eye, in scene units.
    pub position: Vec3,
    /// The point at the image centre.
    pub look_at: Vec3,
    /// Unit vector that points up in the image.
    pub up: Vec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub vfov_deg: f32,
}

/// A light besides the environment; colours are linear-sRGB weights.
#[derive(Clone, Copy, Debug)]
pub enum Light {
    /// Radiance scale `color` arriving from unit `direction` (toward the light).
    Directional {
        /// Unit vector toward the light.
        direction: Vec3,
        /// Radiance scale per channel.
        color: Vec3,
    },
    /// Intensity `color` at `position`, falling off as 1/r².
    Point {
        /// Where the light is.
        position: Vec3,
        /// Intensity per channel.
        color: Vec3,
    },
}

/// An object's geometry.
#[derive(Clone, Debug)]
pub enum Shape {
    /// A sphere.
    Sphere(Sphere),
    /// An infinite plane.
    Plane(Plane),
    /// A triangle mesh with its BVH (shared, as meshes can be large).
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

    /// The nearest hit with ray parameter in (`t_min`, `t_max`), on either face.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<SurfaceHit> {
        match self {
            Shape::Sphere(s) => s.intersect(ray, t_min, t_max),
            Shape::Plane(p) => p.intersect(ray, t_min, t_max),
            Shape::Mesh(m) => m.intersect(ray, t_min, t_max),
        }
    }
}

/// A shape and its material.
#[derive(Clone, Debug)]
pub struct Object {
    /// The geometry.
    pub shape: Shape,
    /// Index into [`Scene::materials`].
    pub material: usize,
}

/// A film stack used by the scene: which layer varies and over what range,
/// and whether light also meets it from the substrate side.
#[derive(Clone, Debug)]
pub struct Film {
    /// The material name it came from, for messages and cache names.
    pub name: String,
    /// The stack, ambient side outward.
    pub stack: Stack,
    /// 0-based index of the layer whose thickness the field sets.
    pub layer: usize,
    /// The least and greatest thickness (nm) the film takes in the scene:
    /// what its table must cover.
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
