//! Film thickness over a surface: uniform, or the paper's procedural field
//! d(p) = d_min + (d_max − d_min) · noise(s · p) with Perlin noise (eq. 12).

use glam::Vec3;
use noise::{NoiseFn, Perlin};

#[derive(Clone, Debug)]
pub enum ThicknessField {
    Uniform {
        thickness_nm: f32,
    },
    Noise {
        min_nm: f32,
        max_nm: f32,
        /// Frequency s, per scene unit.
        scale: f32,
        perlin: Box<Perlin>,
    },
}

impl ThicknessField {
    pub fn noise(min_nm: f32, max_nm: f32, scale: f32, seed: u32) -> ThicknessField {
        ThicknessField::Noise {
            min_nm,
            max_nm,
            scale,
            perlin: Box::new(Perlin::new(seed)),
        }
    }

    #[inline]
    pub fn at(&self, p: Vec3) -> f32 {
        match self {
            ThicknessField::Uniform { thickness_nm } => *thickness_nm,
            ThicknessField::Noise {
                min_nm,
                max_nm,
                scale,
                perlin,
            } => {
                let q = *scale * p;
                let n = unit_noise(perlin, [q.x as f64, q.y as f64, q.z as f64]);
                min_nm + (max_nm - min_nm) * n
            }
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

/// Perlin noise mapped from its signed range to [0, 1]. The `noise` crate
/// scales 3D Perlin so its output lies in [−1, 1]; the clamp only guards
/// against rounding, so d(p) never leaves [d_min, d_max].
#[inline]
fn unit_noise(perlin: &Perlin, p: [f64; 3]) -> f32 {
    ((perlin.get(p) * 0.5 + 0.5) as f32).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> impl Iterator<Item = Vec3> {
        (0..40).flat_map(|i| {
            (0..40).flat_map(move |j| {
                (0..10).map(move |k| {
                    Vec3::new(
                        i as f32 * 0.173,
                        j as f32 * 0.131 - 2.0,
                        k as f32 * 0.291 + 0.05,
                    )
                })
            })
        })
    }

    #[test]
    fn noise_field_stays_in_range_and_uses_it() {
        let f = ThicknessField::noise(100.0, 1000.0, 1.3, 7);
        let (mut lo, mut hi, mut sum, mut n) = (f32::MAX, f32::MIN, 0.0f64, 0);
        for p in grid() {
            let d = f.at(p);
            assert!((100.0..=1000.0).contains(&d), "d = {d} at {p}");
            lo = lo.min(d);
            hi = hi.max(d);
            sum += d as f64;
            n += 1;
        }
        // Perlin noise clusters around its middle, but a field this size must
        // spread well across the range and be centred in it.
        assert!(lo < 300.0 && hi > 800.0, "range used: {lo}..{hi}");
        let mean = sum / n as f64;
        assert!((mean - 550.0).abs() < 60.0, "mean {mean}");
    }

    #[test]
    fn noise_field_is_continuous_deterministic_and_seeded() {
        let a = ThicknessField::noise(0.0, 1.0, 2.0, 3);
        let b = ThicknessField::noise(0.0, 1.0, 2.0, 3);
        let c = ThicknessField::noise(0.0, 1.0, 2.0, 4);
        let mut differs = false;
        for p in grid() {
            assert_eq!(a.at(p).to_bits(), b.at(p).to_bits());
            differs |= (a.at(p) - c.at(p)).abs() > 1e-3;
            // Gradient of Perlin noise is bounded: a tiny step moves it little.
            let step = a.at(p + Vec3::splat(1e-4)) - a.at(p);
            assert!(step.abs() < 1e-2, "jump {step} at {p}");
        }
        assert!(differs, "another seed must give another field");
    }

    #[test]
    fn scale_sets_the_frequency() {
        // Perlin noise is 0 (mapped: 0.5) on the integer lattice of s·p.
        let f = ThicknessField::noise(0.0, 1.0, 0.5, 1);
        for p in [Vec3::new(2.0, 4.0, -6.0), Vec3::new(0.0, 2.0, 8.0)] {
            assert!((f.at(p) - 0.5).abs() < 1e-6);
        }
        let u = ThicknessField::Uniform {
            thickness_nm: 420.0,
        };
        assert_eq!(u.at(Vec3::new(1.0, 2.0, 3.0)), 420.0);
        assert_eq!(u.range_nm(), (420.0, 420.0));
    }
}
