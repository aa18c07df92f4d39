//! Rays, hits and the analytic shapes (spheres, planes) of the tracer.

use glam::Vec3;

/// A half-line in world space: the points origin + t · dir for t > 0.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Where the ray starts, in scene units.
    pub origin: Vec3,
    /// Unit length.
    pub dir: Vec3,
}

impl Ray {
    /// A ray from `origin` along `dir`, which the caller must have
    /// normalized (it is stored as given).
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Ray { origin, dir }
    }

    /// The point at parameter `t`, which is also its distance from the
    /// origin in scene units since `dir` has unit length.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }
}

/// The nearest intersection of a ray with one shape.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    /// Ray parameter of the hit: its distance along the ray in scene units.
    pub t: f32,
    /// Unit geometric normal pointing out of the shape (for planes: the
    /// side the plane's normal names).
    pub normal: Vec3,
    /// Unit shading normal (interpolated on smooth meshes), on the same
    /// side as `normal`.
    pub shading_normal: Vec3,
}

/// A sphere; its outside is the side its normals point to.
#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    /// Centre in world space.
    pub center: Vec3,
    /// Radius in scene units (positive).
    pub radius: f32,
}

impl Sphere {
    /// Nearest hit with t in (t_min, t_max).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<SurfaceHit> {
        let oc = ray.origin - self.center;
        let half_b = oc.dot(ray.dir);
        let c = oc.length_squared() - self.radius * self.radius;
        let disc = half_b * half_b - c;
        if disc < 0.0 {
            return None;
        }
        let sq = disc.sqrt();
        let mut t = -half_b - sq;
        if t <= t_min || t >= t_max {
            t = -half_b + sq;
            if t <= t_min || t >= t_max {
                return None;
            }
        }
        let normal = (ray.at(t) - self.center) / self.radius;
        Some(SurfaceHit {
            t,
            normal,
            shading_normal: normal,
        })
    }

    /// The axis-aligned cube that just contains the sphere.
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: self.center - Vec3::splat(self.radius),
            max: self.center + Vec3::splat(self.radius),
        }
    }
}

/// An infinite plane through `point` with unit `normal`.
#[derive(Clone, Copy, Debug)]
pub struct Plane {
    /// Any point on the plane, in world space.
    pub point: Vec3,
    /// Unit normal; it names the plane's outside (front) side.
    pub normal: Vec3,
}

impl Plane {
    /// The hit with t in (t_min, t_max), if any; a ray (nearly) parallel to
    /// the plane misses. The hit's normals are the plane's whichever side
    /// the ray comes from.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<SurfaceHit> {
        let denom = self.normal.dot(ray.dir);
        if denom.abs() < 1e-8 {
            return None;
        }
        let t = (self.point - ray.origin).dot(self.normal) / denom;
        if t <= t_min || t >= t_max {
            return None;
        }
        Some(SurfaceHit {
            t,
            normal: self.normal,
            shading_normal: self.normal,
        })
    }
}

/// Axis-aligned bounding box.
#[derive(Clone, Copy, Debug)]
pub struct Aabb {
    /// The corner with the smallest x, y and z.
    pub min: Vec3,
    /// The corner with the largest x, y and z.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (min = +∞, max = −∞): the identity of
    /// [`Aabb::grow`] and [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// Enlarges the box to contain `p`.
    #[inline]
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// The smallest box containing both boxes.
    #[inline]
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// The box's midpoint (not finite for [`Aabb::EMPTY`]).
    #[inline]
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Slab test with a precomputed reciprocal direction; the entry
    /// distance when the box is hit within (t_min, t_max).
    #[inline]
    pub fn hit(&self, origin: Vec3, inv_dir: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
        let t0 = (self.min - origin) * inv_dir;
        let t1 = (self.max - origin) * inv_dir;
        let near = t0.min(t1).max_element().max(t_min);
        let far = t0.max(t1).min_element().min(t_max);
        (near <= far).then_some(near)
    }
}

/// Mirror reflection of `dir` about the unit normal `n`.
#[inline]
pub fn reflect(dir: Vec3, n: Vec3) -> Vec3 {
    dir - 2.0 * dir.dot(n) * n
}

/// Snell refraction of unit `dir` through unit `n` (facing against `dir`)
/// with `eta` = n_from / n_to; `None` on total internal reflection.
#[inline]
pub fn refract(dir: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -dir.dot(n);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((eta * dir + (eta * cos_i - cos_t) * n).normalize())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_hit_from_outside_and_inside() {
        let s = Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        };
        let outside = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        let h = s.intersect(&outside, 1e-4, f32::INFINITY).unwrap();
        assert!((h.t - 4.0).abs() < 1e-5);
        assert!((h.normal - Vec3::NEG_Z).length() < 1e-5);
        let inside = Ray::new(Vec3::ZERO, Vec3::X);
        let h = s.intersect(&inside, 1e-4, f32::INFINITY).unwrap();
        assert!((h.t - 1.0).abs() < 1e-5);
        assert!(
            h.normal.dot(inside.dir) > 0.0,
            "outward normal seen from inside"
        );
        let miss = Ray::new(Vec3::new(0.0, 2.0, -5.0), Vec3::Z);
        assert!(s.intersect(&miss, 1e-4, f32::INFINITY).is_none());
    }

    #[test]
    fn plane_hit_respects_interval() {
        let p = Plane {
            point: Vec3::ZERO,
            normal: Vec3::Y,
        };
        let r = Ray::new(Vec3::new(1.0, 2.0, 0.0), Vec3::NEG_Y);
        assert!((p.intersect(&r, 0.0, 10.0).unwrap().t - 2.0).abs() < 1e-6);
        assert!(p.intersect(&r, 0.0, 1.5).is_none());
        let parallel = Ray::new(Vec3::Y, Vec3::X);
        assert!(p.intersect(&parallel, 0.0, 10.0).is_none());
    }

    #[test]
    fn snell_and_total_internal_reflection() {
        let n = Vec3::Y;
        let theta_i = 30f32.to_radians();
        let dir = Vec3::new(theta_i.sin(), -theta_i.cos(), 0.0);
        let t = refract(dir, n, 1.0 / 1.5).unwrap();
        let sin_t = t.x;
        assert!((sin_t - theta_i.sin() / 1.5).abs() < 1e-6);
        // From glass at 60° (critical ≈ 41.8°) the ray is totally reflected.
        let theta = 60f32.to_radians();
        let dir = Vec3::new(theta.sin(), -theta.cos(), 0.0);
        assert!(refract(dir, n, 1.5).is_none());
        let r = reflect(dir, n);
        assert!((r - Vec3::new(dir.x, -dir.y, 0.0)).length() < 1e-6);
    }

    #[test]
    fn aabb_slab_test() {
        let b = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        let dir = Vec3::new(1.0, 0.0, 0.0);
        let inv = dir.recip();
        assert_eq!(b.hit(Vec3::new(-3.0, 0.0, 0.0), inv, 0.0, 10.0), Some(2.0));
        assert!(b.hit(Vec3::new(-3.0, 2.0, 0.0), inv, 0.0, 10.0).is_none());
        assert!(b.hit(Vec3::new(-3.0, 0.0, 0.0), inv, 0.0, 1.0).is_none());
    }
}
