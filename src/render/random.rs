//! The renderer's random numbers: one small generator per camera sample,
//! seeded from the render's seed, the pixel and the sample's index, so an
//! image does not depend on threads or scheduling.

/// SplitMix64: a tiny, well-mixed generator; ample for pixel jitter and
/// microfacet sampling.
#[derive(Clone, Debug)]
pub struct SplitMix(u64);

impl SplitMix {
    /// The generator of camera sample `sample` of pixel `pixel_index` in a
    /// render seeded with `seed`.
    pub fn for_sample(seed: u64, pixel_index: u64, sample: u32) -> SplitMix {
        SplitMix(seed ^ pixel_index.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (u64::from(sample) << 40))
    }

    /// A generator started from `state`.
    pub fn new(state: u64) -> SplitMix {
        SplitMix(state)
    }

    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A uniform number in [0, 1), 24 bits.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
}

thread_local! {
    /// The state of the generator of the camera sample this thread traces.
    static SAMPLE: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// The generator of the camera sample being traced, per thread: the
/// renderer starts it before tracing a sample, and a rough surface draws
/// from it. A thread traces one sample to its end before the next (nothing
/// the tracer calls hands work to rayon, which could start another sample
/// on the same thread), so the numbers a surface gets depend only on the
/// sample, not on scheduling.
/// (A parameter threaded through the tracer would do the same, at the cost
/// of one more argument on every call of the smooth path.)
pub struct SampleRng;

impl SampleRng {
    /// Makes `rng` the generator of the sample about to be traced.
    #[inline]
    pub fn start(rng: SplitMix) {
        SAMPLE.with(|s| s.set(rng.0));
    }

    /// Two uniform numbers in [0, 1) from the current sample's generator.
    #[inline]
    pub fn pair() -> (f32, f32) {
        SAMPLE.with(|s| {
            let mut rng = SplitMix(s.get());
            let pair = (rng.next_f32(), rng.next_f32());
            s.set(rng.0);
            pair
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_on_the_unit_interval() {
        let mut r = SplitMix::new(42);
        let v: Vec<f32> = (0..10_000).map(|_| r.next_f32()).collect();
        assert!(v.iter().all(|x| (0.0..1.0).contains(x)));
        let mean = v.iter().sum::<f32>() / v.len() as f32;
        assert!((mean - 0.5).abs() < 0.02, "{mean}");
    }
}
