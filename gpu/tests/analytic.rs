//! The WGSL Belcour–Barla (glTF reference) model used for the speed
//! comparison in docs/gpu.md computes what irid's CPU version does: a
//! faithful port, so the comparison times the real model.

mod harness;

use harness::{bind_export, gpu, program, run, wgsl_program};
use irid::analytic::{AnalyticFilm, Variant};
use irid::export::{export, ExportSpec};
use irid::optics::Stack;

/// irid_film.wgsl (for IridFilm and the bindings), the analytic model and
/// a wrapper with irid_film's signature.
pub fn analytic_library() -> String {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let irid = std::fs::read_to_string(dir.join("../shaders/irid_film.wgsl")).unwrap();
    let bb = std::fs::read_to_string(dir.join("shaders/belcour_barla_gltf.wgsl")).unwrap();
    format!(
        "{irid}\n{bb}\n\
         fn bb_film(thickness_nm: f32, cos_theta: f32, side: i32) -> IridFilm {{\n\
             let film = BbFilm(1.0, 1.33, vec3<f32>(0.04));\n\
             return IridFilm(belcour_barla_gltf(film, thickness_nm, cos_theta), vec3<f32>(0.0));\n\
         }}\n"
    )
}

#[test]
fn wgsl_belcour_barla_matches_the_cpu_model() {
    let Some(gpu) = gpu() else { return };
    // Any export: the analytic shader ignores the textures, but the
    // pipeline binds them as irid_film's would be.
    let stack = Stack::from_toml_str(
        "ambient = { n = 1.0 }\nsubstrate = { n = 1.5 }\n[[layers]]\nn = 1.33\nthickness_nm = 300.0\n",
        std::path::Path::new("."),
        "test",
    )
    .unwrap();
    let mut spec = ExportSpec::new(stack);
    spec.thickness_nm = (0.0, 1000.0);
    spec.points = 100;
    let e = export(&spec, &|_| {}).unwrap();
    let bound = bind_export(&gpu, &e);
    let program = program(
        &gpu,
        &bound.layout,
        wgsl_program(&analytic_library(), "bb_film"),
    );
    let points: Vec<[f32; 2]> = (0..10_000)
        .map(|k| {
            let a = (k as f32 * 0.618_034).fract();
            let b = (k as f32 * 0.754_877_7).fract();
            [1000.0 * a, 0.02 + 0.98 * b]
        })
        .collect();
    let (got, _) = run(&gpu, &program, &bound, &points, 1, 0);
    let film = AnalyticFilm::from_base_f0(1.0, 1.33, [0.04; 3]);
    let mut worst = 0.0f64;
    for (p, g) in points.iter().zip(&got) {
        let want = film.reflectance_rgb(Variant::Gltf, f64::from(p[0]), f64::from(p[1]));
        for k in 0..3 {
            worst = worst.max((f64::from(g[k]) - want[k]).abs());
        }
    }
    eprintln!(
        "WGSL glTF model vs CPU: max |difference| {worst:.2e} over {} points",
        points.len()
    );
    assert!(worst < 2e-4, "{worst}");
}
