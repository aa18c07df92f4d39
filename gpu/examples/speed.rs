//! irid_film against the Belcour–Barla model (glTF reference, WGSL) in the
//! same compute pipeline on the same device: the ratio docs/gpu.md reports.
//!
//!     cargo run --release -p irid-gpu --example speed
//!
//! Both run at the same 65 536 points, 64 calls per point (each at a moved
//! thickness, so no call is hoisted), alternating, 7 times each; the medians
//! are compared. The ratio holds for the device it ran on (docs/gpu.md says
//! which): a software driver such as lavapipe filters textures in code, so
//! on GPU hardware, where filtering is fixed-function, the ratio differs.

#[path = "../tests/analytic.rs"]
#[allow(dead_code, unused_imports)]
mod analytic;
// analytic.rs loads the harness for itself too; each copy is private.
#[path = "../tests/harness/mod.rs"]
#[allow(clippy::duplicate_mod)]
mod harness;

use harness::{bind_export, gpu, program, run, wgsl_program};
use irid::export::{export, ExportSpec};
use irid::optics::Stack;

fn main() {
    let gpu = gpu().expect("a Vulkan adapter");
    println!(
        "adapter: {} ({:?}, {})",
        gpu.info.name, gpu.info.backend, gpu.info.driver_info
    );
    let stack = Stack::from_toml_str(
        "ambient = { n = 1.0 }\nsubstrate = { n = 1.5 }\n[[layers]]\nn = 1.33\nthickness_nm = 300.0\n",
        std::path::Path::new("."),
        "speed",
    )
    .unwrap();
    let mut spec = ExportSpec::new(stack);
    spec.thickness_nm = (0.0, 1000.0);
    let e = export(&spec, &|_| {}).unwrap();
    let bytes = 2 * e.atlas.width * e.atlas.height * 8;
    let front = e.side(irid::export::Side::Front).unwrap();
    println!(
        "export: atlas {}×{} texels ({} charts), two RGBA16F textures = {} KiB, front max error {:.2e}",
        e.atlas.width,
        e.atlas.height,
        e.atlas.charts.len(),
        bytes / 1024,
        front.error.max_all()
    );
    let irid_src = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders/irid_film.wgsl"),
    )
    .unwrap();
    let bound = bind_export(&gpu, &e);
    let irid = program(&gpu, &bound.layout, wgsl_program(&irid_src, "irid_film"));
    let bb = program(
        &gpu,
        &bound.layout,
        wgsl_program(&analytic::analytic_library(), "bb_film"),
    );
    let points: Vec<[f32; 2]> = (0..65_536)
        .map(|k| {
            let a = (k as f32 * 0.618_034).fract();
            let b = (k as f32 * 0.754_877_7).fract();
            [900.0 * a, 0.02 + 0.98 * b]
        })
        .collect();
    const REPEAT: u32 = 64;
    // Warm-up (pipeline compilation in the driver).
    run(&gpu, &irid, &bound, &points[..64], 1, 0);
    run(&gpu, &bb, &bound, &points[..64], 1, 0);
    let (mut t_irid, mut t_bb) = (Vec::new(), Vec::new());
    for _ in 0..7 {
        t_irid.push(run(&gpu, &irid, &bound, &points, REPEAT, 0).1.as_secs_f64());
        t_bb.push(run(&gpu, &bb, &bound, &points, REPEAT, 0).1.as_secs_f64());
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (a, b) = (median(&mut t_irid), median(&mut t_bb));
    let calls = points.len() as f64 * f64::from(REPEAT);
    println!(
        "irid_film: {:.1} ns/call; Belcour–Barla (glTF): {:.1} ns/call; ratio {:.2} (analytic / irid_film), medians of 7",
        a / calls * 1e9,
        b / calls * 1e9,
        b / a
    );
}
