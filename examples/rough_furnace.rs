//! The white furnace of irid's renderer on rough spheres (docs/rough.md,
//! "Multiple scattering"): a sphere under a uniform white sky, the mean
//! radiance over the pixels it covers. A lossless surface returns 1; what
//! is missing is what the single-scattering lobe loses.
//!
//! Each sphere is rendered twice: single scattering (the compensation
//! taken off its material) and with the renderer's multiple-scattering
//! compensation.
//!
//! `cargo run --release --example rough_furnace [-- SPP SIZE DEPTH]`

use std::path::Path;

#[path = "../tests/common/furnace.rs"]
mod furnace;

use furnace::{single_scattering, Furnace};

/// The materials measured: a soap-like film on glass, bare glass (a layer
/// matched to its substrate), and a lossless film on silver.
const MATERIALS: [(&str, &str); 3] = [
    (
        "film on glass",
        "substrate = { n = 1.5 }, layers = [{ n = 1.33, thickness_nm = 500.0 }]",
    ),
    (
        "bare glass",
        "substrate = { n = 1.5 }, layers = [{ n = 1.5, thickness_nm = 100.0 }]",
    ),
    (
        "film on silver",
        "substrate = { material = \"silver\" }, layers = [{ n = 1.5, thickness_nm = 300.0 }]",
    ),
];

fn main() {
    let args: Vec<u32> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("SPP SIZE DEPTH: whole numbers"))
        .collect();
    let (spp, size, depth) = (
        *args.first().unwrap_or(&16),
        *args.get(1).unwrap_or(&48),
        *args.get(2).unwrap_or(&8),
    );
    let cache = Path::new("target/tmp/rough-furnace-cache");
    let furnace = Furnace { size, spp, depth };
    println!(
        "white furnace, {size}×{size} pixels, {spp} spp, depth {depth}: mean R G B over the sphere"
    );
    for (name, material) in MATERIALS {
        for roughness in [0.0f32, 0.2, 0.4, 0.6, 0.8, 1.0] {
            for compensated in [false, true] {
                let mut scene = furnace.sphere(Some(material), roughness);
                if !compensated {
                    scene = single_scattering(scene);
                }
                let mean = furnace.mean(&scene, cache);
                let which = if compensated { "compensated" } else { "single" };
                println!(
                    "{name:15} roughness {roughness:.1} {which:11}: {:.4} {:.4} {:.4}",
                    mean[0], mean[1], mean[2]
                );
            }
        }
    }
}
