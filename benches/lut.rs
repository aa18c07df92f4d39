//! Table speed: one sampler lookup (bilinear rgb, trilinear spectral), the
//! baker's cost per (node, wavelength), and a whole small bake.

// Not an API: criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use irid::color::Sampling;
use irid::lut::{bake, BakeSpec, Kind, Resolution};
use irid::optics::twoport::{Scratch, VaryingLayer};
use irid::optics::{Layer, Material, Stack};
use num_complex::Complex64 as C64;

fn soap() -> Stack {
    Stack {
        ambient: Material::constant(1.0, 0.0),
        layers: vec![Layer::new(Material::constant(1.33, 0.0), 500.0)],
        substrate: Material::constant(1.0, 0.0),
    }
}

fn spec(kind: Kind, nodes: (usize, usize, usize)) -> BakeSpec {
    let mut spec = BakeSpec::new(soap());
    spec.thickness_nm = (0.0, 1000.0);
    spec.kind = kind;
    spec.sampling = Sampling::Uniform(31);
    spec.validation_points = 0;
    spec.resolution = Resolution::Nodes {
        thickness: nodes.0,
        angle: nodes.1,
        wavelength: nodes.2,
    };
    spec
}

/// Pseudo-random lookups spread over the table (a fixed LCG: no I/O, no
/// allocation inside the timed loop).
fn points(n: usize) -> Vec<[f32; 3]> {
    let mut s = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..n)
        .map(|_| [next() * 1000.0, next(), 380.0 + 400.0 * next()])
        .collect()
}

fn sampler(c: &mut Criterion) {
    let pts = points(4096);
    let rgb = bake(&spec(Kind::Rgb, (453, 127, 1))).unwrap();
    let mut g = c.benchmark_group("lookup");
    g.throughput(Throughput::Elements(pts.len() as u64));
    g.bench_function("sample_rgb 453x127", |b| {
        b.iter(|| {
            let mut acc = 0.0f32;
            for p in &pts {
                let s = rgb.sample_rgb(black_box(p[0]), black_box(p[1]));
                acc += s.reflectance[1] + s.transmittance[2];
            }
            acc
        })
    });
    // A renderer's access pattern: neighbouring pixels, nearby thickness
    // and angle (a slow sweep across the table).
    let coherent: Vec<[f32; 2]> = (0..4096)
        .map(|i| [i as f32 * 0.2, 0.3 + i as f32 * 1e-4])
        .collect();
    g.bench_function("sample_rgb 453x127 coherent", |b| {
        b.iter(|| {
            let mut acc = 0.0f32;
            for p in &coherent {
                let s = rgb.sample_rgb(black_box(p[0]), black_box(p[1]));
                acc += s.reflectance[1] + s.transmittance[2];
            }
            acc
        })
    });
    let spectral = bake(&spec(Kind::Spectral, (201, 65, 41))).unwrap();
    g.bench_function("sample_spectral 201x65x41", |b| {
        b.iter(|| {
            let mut acc = 0.0f32;
            for p in &pts {
                let (r, t) = spectral.sample_spectral(black_box(p[0]), black_box(p[1]), p[2]);
                acc += r + t;
            }
            acc
        })
    });
    g.finish();
}

fn baker(c: &mut Criterion) {
    // The hot loop: one (wavelength, angle), 1000 thickness nodes, phase
    // advanced by a complex multiplication (re-synchronized every 16).
    let n = [C64::new(1.0, 0.0), C64::new(1.33, 0.0), C64::new(1.0, 0.0)];
    let mut scratch = Scratch::default();
    let v = VaryingLayer::new(&n, &[0.0], 1, 550.0, 0.7, &mut scratch);
    let mut g = c.benchmark_group("bake");
    g.throughput(Throughput::Elements(1000));
    g.bench_function("node response x1000", |b| {
        b.iter(|| {
            let delta = v.phase(1.0);
            let mut phase = C64::new(1.0, 0.0);
            let mut acc = 0.0;
            for j in 0..1000 {
                if j % 16 == 0 {
                    phase = v.phase(j as f64);
                }
                let r = v.response(phase);
                acc += r.r() + r.t();
                phase *= delta;
            }
            acc
        })
    });
    g.throughput(Throughput::Elements(1));
    g.bench_function("split one (wavelength, angle)", |b| {
        b.iter(|| VaryingLayer::new(black_box(&n), &[0.0], 1, 550.0, 0.7, &mut scratch))
    });
    let small = spec(Kind::Rgb, (101, 33, 1));
    g.sample_size(10);
    g.bench_function("bake rgb 101x33, 31 wavelengths (checked on 201x65)", |b| {
        b.iter(|| bake(black_box(&small)).unwrap())
    });
    g.finish();
}

criterion_group!(benches, sampler, baker);
criterion_main!(benches);
