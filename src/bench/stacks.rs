//! The fixed stacks every benchmark run measures, chosen to cover what the
//! methods differ on: one lossless film (where the analytic model is at its
//! best), an absorbing film and a gain film (which it cannot represent), a
//! two-layer stack, and a 10-layer mirror seen from both sides.

use crate::optics::{Layer, Material, Stack};

#[derive(Clone, Debug)]
pub struct BenchStack {
    /// Short name used on the command line and in reports.
    pub name: &'static str,
    pub description: &'static str,
    pub stack: Stack,
    /// Index (from the top, 0-based) of the layer whose thickness varies.
    pub varying_layer: usize,
    pub thickness_range_nm: (f64, f64),
}

fn layer(material: Material, thickness_nm: f64) -> Layer {
    Layer {
        material,
        thickness_nm,
    }
}

fn named(name: &str, n: f64, k: f64) -> Material {
    Material {
        name: name.to_string(),
        ..Material::constant(n, k)
    }
}

/// A quarter-wave TiO2/SiO2 Bragg mirror centred on 550 nm, 10 layers.
fn mirror() -> Stack {
    let (n_hi, n_lo) = (2.40, 1.46);
    let layers = (0..10)
        .map(|i| {
            if i % 2 == 0 {
                layer(named("TiO2", n_hi, 0.0), 550.0 / (4.0 * n_hi))
            } else {
                layer(named("SiO2", n_lo, 0.0), 550.0 / (4.0 * n_lo))
            }
        })
        .collect();
    Stack {
        ambient: named("air", 1.0, 0.0),
        layers,
        substrate: named("glass", 1.52, 0.0),
    }
}

pub fn fixed_stacks() -> Vec<BenchStack> {
    let air = || named("air", 1.0, 0.0);
    let single = |film: Material, substrate: Material| Stack {
        ambient: air(),
        layers: vec![layer(film, 500.0)],
        substrate,
    };
    let mirror_front = mirror();
    let mirror_back = mirror_front.reversed();
    vec![
        BenchStack {
            name: "soap",
            description: "soap film n=1.33 in air, 0-1000 nm",
            stack: single(named("soap", 1.33, 0.0), air()),
            varying_layer: 0,
            thickness_range_nm: (0.0, 1000.0),
        },
        BenchStack {
            name: "absorbing",
            description: "absorbing film n=1.5+0.15i in air, 0-1000 nm",
            stack: single(named("absorber", 1.5, 0.15), air()),
            varying_layer: 0,
            thickness_range_nm: (0.0, 1000.0),
        },
        BenchStack {
            name: "two-layer",
            description: "TiO2 (n=2.4, 0-500 nm) over MgF2 (n=1.38, 100 nm) on glass",
            stack: Stack {
                ambient: air(),
                layers: vec![
                    layer(named("TiO2", 2.4, 0.0), 250.0),
                    layer(named("MgF2", 1.38, 0.0), 100.0),
                ],
                substrate: named("glass", 1.52, 0.0),
            },
            varying_layer: 0,
            thickness_range_nm: (0.0, 500.0),
        },
        BenchStack {
            name: "mirror-front",
            description:
                "10-layer TiO2/SiO2 quarter-wave mirror on glass, from air; top layer 0-200 nm",
            stack: mirror_front,
            varying_layer: 0,
            thickness_range_nm: (0.0, 200.0),
        },
        BenchStack {
            name: "mirror-back",
            description: "the same mirror seen from inside the glass; first layer 0-200 nm",
            stack: mirror_back,
            varying_layer: 0,
            thickness_range_nm: (0.0, 200.0),
        },
    ]
}

pub fn names() -> Vec<&'static str> {
    fixed_stacks().iter().map(|s| s.name).collect()
}

pub fn find(name: &str) -> Option<BenchStack> {
    fixed_stacks()
        .into_iter()
        .find(|s| s.name.eq_ignore_ascii_case(name))
}
