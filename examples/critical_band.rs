//! The 10-layer mirror seen from its glass side (luts/mirror-10.toml
//! reversed, its TiO2 layer next to the air varying) near its critical
//! angle, where its export spends its time (docs/limits.md, "The mirror
//! from its glass side"): `cargo run --release --example critical_band`.
//! Per cos θ: the points per nanometre the colour integration asks for at
//! 100 nm, then along thickness 90–110 nm, at spacings 0.4 and 0.1 nm and
//! at 1, 4, 16 and 64 points per nanometre, the largest deviation of a
//! node's colour from the mean of its neighbours (what a linear
//! interpolation between them misses), and the largest difference from
//! the 64 / nm colour.
use irid::color::refine::Refinement;
use irid::color::{Sampling, SpectralIntegrator, White};
use irid::optics::Stack;

const DENSITIES: [usize; 4] = [1, 4, 16, 64];

fn main() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/luts/mirror-10.toml");
    let stack = Stack::load(path.as_ref())
        .unwrap_or_else(|e| {
            eprintln!("critical_band: {path}: {e}");
            std::process::exit(2);
        })
        .reversed();
    let layer = stack.layers.len();
    let integ = SpectralIntegrator::with_white(Sampling::Exact, White::D65);
    let refinement = Refinement::new(&stack, Some(layer), &integ).expect("the stack integrates");
    let colour = |m: usize, d: f64, c: f64| -> [f64; 6] {
        let mut thicknesses = stack.thicknesses_nm();
        thicknesses[layer - 1] = d;
        let level = refinement.level(m).expect("a level of the integration");
        let p = level
            .grid
            .weighted_spectrum(&thicknesses, c, &level.weights);
        let (r, t) = (p.reflectance, p.transmittance);
        [r[0], r[1], r[2], t[0], t[1], t[2]]
    };
    let largest =
        |a: &[f64; 6], b: &[f64; 6]| (0..6).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max);
    for c in [0.7265, 0.728, 0.729, 0.731, 0.734] {
        println!(
            "cos θ {c}: {} / nm asked at 100 nm",
            refinement.sub_steps(100.0, c)
        );
        for h in [0.4, 0.1] {
            let n = (20.0 / h) as usize;
            let line = |m: usize| -> Vec<[f64; 6]> {
                (0..=n).map(|k| colour(m, 90.0 + h * k as f64, c)).collect()
            };
            let finest = line(64);
            for m in DENSITIES {
                let v = line(m);
                let deviation = (1..n)
                    .map(|k| {
                        let mean: [f64; 6] =
                            std::array::from_fn(|ch| 0.5 * (v[k - 1][ch] + v[k + 1][ch]));
                        largest(&mean, &v[k])
                    })
                    .fold(0.0, f64::max);
                let off = v
                    .iter()
                    .zip(&finest)
                    .map(|(a, b)| largest(a, b))
                    .fold(0.0, f64::max);
                println!(
                    "  {h} nm apart, {m:2} / nm: deviation {deviation:.2e}, from 64 / nm {off:.2e}"
                );
            }
        }
    }
}
