//! Random stacks for the solver tests that compare two solvers point by
//! point: one draw of indices and thicknesses, so every such test covers
//! the same kinds of media.

use num_complex::Complex64 as C64;
use rand::Rng;
use rand_pcg::Pcg64;

/// What the layers and substrate of a random stack may be.
#[derive(Clone, Copy, Debug)]
pub enum Kind {
    /// Every medium real.
    Lossless,
    /// Half the layers absorbing, the substrate lossy.
    Passive,
    /// Layers with k down to −0.05 (gain), the substrate lossy.
    WithGain,
    /// Absorbing layers on a metal substrate.
    Metal,
}

/// Every kind, in the order the tests cycle through them.
pub const KINDS: [Kind; 4] = [Kind::Lossless, Kind::Passive, Kind::WithGain, Kind::Metal];

/// A stack of `layers` layers: its N + 2 indices (a lossless ambient of
/// index 1–2 first, the substrate last) and N thicknesses up to `max_nm`.
pub fn random_stack(
    rng: &mut Pcg64,
    kind: Kind,
    layers: usize,
    max_nm: f64,
) -> (Vec<C64>, Vec<f64>) {
    let mut n = vec![C64::new(rng.random_range(1.0..2.0), 0.0)];
    for _ in 0..layers {
        let k = match kind {
            Kind::Lossless => 0.0,
            Kind::Passive | Kind::Metal if rng.random_bool(0.5) => 0.0,
            Kind::Passive | Kind::Metal => rng.random_range(0.0..1.0),
            Kind::WithGain => rng.random_range(-0.05..0.5),
        };
        n.push(C64::new(rng.random_range(1.0..3.0), k));
    }
    n.push(match kind {
        Kind::Lossless => C64::new(rng.random_range(1.0..2.5), 0.0),
        Kind::Metal => C64::new(rng.random_range(0.05..2.0), rng.random_range(1.0..8.0)),
        _ => C64::new(rng.random_range(1.0..2.5), rng.random_range(0.0..0.5)),
    });
    let d = (0..layers).map(|_| rng.random_range(0.0..max_nm)).collect();
    (n, d)
}
