//! How the gain film's colour grows towards a lasing pole (docs/limits.md,
//! "Lasing poles"): `cargo run --release --example pole_divergence`.
//! At 214.844 nm of luts/gain-on-gold.toml, finds the peak of the reflected
//! colour over cos θ 0.050–0.060 at 64 points per nanometre, then prints
//! the largest channel of the reflected linear RGB at distances δ in cos θ
//! from it, integrated at 1, 4, 16 and 64 points per nanometre, and the
//! finest times δ (constant where the colour diverges as 1 / δ).
use irid::color::refine::Refinement;
use irid::color::{Sampling, SpectralIntegrator, White};
use irid::optics::Stack;

const THICKNESS_NM: f64 = 214.844;

fn main() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/luts/gain-on-gold.toml");
    let stack = Stack::load(path.as_ref()).unwrap_or_else(|e| {
        eprintln!("pole_divergence: {path}: {e}");
        std::process::exit(2);
    });
    let integ = SpectralIntegrator::with_white(Sampling::Exact, White::D65);
    let refinement = Refinement::new(&stack, Some(1), &integ).expect("the stack integrates");
    let mut thicknesses = stack.thicknesses_nm();
    thicknesses[0] = THICKNESS_NM;
    let colour = |m: usize, c: f64| {
        let level = refinement.level(m).expect("a level of the integration");
        let p = level
            .grid
            .weighted_spectrum(&thicknesses, c, &level.weights);
        p.reflectance[0].max(p.reflectance[1]).max(p.reflectance[2])
    };
    let (peak, at) = (0..=2000)
        .map(|k| 0.050 + 5e-6 * k as f64)
        .map(|c| (colour(64, c), c))
        .fold((0.0, 0.0), |a, b| if b.0 > a.0 { b } else { a });
    println!("peak at 64 / nm: {peak:.1} at cos θ {at:.6}");
    for delta in [3e-3, 1e-3, 3e-4, 1e-4, 3e-5] {
        for sign in [-1.0, 1.0] {
            let c = at + sign * delta;
            let sums: Vec<String> = [1, 4, 16, 64]
                .iter()
                .map(|&m| format!("{:.2}", colour(m, c)))
                .collect();
            println!(
                "δ {:+.0e}: at 1, 4, 16, 64 / nm {}; 64 / nm × δ {:.3}",
                sign * delta,
                sums.join(" "),
                colour(64, c) * delta
            );
        }
    }
}
