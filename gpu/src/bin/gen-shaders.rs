//! Writes the atlas mapping (gpu/src/generate.rs) into shaders/irid_film.wgsl,
//! then shaders/irid_film.glsl, irid_film_es.glsl and irid_film.hlsl from
//! it, and likewise irid_film_rough.* from
//! shaders/irid_film_rough.wgsl (run from the repository root, or anywhere in it:
//! the paths are the crate's):
//!
//!     cargo run -p irid-gpu --bin gen-shaders
//!
//! With `--check`, writes nothing and exits 1 when a committed file differs.

use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    let check = std::env::args().any(|a| a == "--check");
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
    let mut files = Vec::new();
    for lib in [&irid_gpu::generate::FILM, &irid_gpu::generate::ROUGH] {
        let source = dir.join(format!("{}.wgsl", lib.stem));
        let wgsl = match std::fs::read_to_string(&source) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("gen-shaders: {}: {e}", source.display());
                return ExitCode::from(2);
            }
        };
        // The atlas mapping comes from the generator, into the WGSL too.
        let wgsl = if wgsl.contains(irid_gpu::generate::MAPPING_BEGIN) {
            match irid_gpu::generate::with_mapping(lib, &wgsl) {
                Ok(w) => w,
                Err(e) => {
                    eprintln!("gen-shaders: {e}");
                    return ExitCode::from(2);
                }
            }
        } else {
            wgsl
        };
        files.push((format!("{}.wgsl", lib.stem), wgsl.clone()));
        match irid_gpu::generate::generate_library(lib, &wgsl) {
            Ok(f) => files.extend(f),
            Err(e) => {
                eprintln!("gen-shaders: {e}");
                return ExitCode::from(2);
            }
        }
    }
    let mut stale = false;
    for (name, text) in files {
        let path = dir.join(&name);
        let current = std::fs::read_to_string(&path).unwrap_or_default();
        if current == text {
            continue;
        }
        if check {
            eprintln!("gen-shaders: {} is out of date", path.display());
            stale = true;
        } else if let Err(e) = std::fs::write(&path, &text) {
            eprintln!("gen-shaders: {}: {e}", path.display());
            return ExitCode::from(2);
        } else {
            println!("wrote {}", path.display());
        }
    }
    if stale {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    }
}
