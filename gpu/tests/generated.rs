//! The committed GLSL and HLSL shaders are what the generator makes from
//! the WGSL, and a real compiler (glslang: its GLSL front end for OpenGL
//! 4.5, Vulkan and ES 3.00, its HLSL front end for HLSL) accepts each with
//! a small entry point. Without glslangValidator the compile checks pass
//! with a note, unless IRID_REQUIRE_GPU=1 (CI installs glslang-tools).

use std::path::{Path, PathBuf};
use std::process::Command;

fn shaders() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders")
}

fn read(name: &str) -> String {
    std::fs::read_to_string(shaders().join(name)).unwrap()
}

/// The atlas mapping in the WGSL is the generator's (one source for every
/// library and language), for the atlas irid writes.
#[test]
fn the_wgsl_mapping_is_the_generated_one() {
    assert_eq!(irid_gpu::generate::MAX_CHARTS, irid::atlas::MAX_CHARTS);
    let wgsl = read("irid_film.wgsl");
    let lib = &irid_gpu::generate::FILM;
    assert_eq!(
        irid_gpu::generate::with_mapping(lib, &wgsl).unwrap(),
        wgsl,
        "shaders/irid_film.wgsl: run `cargo run -p irid-gpu --bin gen-shaders`"
    );
    assert!(wgsl.contains(&irid_gpu::generate::mapping_wgsl(lib)));
    assert!(wgsl.contains(&format!("array<vec4<f32>, {}>", irid::atlas::UNIFORM_VEC4)));
}

/// irid_film_rough's chart lookup is the same generated code, on the rough
/// uniform array, whose atlas part starts behind the tiling numbers.
#[test]
fn the_rough_wgsl_mapping_is_the_generated_one() {
    let wgsl = read("irid_film_rough.wgsl");
    let lib = &irid_gpu::generate::ROUGH;
    assert_eq!(
        irid_gpu::generate::with_mapping(lib, &wgsl).unwrap(),
        wgsl,
        "shaders/irid_film_rough.wgsl: run `cargo run -p irid-gpu --bin gen-shaders`"
    );
    let mapping = irid_gpu::generate::mapping_wgsl(lib);
    assert!(wgsl.contains(&mapping));
    // The same text as irid_film's but for its names and where its atlas
    // starts.
    let film = irid_gpu::generate::mapping_wgsl(&irid_gpu::generate::FILM)
        .replace("irid_film_", "irid_film_rough_")
        .replace("irid_params.v", "irid_rough_params.v");
    let base = irid::export::TILING_VEC4;
    assert_eq!(
        mapping,
        film.replace("[0]", &format!("[{base}]"))
            .replace("[0 + 1]", &format!("[{base} + 1]"))
            .replace("= 0 + 2 + 4 * k", &format!("= {base} + 2 + 4 * k"))
    );
    assert!(wgsl.contains(&format!("array<vec4<f32>, {}>", irid::export::ROUGH_VEC4)));
}

#[test]
fn committed_shaders_are_generated_from_the_wgsl() {
    let files = irid_gpu::generate::generate(&read("irid_film.wgsl")).unwrap();
    assert_eq!(files.len(), 3);
    for (name, text) in files {
        assert!(
            read(&name) == text,
            "shaders/{name} is out of date: run `cargo run -p irid-gpu --bin gen-shaders`"
        );
        assert!(text.contains("GENERATED from irid_film.wgsl"), "{name}");
        for interface in [
            "irid_film(",
            "irid_reflectance",
            "irid_transmittance",
            "irid_params",
            "IridFilm",
        ] {
            assert!(text.contains(interface), "{name} lacks {interface}");
        }
    }
    // The library ships exactly these files.
    for (name, text) in irid::export::SHADERS {
        assert_eq!(read(name), text, "{name}");
    }
}

/// glslangValidator, or None (with a note) when it is not installed and
/// IRID_REQUIRE_GPU is not 1.
fn glslang() -> Option<&'static str> {
    let found = Command::new("glslangValidator")
        .arg("--version")
        .output()
        .is_ok();
    if !found {
        let required = std::env::var("IRID_REQUIRE_GPU").is_ok_and(|v| v == "1");
        assert!(
            !required,
            "IRID_REQUIRE_GPU=1 but glslangValidator is missing (apt-get install glslang-tools)"
        );
        eprintln!("glslangValidator not found: compile checks skipped");
        return None;
    }
    Some("glslangValidator")
}

/// Compiles `source` (written to a file named `name`) with `args`.
fn compiles(tool: &str, name: &str, source: &str, args: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, source).unwrap();
    let out = Command::new(tool)
        .args(args)
        .arg(&path)
        .arg("-o")
        .arg(dir.path().join("out.spv"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{name} {args:?}: {}{}\n{source}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Checks GLSL ES 3.00 `source` as ES source (ES 3.00 has no SPIR-V target).
fn compiles_es(tool: &str, source: &str) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("film.frag");
    std::fs::write(&path, source).unwrap();
    let out = Command::new(tool).arg(&path).output().unwrap();
    assert!(
        out.status.success(),
        "{}\n{source}",
        String::from_utf8_lossy(&out.stdout)
    );
}

const GLSL_MAIN: &str = "void main() { IridFilm f = irid_film(250.0, 0.5, 1); \
                         irid_out = vec4(f.reflectance + f.transmittance, 1.0); }\n";

#[test]
fn glsl_compiles_for_opengl_vulkan_and_webgl2() {
    let Some(tool) = glslang() else { return };
    let desktop = format!(
        "#version 450\n{}layout(location = 0) out vec4 irid_out;\n{GLSL_MAIN}",
        read("irid_film.glsl")
    );
    compiles(tool, "film.frag", &desktop, &["-G"]); // OpenGL 4.5 SPIR-V
    compiles(tool, "film.frag", &desktop, &["-V"]); // Vulkan
    let es = format!(
        "#version 300 es\n{}out vec4 irid_out;\n{GLSL_MAIN}",
        read("irid_film_es.glsl")
    );
    compiles_es(tool, &es);
}

#[test]
fn hlsl_compiles() {
    let Some(tool) = glslang() else { return };
    let source = format!(
        "{}float4 main(float2 at : TEXCOORD0) : SV_Target0 {{\n    \
         IridFilm f = irid_film(at.x, at.y, int(at.x < 0.0));\n    \
         return float4(f.reflectance + f.transmittance, 1.0);\n}}\n",
        read("irid_film.hlsl")
    );
    compiles(
        tool,
        "film.hlsl",
        &source,
        &["-D", "-V", "-S", "frag", "-e", "main"],
    );
}

/// irid_film_rough's generated files are current, and each compiles with a
/// real compiler together with irid_film's (their bindings coexist).
#[test]
fn rough_shaders_are_generated_and_compile_beside_irid_film() {
    let files = irid_gpu::generate::generate_library(
        &irid_gpu::generate::ROUGH,
        &read("irid_film_rough.wgsl"),
    )
    .unwrap();
    assert_eq!(files.len(), 3);
    for (name, text) in files {
        assert!(
            read(&name) == text,
            "shaders/{name} is out of date: run `cargo run -p irid-gpu --bin gen-shaders`"
        );
        assert!(
            text.contains("GENERATED from irid_film_rough.wgsl"),
            "{name}"
        );
        for interface in ["irid_film_rough(", "irid_rough", "irid_rough_params"] {
            assert!(text.contains(interface), "{name} lacks {interface}");
        }
    }
    for (name, text) in irid::export::ROUGH_SHADERS {
        assert_eq!(read(name), text, "{name}");
    }
    let Some(tool) = glslang() else { return };
    let main = "void main() { IridFilm f = irid_film(250.0, 0.5, 0); \
                irid_out = vec4(f.reflectance + irid_film_rough(250.0, 0.5, 0.3), 1.0); }\n";
    let desktop = format!(
        "#version 450\n{}{}layout(location = 0) out vec4 irid_out;\n{main}",
        read("irid_film.glsl"),
        read("irid_film_rough.glsl")
    );
    compiles(tool, "rough.frag", &desktop, &["-V"]);
    let es = format!(
        "#version 300 es\n{}{}out vec4 irid_out;\n{main}",
        read("irid_film_es.glsl"),
        read("irid_film_rough_es.glsl")
    );
    compiles_es(tool, &es);
    let hlsl = format!(
        "{}{}float4 main(float2 at : TEXCOORD0) : SV_Target0 {{\n    \
         IridFilm f = irid_film(at.x, at.y, 0);\n    \
         return float4(f.reflectance + irid_film_rough(at.x, at.y, at.x - at.y), 1.0);\n}}\n",
        read("irid_film.hlsl"),
        read("irid_film_rough.hlsl")
    );
    compiles(
        tool,
        "rough.hlsl",
        &hlsl,
        &["-D", "-V", "-S", "frag", "-e", "main"],
    );
}
