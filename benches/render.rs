//! Render speed on the paper's timing scene (`two-layer-noise`, 500 x 500,
//! 1 sample per pixel): LUT film shading, the paper's direct method at 41
//! wavelengths, and the same scene with the film replaced by bare glass
//! (the cost of iridescence). Tables are baked once before timing.

use criterion::{criterion_group, criterion_main, Criterion};
use irid::color::Sampling;
use irid::render::{self, FilmMode, RenderOptions, Scene};

fn bench(c: &mut Criterion) {
    let scene = Scene::builtin("two-layer-noise").unwrap().unwrap();
    let cache = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("render-bench-cache");
    let lut = RenderOptions::new(FilmMode::lut(&cache));
    let lut_films = render::prepare_films(&scene, &lut.film).unwrap();
    let plain = scene.without_films(|_| unreachable!("two-layer-noise coats glass"));
    let plain_films = render::prepare_films(&plain, &lut.film).unwrap();
    let direct = RenderOptions::new(FilmMode::Direct {
        sampling: Sampling::Uniform(41),
    });
    let direct_films = render::prepare_films(&scene, &direct.film).unwrap();

    let mut g = c.benchmark_group("two-layer-noise 500x500 1spp");
    g.sample_size(10);
    g.bench_function("lut", |b| {
        b.iter(|| render::render_with(&scene, &lut_films, &lut))
    });
    g.bench_function("plain glass (no film)", |b| {
        b.iter(|| render::render_with(&plain, &plain_films, &lut))
    });
    g.bench_function("direct uniform:41", |b| {
        b.iter(|| render::render_with(&scene, &direct_films, &direct))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
