//! A pinhole perspective camera.

use glam::Vec3;

use super::geometry::Ray;

/// A pinhole camera: every ray starts at the eye and passes through a
/// point of an image plane at unit distance along the view direction,
/// sized by the vertical field of view and the aspect ratio. Ray
/// directions are unit vectors in world space.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    origin: Vec3,
    /// World-space offsets of the image plane at unit distance.
    lower_left: Vec3,
    horizontal: Vec3,
    vertical: Vec3,
}

impl Camera {
    /// `vfov_deg` is the full vertical field of view; `aspect` = width / height.
    pub fn new(position: Vec3, look_at: Vec3, up: Vec3, vfov_deg: f32, aspect: f32) -> Camera {
        let h = (0.5 * vfov_deg.to_radians()).tan();
        let w = h * aspect;
        let forward = (look_at - position).normalize();
        let right = forward.cross(up).normalize();
        let true_up = right.cross(forward);
        Camera {
            origin: position,
            lower_left: forward - w * right - h * true_up,
            horizontal: 2.0 * w * right,
            vertical: 2.0 * h * true_up,
        }
    }

    /// The ray through image coordinates (u, v) in [0, 1]², u to the right
    /// and v downward (row order of the image).
    #[inline]
    pub fn ray(&self, u: f32, v: f32) -> Ray {
        let dir = self.lower_left + u * self.horizontal + (1.0 - v) * self.vertical;
        Ray::new(self.origin, dir.normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_at_target_and_corners_span_the_fov() {
        let cam = Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 90.0, 2.0);
        let c = cam.ray(0.5, 0.5);
        assert!((c.dir - Vec3::NEG_Z).length() < 1e-6);
        let top = cam.ray(0.5, 0.0).dir;
        assert!(
            (top.y / -top.z - 1.0).abs() < 1e-5,
            "half of 90° vertical fov"
        );
        let right = cam.ray(1.0, 0.5).dir;
        assert!(
            (right.x / -right.z - 2.0).abs() < 1e-5,
            "aspect 2 widens it"
        );
    }
}
