//! Where and how much the converged colour (docs/color.md) moves from the
//! 1 nm sum, for a stack file whose layer 1 varies over 0–1000 nm:
//! `cargo run --release --example converged_colour luts/soap-film.toml`.
//! Per cos θ: the least thickness integrated more finely, the largest
//! change of the reflected linear RGB, the points per nanometre there, and
//! the change at twice that density.
use irid::color::refine::Refinement;
use irid::color::{Sampling, SpectralIntegrator, White};
use irid::optics::{Stack, StackGrid};

fn main() {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: converged_colour STACK.toml");
        std::process::exit(2);
    };
    let stack = Stack::load(path.as_ref()).unwrap_or_else(|e| {
        eprintln!("converged_colour: {path}: {e}");
        std::process::exit(2);
    });
    let integ = SpectralIntegrator::with_white(Sampling::Exact, White::D65);
    let clock = std::time::Instant::now();
    let refinement = Refinement::new(&stack, Some(1), &integ).unwrap();
    println!(
        "criterion built in {:.1} ms",
        clock.elapsed().as_secs_f64() * 1e3
    );
    let grid = StackGrid::new(&stack, integ.wavelengths_nm()).unwrap();
    let w = integ.rgb_lane_weights();
    let mut thick = stack.thicknesses_nm();
    for &c in &[
        0.2, 0.05, 0.03, 0.02, 0.015, 0.012, 0.01, 0.007, 0.005, 0.003, 0.002, 0.001, 0.0005,
    ] {
        let mut worst = (0.0f64, 0.0, 1usize);
        let mut first_m = None;
        for k in 0..=400 {
            let d = 2.5 * k as f64;
            thick[0] = d;
            let base = grid.weighted_spectrum(&thick, c, &w);
            let m = refinement.sub_steps(d, c);
            if m > 1 && first_m.is_none() {
                first_m = Some(d);
            }
            let conv = refinement.weighted_spectrum(&grid, &w, &thick, c).unwrap();
            let diff = (0..3)
                .map(|i| (base.reflectance[i] - conv.reflectance[i]).abs())
                .fold(0.0, f64::max);
            if diff > worst.0 {
                worst = (diff, d, m);
            }
        }
        // convergence at the worst point: m vs 2m
        thick[0] = worst.1;
        let lvl = |m: usize| {
            let l = refinement.level(m).unwrap();
            l.grid.weighted_spectrum(&thick, c, &l.weights).reflectance
        };
        let m = worst.2;
        let (a, b) = (lvl(m), lvl((2 * m).min(64)));
        println!(
            "cos {c}: refined from d {:?}; largest move {:.2e} at d {} (m {}); m vs 2m {:.1e}",
            first_m,
            worst.0,
            worst.1,
            m,
            (0..3).map(|i| (a[i] - b[i]).abs()).fold(0.0, f64::max)
        );
    }
}
