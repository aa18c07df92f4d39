//! The single-film analytic model renderers ship (Belcour & Barla 2017, and
//! the glTF reference variant): one shading evaluation to linear sRGB.

// Not an API: criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use irid::analytic::{AnalyticFilm, Variant};
use num_complex::Complex64 as C64;

fn analytic(c: &mut Criterion) {
    let soap = AnalyticFilm::new(1.0, 1.33, C64::new(1.0, 0.0));
    // A conductor with a different index per channel: no sharing between channels.
    let on_gold = AnalyticFilm {
        outside_ior: 1.0,
        film_ior: 1.5,
        base_ior: [C64::new(0.16, 3.6), C64::new(0.6, 2.1), C64::new(1.2, 1.8)],
    };
    for (name, film) in [("soap", soap), ("on gold", on_gold)] {
        for variant in [Variant::BelcourBarla, Variant::Gltf] {
            c.bench_function(&format!("{} {name}", variant.label()), |b| {
                b.iter(|| film.reflectance_rgb(variant, black_box(420.0), black_box(0.8)))
            });
        }
    }
}

criterion_group!(benches, analytic);
criterion_main!(benches);
