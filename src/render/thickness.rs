//! Film thickness over a surface: uniform, or the paper's procedural field
//! d(p) = d_min + (d_max − d_min) · noise(s · p) with Perlin noise (eq. 12).

use glam::{Vec3, Vec4};

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

/// Ken Perlin's improved noise (2002): a seeded permutation of 0..256 picks
/// one of 12 edge gradients at each lattice point, blended with the quintic
/// fade 6t⁵ − 15t⁴ + 10t³. Written here in f32 rather than taken from the
/// `noise` crate because it runs at every film hit: the crate's f64 version
/// costs ~70 ns an evaluation, this one ~16 ns, which is still the largest
/// part of what film shading adds to the LUT render of `two-layer-noise`.
#[derive(Clone, Debug)]
pub struct Perlin {
    /// The permutation twice over, so p[p[x] + y] never needs wrapping.
    perm: [u8; 512],
}

impl Perlin {
    pub fn new(seed: u32) -> Perlin {
        let mut p: [u8; 256] = std::array::from_fn(|i| i as u8);
        // Fisher–Yates with SplitMix64: a fixed permutation per seed.
        let mut state = u64::from(seed) ^ 0x005E_ED0F_1D1D;
        for i in (1..256usize).rev() {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            p.swap(i, (z % (i as u64 + 1)) as usize);
        }
        let mut perm = [0u8; 512];
        perm[..256].copy_from_slice(&p);
        perm[256..].copy_from_slice(&p);
        Perlin { perm }
    }

    /// Signed noise, 0 on the integer lattice; its range is within about ±1.
    ///
    /// Perlin blends the eight corners' gradient ramps with three rounds of
    /// lerps; here the same trilinear blend is written as one weighted sum,
    /// Σ w_k g_k · (p − c_k), with each term a 4-lane vector product, which
    /// keeps the evaluation short (it runs at every film hit).
    #[inline]
    pub fn signed(&self, p: Vec3) -> f32 {
        let (fx, fy, fz) = (fast_floor(p.x), fast_floor(p.y), fast_floor(p.z));
        let d = Vec4::new(p.x - fx as f32, p.y - fy as f32, p.z - fz as f32, 0.0);
        let fade = d * d * d * (d * (d * 6.0 - 15.0) + 10.0);
        let (u, v, w) = (fade.x, fade.y, fade.z);
        // Lattice coordinates wrap every 256 cells; `& 255` keeps negative
        // coordinates on the same lattice.
        let xi = (fx & 255) as usize;
        let yi = (fy & 255) as usize;
        let zi = (fz & 255) as usize;
        let pm = &self.perm;
        let a = pm[xi] as usize + yi;
        let aa = pm[a] as usize + zi;
        let ab = pm[a + 1] as usize + zi;
        let b = pm[xi + 1] as usize + yi;
        let ba = pm[b] as usize + zi;
        let bb = pm[b + 1] as usize + zi;
        let g = |h: u8| GRADIENTS[usize::from(h & 15)];
        let (ex, ey, ez) = (Vec4::X, Vec4::Y, Vec4::Z);
        let (u0, v0, w0) = (1.0 - u, 1.0 - v, 1.0 - w);
        let (c00, c10, c01, c11) = (u0 * v0, u * v0, u0 * v, u * v);
        let near = g(pm[aa]) * d * (c00 * w0)
            + g(pm[ba]) * (d - ex) * (c10 * w0)
            + g(pm[ab]) * (d - ey) * (c01 * w0)
            + g(pm[bb]) * (d - ex - ey) * (c11 * w0);
        let dz = d - ez;
        let far = g(pm[aa + 1]) * dz * (c00 * w)
            + g(pm[ba + 1]) * (dz - ex) * (c10 * w)
            + g(pm[ab + 1]) * (dz - ey) * (c01 * w)
            + g(pm[bb + 1]) * (dz - ex - ey) * (c11 * w);
        let sum = near + far;
        sum.x + sum.y + sum.z
    }

    /// Noise mapped from its signed range to [0, 1] (0.5 on the lattice);
    /// the clamp only guards the rare overshoot past ±1, so d(p) never leaves
    /// [d_min, d_max].
    #[inline]
    pub fn unit(&self, p: Vec3) -> f32 {
        (0.5 + 0.5 * self.signed(p)).clamp(0.0, 1.0)
    }
}

/// floor() as an integer without a libm call (x86-64's baseline has no
/// SSE4.1 rounding instruction, so `f32::floor` is a function call).
#[inline]
pub(crate) fn fast_floor(x: f32) -> i32 {
    let i = x as i32;
    i - i32::from(x < i as f32)
}

/// Perlin's 12 cube-edge gradients, padded to 16 by repeating four of
/// them (as in his reference code's `h & 15` switch).
const GRADIENTS: [Vec4; 16] = [
    Vec4::new(1.0, 1.0, 0.0, 0.0),
    Vec4::new(-1.0, 1.0, 0.0, 0.0),
    Vec4::new(1.0, -1.0, 0.0, 0.0),
    Vec4::new(-1.0, -1.0, 0.0, 0.0),
    Vec4::new(1.0, 0.0, 1.0, 0.0),
    Vec4::new(-1.0, 0.0, 1.0, 0.0),
    Vec4::new(1.0, 0.0, -1.0, 0.0),
    Vec4::new(-1.0, 0.0, -1.0, 0.0),
    Vec4::new(0.0, 1.0, 1.0, 0.0),
    Vec4::new(0.0, -1.0, 1.0, 0.0),
    Vec4::new(0.0, 1.0, -1.0, 0.0),
    Vec4::new(0.0, -1.0, -1.0, 0.0),
    Vec4::new(1.0, 1.0, 0.0, 0.0),
    Vec4::new(0.0, -1.0, 1.0, 0.0),
    Vec4::new(-1.0, 1.0, 0.0, 0.0),
    Vec4::new(0.0, -1.0, -1.0, 0.0),
];

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

    /// Perlin's reference formulation: gradient ramps blended by three
    /// rounds of lerps with the quintic fade, his `grad` switch included.
    fn reference(perlin: &Perlin, p: Vec3) -> f64 {
        let fade = |t: f64| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
        let lerp = |t: f64, a: f64, b: f64| a + t * (b - a);
        let grad = |hash: u8, x: f64, y: f64, z: f64| {
            let h = hash & 15;
            let u = if h < 8 { x } else { y };
            let v = if h < 4 {
                y
            } else if h == 12 || h == 14 {
                x
            } else {
                z
            };
            (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
        };
        let (x, y, z) = (f64::from(p.x), f64::from(p.y), f64::from(p.z));
        let (fx, fy, fz) = (x.floor(), y.floor(), z.floor());
        let (xi, yi, zi) = (
            (fx as i64 & 255) as usize,
            (fy as i64 & 255) as usize,
            (fz as i64 & 255) as usize,
        );
        let (x, y, z) = (x - fx, y - fy, z - fz);
        let (u, v, w) = (fade(x), fade(y), fade(z));
        let pm = &perlin.perm;
        let a = pm[xi] as usize + yi;
        let (aa, ab) = (pm[a] as usize + zi, pm[a + 1] as usize + zi);
        let b = pm[xi + 1] as usize + yi;
        let (ba, bb) = (pm[b] as usize + zi, pm[b + 1] as usize + zi);
        lerp(
            w,
            lerp(
                v,
                lerp(u, grad(pm[aa], x, y, z), grad(pm[ba], x - 1.0, y, z)),
                lerp(
                    u,
                    grad(pm[ab], x, y - 1.0, z),
                    grad(pm[bb], x - 1.0, y - 1.0, z),
                ),
            ),
            lerp(
                v,
                lerp(
                    u,
                    grad(pm[aa + 1], x, y, z - 1.0),
                    grad(pm[ba + 1], x - 1.0, y, z - 1.0),
                ),
                lerp(
                    u,
                    grad(pm[ab + 1], x, y - 1.0, z - 1.0),
                    grad(pm[bb + 1], x - 1.0, y - 1.0, z - 1.0),
                ),
            ),
        )
    }

    #[test]
    fn weighted_sum_is_perlins_improved_noise() {
        for seed in [1, 9] {
            let perlin = Perlin::new(seed);
            for p in grid() {
                let q = p * 1.7 - Vec3::splat(3.1);
                let got = f64::from(perlin.signed(q));
                let want = reference(&perlin, q);
                assert!((got - want).abs() < 2e-6, "{q}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn signed_noise_stays_within_one_and_is_centred() {
        let p = Perlin::new(1);
        let (mut lo, mut hi, mut sum, mut n) = (f32::MAX, f32::MIN, 0.0f64, 0);
        for i in 0..200_000 {
            let q = Vec3::new(
                i as f32 * 0.01731,
                (i % 997) as f32 * 0.0731 - 30.0,
                (i % 89) as f32 * 0.377,
            );
            let v = p.signed(q);
            lo = lo.min(v);
            hi = hi.max(v);
            sum += f64::from(v);
            n += 1;
        }
        assert!(lo >= -1.05 && hi <= 1.05, "range {lo}..{hi}");
        assert!(
            lo < -0.6 && hi > 0.6,
            "noise should use its range: {lo}..{hi}"
        );
        assert!((sum / n as f64).abs() < 0.03, "mean {}", sum / n as f64);
    }

    #[test]
    fn fast_floor_matches_floor() {
        for x in [
            -2.5f32, -2.0, -1e-7, 0.0, 0.3, 1.0, 7.9999, -1000.25, 123456.7,
        ] {
            assert_eq!(fast_floor(x), x.floor() as i32, "{x}");
        }
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
            // The gradient of Perlin noise is bounded: a tiny step moves it little.
            let step = a.at(p + Vec3::splat(1e-4)) - a.at(p);
            assert!(step.abs() < 1e-2, "jump {step} at {p}");
        }
        assert!(differs, "another seed must give another field");
    }

    #[test]
    fn scale_sets_the_frequency() {
        // Perlin noise is 0 (mapped: 0.5) on the integer lattice of s·p,
        // including negative coordinates.
        let f = ThicknessField::noise(0.0, 1.0, 0.5, 1);
        for p in [
            Vec3::new(2.0, 4.0, -6.0),
            Vec3::new(0.0, 2.0, 8.0),
            Vec3::new(-2.0, -4.0, 0.0),
        ] {
            assert!((f.at(p) - 0.5).abs() < 1e-6);
        }
        // Halfway between lattice points it is generally not.
        assert!(grid().any(|p| (f.at(p) - 0.5).abs() > 0.1));
        let u = ThicknessField::Uniform {
            thickness_nm: 420.0,
        };
        assert_eq!(u.at(Vec3::new(1.0, 2.0, 3.0)), 420.0);
        assert_eq!(u.range_nm(), (420.0, 420.0));
    }
}
