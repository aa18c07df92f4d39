//! Render speed on the paper's timing scene (`two-layer-noise`, 500 x 500,
//! 1 sample per pixel): LUT film shading, the paper's direct method at 41
//! wavelengths, and the same scene with the film replaced by bare glass
//! (the cost of iridescence). Tables and thickness grids are baked once
//! before timing. Then the parts of a LUT film hit on their own: the
//! thickness (noise evaluated, or read from the grid) and the table lookup.

// Not an API: criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

mod common;

use common::TimingScene;
use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;
use irid::color::Sampling;
use irid::render::material::Material;
use irid::render::scene::Shape;
use irid::render::thickness::{Perlin, ThicknessGrid};
use irid::render::{self, FilmMode, FilmShading, LutFilm, RenderOptions, Side};

fn bench(c: &mut Criterion) {
    let timing = TimingScene::load();
    let (cache, scene, uniform, plain) =
        (&timing.cache, &timing.scene, &timing.uniform, &timing.plain);
    let lut = RenderOptions::new(FilmMode::lut(cache));
    let lut_films = render::prepare_films(scene, &lut.film).unwrap();
    let plain_films = render::prepare_films(plain, &lut.film).unwrap();
    let direct = RenderOptions::new(FilmMode::Direct {
        sampling: Sampling::Uniform(41),
    });
    let direct_films = render::prepare_films(scene, &direct.film).unwrap();
    let uniform_films = render::prepare_films(uniform, &lut.film).unwrap();
    // The noise film with its field evaluated at every hit, as before
    // thickness grids (and as direct mode does).
    let exact_noise_films =
        render::prepare_films(scene, &FilmMode::lut_exact_noise(cache)).unwrap();

    // Renders are timed inside the pool, as `irid render` runs them (see
    // `benches/film_cost.rs` on renders handed to the pool from outside).
    let pool = rayon::ThreadPoolBuilder::new().build().unwrap();
    let mut g = c.benchmark_group("two-layer-noise 500x500 1spp");
    g.sample_size(10);
    g.bench_function("lut", |b| {
        pool.install(|| b.iter(|| render::render_with(scene, &lut_films, &lut)))
    });
    g.bench_function("lut, noise evaluated at every hit", |b| {
        pool.install(|| b.iter(|| render::render_with(scene, &exact_noise_films, &lut)))
    });
    g.bench_function("lut, uniform 350 nm film", |b| {
        pool.install(|| b.iter(|| render::render_with(uniform, &uniform_films, &lut)))
    });
    g.bench_function("plain glass (no film)", |b| {
        pool.install(|| b.iter(|| render::render_with(plain, &plain_films, &lut)))
    });
    g.bench_function("direct uniform:41", |b| {
        pool.install(|| b.iter(|| render::render_with(scene, &direct_films, &direct)))
    });
    g.finish();
}

/// The two parts of a film hit in LUT mode: the thickness noise and the
/// table lookup (front side: evenly spaced axes; back side: cos θ crowded
/// around the critical angle), at pseudo-random points.
fn film_hit(c: &mut Criterion) {
    let TimingScene { cache, scene, .. } = TimingScene::load();
    let (lut, _, _) = LutFilm::prepare(&scene.films[0], &cache).unwrap();
    let Material::Film(film) = scene
        .materials
        .iter()
        .find(|m| matches!(m, Material::Film(_)))
        .unwrap()
    else {
        unreachable!()
    };
    // Additive recurrences with irrational steps: spread, repeatable points.
    let spread = |k: usize, step: f64| (k as f64 * step).fract() as f32;
    let points: Vec<(Vec3, f32, f32)> = (0..4096)
        .map(|k| {
            let p = Vec3::new(
                2.0 * spread(k, 0.754_877_666) - 1.0,
                2.0 * spread(k, 0.569_840_291),
                2.0 * spread(k, 0.618_033_989) - 1.0,
            );
            (
                p,
                100.0 + 500.0 * spread(k, 0.414_213_562),
                spread(k, 0.732_050_808),
            )
        })
        .collect();
    let mut g = c.benchmark_group("film hit");
    g.throughput(Throughput::Elements(points.len() as u64));
    g.bench_function("thickness noise", |b| {
        b.iter(|| {
            points
                .iter()
                .map(|(p, _, _)| film.thickness.at(black_box(*p)))
                .sum::<f32>()
        })
    });
    // The noise alone, through its AVX2 copy and through the portable code
    // (what the unsafe AVX2 function gains).
    let perlin = Perlin::new(7);
    let portable = Perlin::new(7).portable();
    for (name, noise) in [("noise, avx2", &perlin), ("noise, portable", &portable)] {
        g.bench_function(name, |b| {
            b.iter(|| {
                points
                    .iter()
                    .map(|(p, _, _)| noise.signed(black_box(*p * 4.0)))
                    .sum::<f32>()
            })
        });
    }
    let sphere = scene
        .objects
        .iter()
        .find(|o| matches!(o.shape, Shape::Sphere(_)))
        .unwrap();
    let grid = ThicknessGrid::bake(&film.thickness, &sphere.shape).unwrap();
    g.bench_function("thickness grid", |b| {
        b.iter(|| {
            points
                .iter()
                .map(|(p, _, _)| grid.at(black_box(*p)))
                .sum::<f32>()
        })
    });
    for (name, side) in [("lut front", Side::Front), ("lut back", Side::Back)] {
        g.bench_function(name, |b| {
            b.iter(|| {
                points
                    .iter()
                    .map(|&(_, d, cos)| {
                        lut.shade(black_box(d), black_box(cos), side).reflectance[1]
                    })
                    .sum::<f32>()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench, film_hit);
criterion_main!(benches);
