//! What film shading adds to a LUT render of the paper's timing scene
//! (`two-layer-noise`, 500 x 500, 1 sample per pixel), measured as paired
//! ratios: each round renders the scene with thickness grids, with the
//! noise evaluated at every hit, with the film at one thickness, and with
//! bare glass, back to back, so every ratio compares renders that saw the
//! same machine load (the order rotates from round to round). Prints the
//! median and quartiles of the per-round ratios against bare glass, and
//! each variant's best and median time.
//!
//! `cargo bench --bench film_cost [-- ROUNDS [THREADS] [handoff]]`
//! (default 40 rounds on 2 threads). A plain program, not criterion:
//! criterion times each variant in its own block of samples, so a change
//! of load between blocks moves the ratio.
//!
//! The rounds run inside the thread pool, as `irid render --threads N` and
//! the demo run their renders. `handoff` instead calls each render from
//! the main thread, outside the pool, as a library caller might.
//!
//! Why it matters: a render called from outside a pool is handed to the
//! workers while the caller sleeps. On one thread, on a 2-vCPU VM, that
//! made renders bimodal: when the sleeping caller and the worker sat on
//! different CPUs, the worker ran 5–15 % slower (`-- 40 1 handoff` gave
//! +17.2 % for the grid against +10.5 % inside the pool, with bare glass's
//! median at 69.8 ms against 64.6). It was not migrations: there were two
//! or three in a whole run. Pinning both threads to one CPU removed it,
//! pinning them to different CPUs brought it back; its cause is below what
//! the guest can see. So a render called from outside a one-worker pool
//! runs on the calling thread (`render_tiles`), and `handoff` on one
//! thread measures that (see docs/performance.md).

mod common;

use common::TimingScene;
use irid::render::{self, FilmMode, RenderOptions};
use std::time::Instant;

fn main() {
    // `cargo bench` passes "--bench"; numbers are ours.
    let numbers: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let rounds = numbers.first().copied().unwrap_or(40).max(1);
    let threads = numbers.get(1).copied().unwrap_or(2).max(1);
    let handoff = std::env::args().any(|a| a == "handoff");
    if handoff {
        // The pool a call from outside any pool hands its work to.
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global()
            .expect("thread pool");
    }

    let timing = TimingScene::load();
    let (cache, scene, uniform, plain) =
        (&timing.cache, &timing.scene, &timing.uniform, &timing.plain);
    let opts = RenderOptions::new(FilmMode::lut(cache));
    let grid = render::prepare_films(scene, &opts.film).unwrap();
    let exact = render::prepare_films(scene, &FilmMode::lut_exact_noise(cache)).unwrap();
    let uniform_films = render::prepare_films(uniform, &opts.film).unwrap();
    let plain_films = render::prepare_films(plain, &opts.film).unwrap();

    let variants = [
        ("LUT, thickness grid", scene, &grid),
        ("LUT, noise at every hit", scene, &exact),
        ("LUT, one thickness", uniform, &uniform_films),
        ("bare glass", plain, &plain_films),
    ];
    let mut times = vec![Vec::with_capacity(rounds); variants.len()];
    let mut run_rounds = || {
        for round in 0..rounds {
            // Each round starts with another variant, so that none always runs
            // first or after the same neighbour.
            for i in 0..variants.len() {
                let k = (round + i) % variants.len();
                let (_, s, f) = variants[k];
                let start = Instant::now();
                std::hint::black_box(render::render_with(s, f, &opts));
                times[k].push(start.elapsed().as_secs_f64() * 1e3);
            }
        }
    };
    if handoff {
        run_rounds();
    } else {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool")
            .install(run_rounds);
    }
    let plain_k = variants.len() - 1;
    let calls = if handoff {
        "each render called from outside the pool"
    } else {
        "rounds run inside the pool"
    };
    println!("two-layer-noise 500x500 1spp, {threads} thread(s), {rounds} rounds, {calls}");
    for (k, (name, _, _)) in variants.iter().enumerate() {
        let mut sorted = times[k].clone();
        sorted.sort_by(f64::total_cmp);
        let (best, median) = (sorted[0], quantile(&sorted, 0.5));
        print!("  {name:<26} best {best:6.1} ms, median {median:6.1} ms");
        if k == plain_k {
            println!();
            continue;
        }
        let mut ratios: Vec<f64> = (0..rounds)
            .map(|r| 100.0 * (times[k][r] / times[plain_k][r] - 1.0))
            .collect();
        ratios.sort_by(f64::total_cmp);
        println!(
            "   adds {:+.1} % to bare glass (median of paired rounds; quartiles {:+.1} .. {:+.1} %)",
            quantile(&ratios, 0.5),
            quantile(&ratios, 0.25),
            quantile(&ratios, 0.75)
        );
    }
}

/// The element at fraction `f` of a sorted, non-empty slice (nearest rank).
fn quantile(sorted: &[f64], f: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * f).round() as usize]
}
