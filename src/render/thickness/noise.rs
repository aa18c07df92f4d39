//! Perlin's improved noise with hashed gradients, portable and in AVX2
//! lanes.

use glam::{Vec3, Vec4};

use super::{avx2_available, fast_floor};

/// Ken Perlin's improved noise (2002): one of 12 edge gradients at each
/// lattice point, blended with the quintic fade 6t⁵ − 15t⁴ + 10t³.
///
/// Perlin picks a lattice point's gradient through a seeded permutation of
/// 0..256 looked up three times (p[p[p[x] + y] + z]); here an integer hash
/// of the lattice coordinates and the seed picks it instead. The field has
/// the same form and statistics, does not repeat every 256 cells, and all
/// eight corners of a cell can be hashed at once in one vector register,
/// which is what makes it cheap: the noise runs at every film hit and was
/// the largest part of what film shading adds to a LUT render (the `noise`
/// crate's f64 version costs ~70 ns an evaluation; a scalar f32 table
/// version ~16 ns; this one, in AVX2 lanes, is timed by the bench's
/// `film hit` group).
#[derive(Clone, Debug)]
pub struct Perlin {
    /// The seed, spread over 32 bits so nearby seeds give unrelated fields.
    key: u32,
    /// Whether this CPU runs the AVX2 evaluation (checked once, here).
    avx2: bool,
}

/// Offsets of a cell's eight corners from its lowest one; corner k is
/// (k & 1, (k >> 1) & 1, k >> 2), the order of the vector lanes.
const CORNER_X: [i32; 8] = [0, 1, 0, 1, 0, 1, 0, 1];
const CORNER_Y: [i32; 8] = [0, 0, 1, 1, 0, 0, 1, 1];
const CORNER_Z: [i32; 8] = [0, 0, 0, 0, 1, 1, 1, 1];

/// Large odd multipliers for the three lattice coordinates (the spatial
/// hash of Teschner et al. 2003), then Wellons' `lowbias32` finaliser, so
/// that every bit of the result depends on every input bit.
const HASH_X: u32 = 0x8DA6_B343;
const HASH_Y: u32 = 0xD816_3841;
const HASH_Z: u32 = 0xCB1A_B31F;
const MIX_1: u32 = 0x7FEB_352D;
const MIX_2: u32 = 0x846C_A68B;

/// The gradient index (0..16) of lattice point (x, y, z).
#[inline(always)]
fn gradient_index(x: i32, y: i32, z: i32, key: u32) -> u32 {
    let mut h = (x as u32).wrapping_mul(HASH_X)
        ^ (y as u32).wrapping_mul(HASH_Y)
        ^ (z as u32).wrapping_mul(HASH_Z)
        ^ key;
    h ^= h >> 16;
    h = h.wrapping_mul(MIX_1);
    h ^= h >> 15;
    h = h.wrapping_mul(MIX_2);
    h ^= h >> 16;
    h >> 28
}

/// Perlin's gradient ramp g·(x, y, z) for gradient index `h`, written as
/// his reference code's `grad` switch (indices 12..15 repeat four of the
/// 12 edge directions so that 16 choices stay unbiased).
#[inline(always)]
fn gradient_dot(h: u32, x: f32, y: f32, z: f32) -> f32 {
    let u = if h < 8 { x } else { y };
    let v = if h < 4 {
        y
    } else if h | 2 == 14 {
        x
    } else {
        z
    };
    // Sign flips by the sign bit, as the vector code does, so the two
    // agree bit for bit (−0.0 included).
    let u = f32::from_bits(u.to_bits() ^ ((h & 1) << 31));
    let v = f32::from_bits(v.to_bits() ^ ((h & 2) << 30));
    u + v
}

/// The quintic fade, on all lanes at once.
#[inline(always)]
fn fade(d: Vec4) -> Vec4 {
    d * d * d * (d * (d * 6.0 - 15.0) + 10.0)
}

impl Perlin {
    /// The noise field for `seed`: the seed is hashed (SplitMix64's
    /// finaliser) into the permutation key, so nearby seeds give unrelated
    /// fields. Uses the AVX2 code when the CPU has it (same values bit for
    /// bit).
    pub fn new(seed: u32) -> Perlin {
        // SplitMix64's finaliser: seeds 1 and 2 get unrelated keys.
        let mut z = u64::from(seed).wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        Perlin {
            key: z as u32,
            avx2: avx2_available(),
        }
    }

    /// The same field evaluated by the portable code even where the CPU has
    /// AVX2 (the values are the same bit for bit): for measuring what the
    /// AVX2 copy gains.
    pub fn portable(mut self) -> Perlin {
        self.avx2 = false;
        self
    }

    /// Signed noise, 0 on the integer lattice; its range is within about ±1.
    #[inline]
    pub fn signed(&self, p: Vec3) -> f32 {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is only set when the CPU has AVX2.
            return unsafe { signed_avx2(self.key, p.x, p.y, p.z) };
        }
        self.signed_portable(p)
    }

    /// Noise mapped from its signed range to [0, 1] (0.5 on the lattice);
    /// the clamp only guards the rare overshoot past ±1, so d(p) never leaves
    /// [d_min, d_max].
    #[inline]
    pub fn unit(&self, p: Vec3) -> f32 {
        (0.5 + 0.5 * self.signed(p)).clamp(0.0, 1.0)
    }

    /// The same sum as the AVX2 code, one corner at a time, in the same
    /// order of operations, so every CPU gets the same image bit for bit.
    fn signed_portable(&self, p: Vec3) -> f32 {
        let (fx, fy, fz) = (fast_floor(p.x), fast_floor(p.y), fast_floor(p.z));
        let d = Vec4::new(p.x - fx as f32, p.y - fy as f32, p.z - fz as f32, 0.0);
        let f = fade(d);
        let mut terms = [0.0f32; 8];
        for (k, term) in terms.iter_mut().enumerate() {
            let (cx, cy, cz) = (CORNER_X[k], CORNER_Y[k], CORNER_Z[k]);
            let h = gradient_index(
                fx.wrapping_add(cx),
                fy.wrapping_add(cy),
                fz.wrapping_add(cz),
                self.key,
            );
            let g = gradient_dot(h, d.x - cx as f32, d.y - cy as f32, d.z - cz as f32);
            let pick = |c: i32, t: f32| if c == 1 { t } else { 1.0 - t };
            let weight = pick(cx, f.x) * pick(cy, f.y) * pick(cz, f.z);
            *term = weight * g;
        }
        let t = terms;
        ((t[0] + t[4]) + (t[2] + t[6])) + ((t[1] + t[5]) + (t[3] + t[7]))
    }
}

/// The eight corners in the eight lanes of one AVX2 register: hash,
/// gradient choice, ramp and weight for all of them at once. Takes scalars,
/// not a `Vec3` behind a reference: it is not inlined into its caller.
///
/// # Safety
///
/// The CPU must support AVX2 (`is_x86_feature_detected!("avx2")`); the
/// function reads and writes no memory through pointers.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn signed_avx2(key: u32, px: f32, py: f32, pz: f32) -> f32 {
    let p = Vec3::new(px, py, pz);
    use std::arch::x86_64::*;
    let (fx, fy, fz) = (fast_floor(p.x), fast_floor(p.y), fast_floor(p.z));
    let d = Vec4::new(p.x - fx as f32, p.y - fy as f32, p.z - fz as f32, 0.0);
    let f = fade(d);
    // Closures here would not inherit this function's target feature
    // and each intrinsic in them would become a call: everything is
    // written out.
    let cx = _mm256_setr_epi32(0, 1, 0, 1, 0, 1, 0, 1);
    let cy = _mm256_setr_epi32(0, 0, 1, 1, 0, 0, 1, 1);
    let cz = _mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1);
    let xs = _mm256_add_epi32(_mm256_set1_epi32(fx), cx);
    let ys = _mm256_add_epi32(_mm256_set1_epi32(fy), cy);
    let zs = _mm256_add_epi32(_mm256_set1_epi32(fz), cz);
    let mut h = _mm256_xor_si256(
        _mm256_xor_si256(
            _mm256_mullo_epi32(xs, _mm256_set1_epi32(HASH_X as i32)),
            _mm256_mullo_epi32(ys, _mm256_set1_epi32(HASH_Y as i32)),
        ),
        _mm256_xor_si256(
            _mm256_mullo_epi32(zs, _mm256_set1_epi32(HASH_Z as i32)),
            _mm256_set1_epi32(key as i32),
        ),
    );
    h = _mm256_xor_si256(h, _mm256_srli_epi32::<16>(h));
    h = _mm256_mullo_epi32(h, _mm256_set1_epi32(MIX_1 as i32));
    h = _mm256_xor_si256(h, _mm256_srli_epi32::<15>(h));
    h = _mm256_mullo_epi32(h, _mm256_set1_epi32(MIX_2 as i32));
    h = _mm256_xor_si256(h, _mm256_srli_epi32::<16>(h));
    let h = _mm256_srli_epi32::<28>(h);

    // Offsets from each corner: d − c, exact for c ∈ {0, 1}.
    let (cxf, cyf, czf) = (
        _mm256_cvtepi32_ps(cx),
        _mm256_cvtepi32_ps(cy),
        _mm256_cvtepi32_ps(cz),
    );
    let x = _mm256_sub_ps(_mm256_set1_ps(d.x), cxf);
    let y = _mm256_sub_ps(_mm256_set1_ps(d.y), cyf);
    let z = _mm256_sub_ps(_mm256_set1_ps(d.z), czf);
    let below_8 = _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(8), h));
    let below_4 = _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(4), h));
    let is_12_or_14 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
        _mm256_or_si256(h, _mm256_set1_epi32(2)),
        _mm256_set1_epi32(14),
    ));
    let u = _mm256_blendv_ps(y, x, below_8);
    let v = _mm256_blendv_ps(_mm256_blendv_ps(z, x, is_12_or_14), y, below_4);
    let sign_u = _mm256_slli_epi32::<31>(h);
    let sign_v = _mm256_slli_epi32::<30>(_mm256_and_si256(h, _mm256_set1_epi32(2)));
    let u = _mm256_xor_ps(u, _mm256_castsi256_ps(sign_u));
    let v = _mm256_xor_ps(v, _mm256_castsi256_ps(sign_v));
    let g = _mm256_add_ps(u, v);

    // Corner weights: the fade where the corner's offset is 1, one
    // minus it where 0: (1 − t) + c·(2t − 1) would round differently
    // from the portable code, so select instead.
    let wx = _mm256_blendv_ps(
        _mm256_set1_ps(1.0 - f.x),
        _mm256_set1_ps(f.x),
        _mm256_castsi256_ps(_mm256_slli_epi32::<31>(cx)),
    );
    let wy = _mm256_blendv_ps(
        _mm256_set1_ps(1.0 - f.y),
        _mm256_set1_ps(f.y),
        _mm256_castsi256_ps(_mm256_slli_epi32::<31>(cy)),
    );
    let wz = _mm256_blendv_ps(
        _mm256_set1_ps(1.0 - f.z),
        _mm256_set1_ps(f.z),
        _mm256_castsi256_ps(_mm256_slli_epi32::<31>(cz)),
    );
    let weight = _mm256_mul_ps(_mm256_mul_ps(wx, wy), wz);
    let t = _mm256_mul_ps(weight, g);

    // ((t0 + t4) + (t2 + t6)) + ((t1 + t5) + (t3 + t7)), as above.
    let s4 = _mm_add_ps(_mm256_castps256_ps128(t), _mm256_extractf128_ps::<1>(t));
    let s2 = _mm_add_ps(s4, _mm_movehl_ps(s4, s4));
    let s1 = _mm_add_ss(s2, _mm_shuffle_ps::<0b01>(s2, s2));
    _mm_cvtss_f32(s1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::thickness::ThicknessField;

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
    /// rounds of lerps with the quintic fade, in f64, his `grad` switch
    /// written out as he wrote it; only the gradient choice is shared.
    fn reference(perlin: &Perlin, p: Vec3) -> f64 {
        let fade = |t: f64| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
        let lerp = |t: f64, a: f64, b: f64| a + t * (b - a);
        let grad = |h: u32, x: f64, y: f64, z: f64| {
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
        let (xi, yi, zi) = (fx as i32, fy as i32, fz as i32);
        let (x, y, z) = (x - fx, y - fy, z - fz);
        let (u, v, w) = (fade(x), fade(y), fade(z));
        let corner = |i: i32, j: i32, k: i32| {
            let h = gradient_index(xi + i, yi + j, zi + k, perlin.key);
            grad(h, x - f64::from(i), y - f64::from(j), z - f64::from(k))
        };
        lerp(
            w,
            lerp(
                v,
                lerp(u, corner(0, 0, 0), corner(1, 0, 0)),
                lerp(u, corner(0, 1, 0), corner(1, 1, 0)),
            ),
            lerp(
                v,
                lerp(u, corner(0, 0, 1), corner(1, 0, 1)),
                lerp(u, corner(0, 1, 1), corner(1, 1, 1)),
            ),
        )
    }

    #[test]
    fn weighted_sum_is_perlins_improved_noise() {
        for seed in [1, 9] {
            let mut perlin = Perlin::new(seed);
            for avx2 in [false, avx2_available()] {
                perlin.avx2 = avx2;
                for p in grid() {
                    let q = p * 1.7 - Vec3::splat(3.1);
                    let got = f64::from(perlin.signed(q));
                    let want = reference(&perlin, q);
                    assert!((got - want).abs() < 2e-6, "{q}: {got} vs {want}");
                }
            }
        }
    }

    /// The vector and portable evaluations are the same arithmetic in the
    /// same order: a render must not depend on which one the CPU runs.
    #[test]
    fn avx2_and_portable_agree_bit_for_bit() {
        if !avx2_available() {
            return;
        }
        let perlin = Perlin::new(5);
        let mut state = 1u64;
        for _ in 0..100_000 {
            let mut next = || {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((state >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 2000.0
            };
            let p = Vec3::new(next(), next(), next());
            // SAFETY: the CPU has AVX2 (checked above).
            let fast = unsafe { signed_avx2(perlin.key, p.x, p.y, p.z) };
            assert_eq!(fast.to_bits(), perlin.signed_portable(p).to_bits(), "{p}");
        }
    }

    /// Every one of the 16 gradient choices occurs, about equally often:
    /// the hash must not favour directions (that would streak the field).
    #[test]
    fn gradient_choices_are_balanced() {
        let mut counts = [0u32; 16];
        for x in -20..20 {
            for y in -20..20 {
                for z in -20..20 {
                    counts[gradient_index(x, y, z, 12345) as usize] += 1;
                }
            }
        }
        let expected = 64_000.0 / 16.0;
        for (h, &c) in counts.iter().enumerate() {
            assert!(
                (f64::from(c) - expected).abs() < 0.06 * expected,
                "gradient {h}: {c} of 64000"
            );
        }
    }

    /// Unlike Perlin's 256-entry permutation, the lattice hash does not
    /// repeat: cells 256 apart get different gradients.
    #[test]
    fn field_does_not_repeat_every_256_cells() {
        let mut perlin = Perlin::new(3);
        for avx2 in [false, avx2_available()] {
            perlin.avx2 = avx2;
            let same = grid()
                .filter(|&p| {
                    let q = p + Vec3::new(0.37, 0.11, 0.59);
                    (perlin.signed(q) - perlin.signed(q + Vec3::new(256.0, 0.0, 0.0))).abs() < 1e-6
                })
                .count();
            assert!(
                same < 100,
                "{same} of 16000 points repeat at 256 cells (avx2 {avx2})"
            );
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
