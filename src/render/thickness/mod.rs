//! Film thickness over a surface: uniform, or the paper's procedural field
//! d(p) = d_min + (d_max − d_min) · noise(s · p) with Perlin noise (eq. 12).
//!
//! [`noise`] is the noise itself (with its AVX2 copy), [`grid`] the
//! precomputed grid of a field over one object's surface that LUT renders
//! read instead.

mod grid;
mod noise;

use glam::Vec3;

pub use grid::{ThicknessGrid, GRID_MAX_ERROR_NM};
pub use noise::Perlin;

/// A film's thickness as a function of the surface point, in nm: the value
/// the film shader gets for the varying layer at each hit.
#[derive(Clone, Debug)]
pub enum ThicknessField {
    /// The same thickness everywhere.
    Uniform {
        /// The layer's thickness in nm.
        thickness_nm: f32,
    },
    /// d(p) = min + (max − min) · noise(s · p), the noise mapped to [0, 1]
    /// (see [`Perlin::unit`]), so d stays within [min, max].
    Noise {
        /// Thickness in nm where the noise is 0.
        min_nm: f32,
        /// Thickness in nm where the noise is 1.
        max_nm: f32,
        /// Frequency s, per scene unit.
        scale: f32,
        /// The seeded noise field.
        perlin: Box<Perlin>,
    },
}

impl ThicknessField {
    /// A noise field between `min_nm` and `max_nm` (nm) with frequency
    /// `scale` per scene unit, its Perlin noise seeded with `seed`.
    pub fn noise(min_nm: f32, max_nm: f32, scale: f32, seed: u32) -> ThicknessField {
        ThicknessField::Noise {
            min_nm,
            max_nm,
            scale,
            perlin: Box::new(Perlin::new(seed)),
        }
    }

    /// The thickness in nm at point `p` (scene units, the same space the
    /// noise frequency is given in).
    #[inline]
    pub fn at(&self, p: Vec3) -> f32 {
        match self {
            ThicknessField::Uniform { thickness_nm } => *thickness_nm,
            ThicknessField::Noise {
                min_nm,
                max_nm,
                scale,
                perlin,
            } => min_nm + (max_nm - min_nm) * perlin.unit(*scale * p),
        }
    }

    /// The thickness range the field can take: what a table must cover.
    pub fn range_nm(&self) -> (f32, f32) {
        match self {
            ThicknessField::Uniform { thickness_nm } => (*thickness_nm, *thickness_nm),
            ThicknessField::Noise { min_nm, max_nm, .. } => (*min_nm, *max_nm),
        }
    }
}

#[cfg(target_arch = "x86_64")]
fn avx2_available() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
}

#[cfg(not(target_arch = "x86_64"))]
fn avx2_available() -> bool {
    false
}

/// floor() as an integer without a libm call (x86-64's baseline has no
/// SSE4.1 rounding instruction, so `f32::floor` is a function call).
#[inline]
pub(crate) fn fast_floor(x: f32) -> i32 {
    let i = x as i32;
    i - i32::from(x < i as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_floor_matches_floor() {
        for x in [
            -2.5f32, -2.0, -1e-7, 0.0, 0.3, 1.0, 7.9999, -1000.25, 123456.7,
        ] {
            assert_eq!(fast_floor(x), x.floor() as i32, "{x}");
        }
    }
}
