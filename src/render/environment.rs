//! What a ray sees when it leaves the scene: a procedural sky over a
//! checkered ground, or an equirectangular image the user supplies.

use std::path::Path;

use glam::Vec3;

use super::thickness::fast_floor;
use crate::error::{Error, Result};

/// The radiance arriving from infinitely far away along each direction.
#[derive(Clone, Debug)]
pub enum Environment {
    /// The procedural sky over a checkered ground.
    Sky(Sky),
    /// A user-supplied equirectangular OpenEXR map.
    Map(EquirectMap),
}

impl Environment {
    /// Linear-sRGB radiance seen along unit direction `dir` (world space,
    /// +y up), for a ray that leaves the scene.
    #[inline]
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        match self {
            Environment::Sky(s) => s.radiance(dir),
            Environment::Map(m) => m.radiance(dir),
        }
    }

    /// Mean radiance over all directions: the ambient term of diffuse
    /// surfaces, read at every diffuse hit, so stored when the scene is built.
    #[inline]
    pub fn ambient(&self) -> Vec3 {
        match self {
            Environment::Sky(s) => s.ambient,
            Environment::Map(m) => m.mean,
        }
    }
}

/// A procedural sky as the scene describes it. Linear RGB radiances; `up` is +y.
#[derive(Clone, Debug)]
pub struct SkyParams {
    /// Radiance straight up; the sky blends from `horizon` to it with the
    /// square root of the direction's height.
    pub zenith: Vec3,
    /// Radiance at the horizon, just above it.
    pub horizon: Vec3,
    /// First colour of the ground checkerboard, seen below the horizon.
    pub ground: Vec3,
    /// Second colour of the ground checkerboard (equal to `ground` for none).
    pub ground_checker: Vec3,
    /// Checker square size on a ground plane `ground_depth` below the eye.
    pub checker_size: f32,
    /// Distance in scene units from the eye down to the virtual ground plane
    /// the checkerboard is projected on (directions, not positions, pick
    /// the square, so it moves with the viewer).
    pub ground_depth: f32,
    /// Unit direction toward the sun.
    pub sun_direction: Vec3,
    /// Radiance added to the sky within the sun's disc.
    pub sun_radiance: Vec3,
    /// Angular radius of the sun's disc in degrees; 0 or less for no sun.
    pub sun_radius_deg: f32,
}

/// A sky ready to shade rays: its parameters, and what depends on them
/// alone, worked out once instead of per ray.
#[derive(Clone, Debug)]
pub struct Sky {
    params: SkyParams,
    /// Directions this close to the sun (cosine of the angle) see it; +∞
    /// without a sun, which no direction's cosine reaches.
    sun_cos_radius: f32,
    /// What the checkerboard fades to toward the horizon: its mean.
    ground_far: Vec3,
    /// Mean radiance over all directions (sky half and ground half).
    ambient: Vec3,
}

impl Sky {
    /// The sky for `params`, with the sun's cone, the far-ground colour and
    /// the ambient mean computed once.
    pub fn new(params: SkyParams) -> Sky {
        let p = &params;
        Sky {
            sun_cos_radius: if p.sun_radius_deg > 0.0 {
                p.sun_radius_deg.to_radians().cos()
            } else {
                f32::INFINITY
            },
            ground_far: 0.5 * (p.ground + p.ground_checker),
            ambient: 0.5 * (0.5 * (p.zenith + p.horizon)) + 0.5 * p.ground,
            params,
        }
    }

    /// The parameters the sky was built from.
    pub fn params(&self) -> &SkyParams {
        &self.params
    }

    /// Linear-sRGB radiance along unit direction `dir`: above the horizon
    /// (y ≥ 0) the horizon-to-zenith gradient plus the sun inside its disc;
    /// below it the checkerboard, fading toward its mean near the horizon.
    #[inline]
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        let p = &self.params;
        if dir.y >= 0.0 {
            let t = dir.y.sqrt();
            let mut sky = p.horizon.lerp(p.zenith, t);
            if dir.dot(p.sun_direction) >= self.sun_cos_radius {
                sky += p.sun_radiance;
            }
            sky
        } else {
            // Project onto a ground plane; fade the checker toward the
            // horizon, where its squares would alias. (Dividing by the
            // square size, not multiplying by its inverse, keeps the
            // squares' edges where they have always been, to the bit.)
            let dist = p.ground_depth / -dir.y;
            let q = dist * dir;
            let checker = if checker_even(q.x / p.checker_size, q.z / p.checker_size) {
                p.ground
            } else {
                p.ground_checker
            };
            let fade = (-dir.y * 8.0).min(1.0);
            self.ground_far.lerp(checker, fade)
        }
    }
}

/// An equirectangular (latitude–longitude) radiance map, +y up, the
/// image centre looking down −z.
#[derive(Clone, Debug)]
pub struct EquirectMap {
    width: usize,
    height: usize,
    pixels: Vec<Vec3>,
    mean: Vec3,
}

impl EquirectMap {
    /// Loads the first RGB(A) layer of an OpenEXR file, scaled by `intensity`.
    pub fn load(path: &Path, intensity: f32) -> Result<EquirectMap> {
        if !path.is_file() {
            return Err(Error::io(
                path,
                std::io::Error::new(std::io::ErrorKind::NotFound, "environment map not found"),
            ));
        }
        // The data window is read from the header and checked against the
        // memory budget before the reader allocates it: a few hundred bytes
        // of file can declare a window of terabytes.
        let meta = exr::meta::MetaData::read_from_file(path, false)
            .map_err(|e| Error::malformed(path, format!("not a readable OpenEXR image: {e}")))?;
        let largest = meta
            .headers
            .iter()
            .map(|h| crate::limits::product(&[h.layer_size.0 as u64, h.layer_size.1 as u64], 1))
            .try_fold(0u64, |acc, px| px.map(|px| acc.max(px)));
        // The reader's RGBA f32 samples (16 bytes a pixel), the map (12)
        // and the tuple it is built from (12).
        crate::limits::check_allocation(
            &format!("{}: environment map", path.display()),
            largest.and_then(|px| px.checked_mul(40)),
        )?;
        let image = exr::prelude::read_first_rgba_layer_from_file(
            path,
            |res, _| {
                let (w, h) = (res.width(), res.height());
                (w, h, vec![Vec3::ZERO; w * h])
            },
            |(w, _, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                px[pos.y() * *w + pos.x()] = Vec3::new(r, g, b);
            },
        )
        .map_err(|e| Error::malformed(path, format!("not a readable OpenEXR image: {e}")))?;
        let (width, height, mut pixels) = image.layer_data.channel_data.pixels;
        if width < 2 || height < 2 {
            return Err(Error::malformed(
                path,
                "environment map must be at least 2x2",
            ));
        }
        let mut sum = Vec3::ZERO;
        for p in pixels.iter_mut() {
            if !p.is_finite() {
                *p = Vec3::ZERO;
            }
            *p *= intensity;
            sum += *p;
        }
        let mean = sum / pixels.len() as f32;
        Ok(EquirectMap {
            width,
            height,
            pixels,
            mean,
        })
    }

    /// Bilinear lookup, wrapping in longitude.
    #[inline]
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        let u = 0.5 + dir.x.atan2(-dir.z) / std::f32::consts::TAU;
        let v = dir.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
        let x = u * self.width as f32 - 0.5;
        let y = (v * self.height as f32 - 0.5).clamp(0.0, (self.height - 1) as f32);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let w = self.width as i64;
        let xi = |k: i64| ((x0 as i64 + k).rem_euclid(w)) as usize;
        let yi = |k: usize| (y0 as usize + k).min(self.height - 1);
        let px = |xx: usize, yy: usize| self.pixels[yy * self.width + xx];
        let top = px(xi(0), yi(0)).lerp(px(xi(1), yi(0)), fx);
        let bottom = px(xi(0), yi(1)).lerp(px(xi(1), yi(1)), fx);
        top.lerp(bottom, fy)
    }
}

/// Whether (x, z) lies on an even square of a unit checkerboard.
#[inline]
pub(crate) fn checker_even(x: f32, z: f32) -> bool {
    // Far-away points overflow i32 on the ground plane near the horizon;
    // saturating casts keep them on some square.
    (fast_floor(x).wrapping_add(fast_floor(z))) & 1 == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sky() -> Sky {
        Sky::new(SkyParams {
            zenith: Vec3::new(0.1, 0.2, 0.8),
            horizon: Vec3::ONE,
            ground: Vec3::splat(0.2),
            ground_checker: Vec3::splat(0.6),
            checker_size: 1.0,
            ground_depth: 1.0,
            sun_direction: Vec3::new(0.0, 1.0, 1.0).normalize(),
            sun_radiance: Vec3::splat(50.0),
            sun_radius_deg: 2.0,
        })
    }

    #[test]
    fn sky_gradient_sun_and_checker() {
        let s = sky();
        let p = s.params();
        assert!((s.radiance(Vec3::Y) - p.zenith).length() < 1e-6);
        assert!((s.radiance(Vec3::X) - p.horizon).length() < 1e-6);
        assert!(s.radiance(p.sun_direction).x > 50.0);
        // Straight down onto the centre of a checker square, and one square over.
        let a = s.radiance(Vec3::new(0.0, -1.0, 0.0001).normalize());
        let b = s.radiance(Vec3::new(1.5, -1.0, 0.5).normalize());
        assert!((a - b).length() > 0.1, "{a} vs {b}");
    }

    #[test]
    fn equirect_map_round_trips_directions() {
        let dir = std::env::temp_dir().join(format!("irid-env-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("env.exr");
        // Upper half red, lower half blue; 8 x 4.
        exr::prelude::write_rgb_file(&path, 8, 4, |_x, y| {
            if y < 2 {
                (1.0f32, 0.0f32, 0.0f32)
            } else {
                (0.0, 0.0, 1.0)
            }
        })
        .unwrap();
        let map = EquirectMap::load(&path, 2.0).unwrap();
        assert!((map.radiance(Vec3::Y) - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6);
        assert!((map.radiance(Vec3::NEG_Y) - Vec3::new(0.0, 0.0, 2.0)).length() < 1e-6);
        assert!((map.mean - Vec3::new(1.0, 0.0, 1.0)).length() < 1e-6);
        let err = EquirectMap::load(&dir.join("missing.exr"), 1.0)
            .unwrap_err()
            .to_string();
        assert!(err.contains("missing.exr"), "{err}");
        std::fs::write(dir.join("bad.exr"), b"not exr").unwrap();
        assert!(EquirectMap::load(&dir.join("bad.exr"), 1.0).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
