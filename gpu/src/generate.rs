//! The GLSL 4.50, GLSL ES 3.00 and HLSL forms of `shaders/irid_film.wgsl`
//! and `shaders/irid_film_rough.wgsl`, generated with naga's back ends and
//! tidied into include-able code with the interface names of docs/gpu.md.
//!
//! naga writes whole shaders: its GLSL back end needs an entry point, names
//! resources after their bindings (`_group_0_binding_0_fs`), and its HLSL
//! back end reads samplers from a heap. The generator therefore compiles the
//! WGSL with a small fragment entry point that calls the library's function,
//! then drops that entry point and its inputs and outputs, gives every
//! resource its WGSL name, and declares the HLSL sampler directly. Each step
//! checks that it found what it replaces, so a change in naga's output stops
//! the generator instead of producing a wrong file.

use std::fmt::Write as _;

use naga::back::{glsl, hlsl};

/// What differs between the shader libraries the generator handles.
pub struct Library {
    /// The WGSL file's stem: `irid_film`; also the prefix of its mapping's
    /// functions.
    pub stem: &'static str,
    /// The uniform array its mapping reads (`irid_params.v`).
    uniform: &'static str,
    /// The vec4 of that array the atlas header starts at.
    atlas_base: usize,
    /// The entry point's body, from `at: vec2<f32>` to a `vec4<f32>`.
    entry_body: &'static str,
    /// naga's GLSL names of the textures and the uniform block, and theirs.
    glsl_names: &'static [(&'static str, &'static str)],
    /// GLSL 4.50 bindings of the textures and the uniform block.
    desktop_bindings: &'static [u32],
    /// What a host binds where, for the GLSL 4.50 and ES 3.00 headers.
    glsl_notes: [&'static str; 2],
    /// WGSL binding → HLSL register (textures t, the sampler s, the block b).
    hlsl_registers: &'static [(u32, u32)],
    /// The sampler's name and its HLSL register.
    sampler: (&'static str, u32),
    /// What a host binds where, for the HLSL header.
    hlsl_note: &'static str,
}

/// `irid_film` (shaders/irid_film.wgsl).
pub const FILM: Library = Library {
    stem: "irid_film",
    uniform: "irid_params.v",
    atlas_base: 0,
    entry_body: "let film = irid_film(at.x, at.y, select(0, 1, at.x < 0.0));\n    \
                 return vec4<f32>(film.reflectance + film.transmittance, 1.0);",
    glsl_names: &[
        ("_group_0_binding_0_fs", "irid_reflectance"),
        ("_group_0_binding_1_fs", "irid_transmittance"),
        ("_group_0_binding_3_fs", "irid_params"),
        ("IridParams_block_0Fragment", "IridParamsBlock"),
    ],
    desktop_bindings: &[0, 1, 3],
    glsl_notes: [
        "// Prepend `#version 450` (or `#version 450 core`). Textures are combined samplers\n\
         // (bilinear, clamp to edge, no mipmaps): irid_reflectance at binding 0,\n\
         // irid_transmittance at 1; the IridParamsBlock uniform block at binding 3.\n",
        "// Prepend `#version 300 es`. Textures are combined samplers (bilinear, clamp to\n\
         // edge, no mipmaps): bind with gl.uniform1i; the IridParamsBlock uniform block\n\
         // with gl.uniformBlockBinding.\n",
    ],
    hlsl_registers: &[(0, 0), (1, 1), (2, 0), (3, 0)],
    sampler: ("irid_sampler", 0),
    hlsl_note: "// Textures at t0 and t1, the sampler (bilinear, clamp to edge) at s0, the\n\
                // parameters in cbuffer irid_params at b0.\n\n",
};

/// `irid_film_rough` (shaders/irid_film_rough.wgsl): bindings beside
/// irid_film's, so a shader can hold both.
pub const ROUGH: Library = Library {
    stem: "irid_film_rough",
    uniform: "irid_rough_params.v",
    atlas_base: 2,
    entry_body: "return vec4<f32>(irid_film_rough(at.x, at.y, at.x - at.y), 1.0);",
    glsl_names: &[
        ("_group_0_binding_4_fs", "irid_rough"),
        ("_group_0_binding_6_fs", "irid_rough_params"),
        ("IridRoughParams_block_0Fragment", "IridRoughParamsBlock"),
    ],
    desktop_bindings: &[4, 6],
    glsl_notes: [
        "// Prepend `#version 450` (or `#version 450 core`). irid_rough is a combined sampler\n\
         // (bilinear, clamp to edge, no mipmaps) at binding 4; the IridRoughParamsBlock\n\
         // uniform block at binding 6.\n",
        "// Prepend `#version 300 es`. irid_rough is a combined sampler (bilinear, clamp to\n\
         // edge, no mipmaps): bind with gl.uniform1i; the IridRoughParamsBlock uniform\n\
         // block with gl.uniformBlockBinding.\n",
    ],
    hlsl_registers: &[(4, 2), (5, 1), (6, 1)],
    sampler: ("irid_rough_sampler", 1),
    hlsl_note: "// The texture at t2, the sampler (bilinear, clamp to edge) at s1, the\n\
                // parameters in cbuffer irid_rough_params at b1 (beside irid_film's).\n\n",
};

/// The generated files of `irid_film`, name and text, in the order
/// docs/gpu.md lists them.
pub fn generate(wgsl: &str) -> Result<Vec<(String, String)>, String> {
    generate_library(&FILM, wgsl)
}

/// The generated files of `library` from its WGSL.
pub fn generate_library(lib: &Library, wgsl: &str) -> Result<Vec<(String, String)>, String> {
    let module = with_entry(lib, wgsl)?;
    let stem = lib.stem;
    Ok(vec![
        (
            format!("{stem}.glsl"),
            glsl_form(
                lib,
                &module,
                glsl::Version::Desktop(450),
                "GLSL 4.50 (OpenGL 4.5, Vulkan)",
            )?,
        ),
        (
            format!("{stem}_es.glsl"),
            glsl_form(
                lib,
                &module,
                glsl::Version::Embedded {
                    version: 300,
                    is_webgl: true,
                },
                "GLSL ES 3.00 (WebGL2)",
            )?,
        ),
        (format!("{stem}.hlsl"), hlsl_form(lib, &module)?),
    ])
}

/// The entry point the generator compiles with (and removes again).
const ENTRY: &str = "irid_generated_entry";

struct Module {
    module: naga::Module,
    info: naga::valid::ModuleInfo,
}

fn with_entry(lib: &Library, wgsl: &str) -> Result<Module, String> {
    let source = format!(
        "{wgsl}\n@fragment\nfn {ENTRY}(@location(0) at: vec2<f32>) -> @location(0) vec4<f32> {{\n    {}\n}}\n",
        lib.entry_body
    );
    let module = naga::front::wgsl::parse_str(&source).map_err(|e| e.emit_to_string(&source))?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::empty(),
    )
    .validate(&module)
    .map_err(|e| format!("validation: {e:?}"))?;
    Ok(Module { module, info })
}

fn header(lib: &Library, form: &str) -> String {
    let stem = lib.stem;
    format!(
        "// {stem}, {form}: GENERATED from {stem}.wgsl by naga {} \
         (cargo run -p irid-gpu --bin gen-shaders); do not edit.\n\
         // Interface, bindings and upload: docs/gpu.md.\n",
        NAGA_VERSION
    )
}

/// The naga release the files come from (Cargo.lock pins it).
pub const NAGA_VERSION: &str = "30";

fn glsl_form(
    lib: &Library,
    m: &Module,
    version: glsl::Version,
    form: &str,
) -> Result<String, String> {
    let mut binding_map = glsl::BindingMap::default();
    let desktop = matches!(version, glsl::Version::Desktop(_));
    if desktop {
        for &binding in lib.desktop_bindings {
            binding_map.insert(naga::ResourceBinding { group: 0, binding }, binding as u8);
        }
    }
    let options = glsl::Options {
        version,
        writer_flags: glsl::WriterFlags::empty(),
        binding_map,
        zero_initialize_workgroup_memory: false,
    };
    let pipeline = glsl::PipelineOptions {
        shader_stage: naga::ShaderStage::Fragment,
        entry_point: ENTRY.into(),
        multiview: None,
    };
    let mut raw = String::new();
    glsl::Writer::new(
        &mut raw,
        &m.module,
        &m.info,
        &options,
        &pipeline,
        naga::proc::BoundsCheckPolicies::default(),
    )
    .map_err(|e| format!("glsl: {e}"))?
    .write()
    .map_err(|e| format!("glsl: {e}"))?;

    let mut text = raw;
    for (from, to) in lib.glsl_names {
        text = replace_all(&text, from, to)?;
    }
    let mut out = header(lib, form);
    out.push_str(lib.glsl_notes[if desktop { 0 } else { 1 }]);
    let mut skipping_entry = false;
    let mut kept_any = false;
    for line in text.lines() {
        if line.starts_with("#version") {
            continue;
        }
        // The entry point's input and output variables.
        if (line.contains(" in ")
            || line.contains(" out ")
            || line.starts_with("in ")
            || line.starts_with("out "))
            && line.contains("location")
            || line.starts_with("smooth in ")
        {
            continue;
        }
        if line.starts_with("void main(") {
            skipping_entry = true;
            continue;
        }
        if skipping_entry {
            if line == "}" {
                skipping_entry = false;
            }
            continue;
        }
        kept_any = true;
        out.push_str(line);
        out.push('\n');
    }
    if !kept_any || out.contains("main(") || out.contains(ENTRY) {
        return Err(format!(
            "glsl: the entry point was not removed cleanly:\n{out}"
        ));
    }
    Ok(tidy(out))
}

fn hlsl_form(lib: &Library, m: &Module) -> Result<String, String> {
    let mut binding_map = hlsl::BindingMap::default();
    for &(binding, register) in lib.hlsl_registers {
        binding_map.insert(
            naga::ResourceBinding { group: 0, binding },
            hlsl::BindTarget {
                space: 0,
                register,
                binding_array_size: None,
                dynamic_storage_buffer_offsets_index: None,
                restrict_indexing: false,
            },
        );
    }
    let mut sampler_buffer_binding_map = hlsl::SamplerIndexBufferBindingMap::default();
    sampler_buffer_binding_map.insert(
        hlsl::SamplerIndexBufferKey { group: 0 },
        hlsl::BindTarget {
            space: 0,
            register: 2,
            binding_array_size: None,
            dynamic_storage_buffer_offsets_index: None,
            restrict_indexing: false,
        },
    );
    let options = hlsl::Options {
        shader_model: hlsl::ShaderModel::V5_1,
        binding_map,
        sampler_buffer_binding_map,
        fake_missing_bindings: false,
        ..Default::default()
    };
    let pipeline = hlsl::PipelineOptions {
        entry_point: Some((naga::ShaderStage::Fragment, ENTRY.into())),
    };
    let mut raw = String::new();
    hlsl::Writer::new(&mut raw, &options, &pipeline)
        .write(&m.module, &m.info, None)
        .map_err(|e| format!("hlsl: {e}"))?;
    let mut out = header(lib, "HLSL (Shader Model 5.1)");
    out.push_str(lib.hlsl_note);
    let (sampler_name, sampler_register) = lib.sampler;
    let (mut sampler, mut skipping) = (false, false);
    for line in raw.lines() {
        // naga reads samplers through a heap and an index buffer (as wgpu's
        // Direct3D 12 back end binds them): declare the sampler instead.
        if line.contains("nagaSamplerHeap")
            || line.contains("nagaComparisonSamplerHeap")
            || line.contains("nagaGroup0SamplerIndexArray")
        {
            if line.starts_with(&format!("static const SamplerState {sampler_name} ")) {
                let _ = writeln!(
                    out,
                    "SamplerState {sampler_name} : register(s{sampler_register});"
                );
                sampler = true;
            }
            continue;
        }
        if line.starts_with(&format!("struct FragmentInput_{ENTRY}"))
            || line.starts_with(&format!("float4 {ENTRY}("))
        {
            skipping = true;
            continue;
        }
        if skipping {
            if line == "}" || line == "};" {
                skipping = false;
            }
            continue;
        }
        out.push_str(line);
        out.push('\n');
    }
    if !sampler || out.contains(ENTRY) || out.contains("naga") && !out.contains("by naga") {
        return Err(format!("hlsl: unexpected output from naga:\n{raw}"));
    }
    Ok(tidy(out))
}

/// Replaces every `from` (which must occur) by `to`.
fn replace_all(text: &str, from: &str, to: &str) -> Result<String, String> {
    if !text.contains(from) {
        return Err(format!("naga's output has no `{from}`:\n{text}"));
    }
    Ok(text.replace(from, to))
}

/// At most one blank line in a row, and one newline at the end.
fn tidy(text: String) -> String {
    let mut out = String::with_capacity(text.len());
    let mut blank = 0;
    for line in text.lines() {
        if line.trim().is_empty() {
            blank += 1;
            if blank > 1 {
                continue;
            }
        } else {
            blank = 0;
        }
        let _ = writeln!(out, "{}", line.trim_end());
    }
    out.trim_end().to_string() + "\n"
}

/// The atlas mapping both libraries share, in WGSL: which chart serves a
/// lookup (chosen in closed form) and where in it the lookup lands, in
/// texels. `{P}` is the library's prefix, `{U}` its uniform array and `{B}`
/// the vec4 its atlas header starts at (docs/gpu.md "Uniform array").
/// Operation for operation `irid::atlas::locate_f32`.
const ATLAS_MAPPING: &str = r#"// The optical thickness factor s(c) = sqrt(max(1 - a (1 - c^2), floor^2))
// of a chart whose (side, kind, a, floor) is q1.
fn {P}_optical(q1: vec4<f32>, c: f32) -> f32 {
    return sqrt(max(1.0 - q1.z * (1.0 - c * c), q1.w * q1.w));
}

// A band's thickness warp: ln(1 + p / p0), or p itself when p0 is 0.
fn {P}_warp_p(p: f32, p0: f32) -> f32 {
    if p0 > 0.0 {
        return log(1.0 + max(p, 0.0) / p0);
    }
    return p;
}

// A band's cos θ warp: sign · g(|c - anchor|), g = ln(x + offset) for
// offset > 0, sqrt(x) for offset 0, x for offset < 0.
fn {P}_warp_c(c: f32, anchor: f32, offset: f32, sign: f32) -> f32 {
    let t = abs(c - anchor);
    var g = t;
    if offset > 0.0 {
        g = log(t + offset);
    } else if offset == 0.0 {
        g = sqrt(t);
    }
    return sign * g;
}

// The texel position (in texels) of thickness d (nm) and cos θ c in chart
// k: node i of its rectangle sits at the centre of texel i, and positions
// clamp to its first and last nodes, so the filter reads that chart only.
fn {P}_chart_texel(k: i32, d: f32, c: f32) -> vec2<f32> {
    let at = {B} + 2 + 4 * k;
    let rect = {U}[at];
    let q1 = {U}[at + 1];
    let q2 = {U}[at + 2];
    let q3 = {U}[at + 3];
    var xy = vec2<f32>(0.0, 0.0);
    if q1.y < 0.5 {
        // A band: u along ln(1 + p / p0) of the optical thickness p, v along
        // the warped cos θ.
        let cc = min(max(c, q3.x), q3.y);
        let p = d * {P}_optical(q1, cc);
        let u0 = {P}_warp_p(q2.y, q2.x);
        let u1 = {P}_warp_p(q2.z, q2.x);
        if u1 > u0 {
            xy.x = clamp(({P}_warp_p(p, q2.x) - u0) / (u1 - u0), 0.0, 1.0);
        }
        var sign = -1.0;
        if q3.x >= q3.z {
            sign = 1.0;
        }
        let v0 = {P}_warp_c(q3.x, q3.z, q3.w, sign);
        let v1 = {P}_warp_c(q3.y, q3.z, q3.w, sign);
        if v1 > v0 {
            xy.y = clamp(({P}_warp_c(cc, q3.z, q3.w, sign) - v0) / (v1 - v0), 0.0, 1.0);
        }
    } else {
        // The grazing corner: polar coordinates about (p = 0, cos θ = 0).
        let pp = d * {P}_optical(q1, c) / q2.x;
        let rho = sqrt(pp * pp + c * c);
        var phi = 0.0;
        if rho > 0.0 {
            phi = atan2(pp, c);
        }
        xy = vec2<f32>(clamp(phi / 1.5707964, 0.0, 1.0), clamp(rho / q2.y, 0.0, 1.0));
    }
    return rect.xy + 0.5 + xy * (rect.zw - 1.0);
}

// The texel position (in texels) a film at thickness_nm and cos_theta is
// read at, for light from `side`: the chart is the first of the side's
// corners whose radius holds the point, else the first of its bands whose
// cos θ range reaches up to cos_theta, else its last band. Any side but 0
// reads the side the header names (1, or 0 for a film that reads the same
// from both sides or that no light crosses).
fn {P}_texel(thickness_nm: f32, cos_theta: f32, side: i32) -> vec2<f32> {
    let header = {U}[{B}];
    let range = {U}[{B} + 1];
    // The count stays in f32: no float-to-int helper that would clash when
    // a shader holds both libraries' HLSL.
    var s = 0.0;
    if side != 0 {
        s = header.w;
    }
    let d = min(max(thickness_nm, range.x), range.y);
    let c = clamp(cos_theta, 0.0, 1.0);
    var chosen = -1;
    var last = -1;
    for (var k = 0; k < {MAX}; k++) {
        if f32(k) >= header.z || chosen >= 0 {
            break;
        }
        let at = {B} + 2 + 4 * k;
        let q1 = {U}[at + 1];
        if q1.x != s {
            continue;
        }
        if q1.y > 0.5 {
            let q2 = {U}[at + 2];
            let pp = d * {P}_optical(q1, c) / q2.x;
            if sqrt(pp * pp + c * c) < q2.y {
                chosen = k;
            }
            continue;
        }
        last = k;
        if c <= {U}[at + 3].y {
            chosen = k;
        }
    }
    if chosen < 0 {
        chosen = last;
    }
    if chosen < 0 {
        return vec2<f32>(0.5, 0.5);
    }
    return {P}_chart_texel(chosen, d, c);
}"#;

/// The most charts an atlas holds: `irid::atlas::MAX_CHARTS` (the gpu
/// tests check they agree).
pub const MAX_CHARTS: usize = 16;

/// The first and last line of the generated mapping in a WGSL library.
pub const MAPPING_BEGIN: &str =
    "// BEGIN atlas mapping: generated by gpu/src/generate.rs (cargo run -p irid-gpu --bin gen-shaders); do not edit.";
/// See [`MAPPING_BEGIN`].
pub const MAPPING_END: &str = "// END atlas mapping";

/// The atlas mapping for `lib`, between its markers.
pub fn mapping_wgsl(lib: &Library) -> String {
    let text = ATLAS_MAPPING
        .replace("{P}", lib.stem)
        .replace("{U}", lib.uniform)
        .replace("{B}", &lib.atlas_base.to_string())
        .replace("{MAX}", &MAX_CHARTS.to_string());
    format!("{MAPPING_BEGIN}\n{text}\n{MAPPING_END}")
}

/// `wgsl` with its mapping region (between the markers) replaced by
/// [`mapping_wgsl`]; an error when the markers are missing.
pub fn with_mapping(lib: &Library, wgsl: &str) -> Result<String, String> {
    let begin = wgsl
        .find(MAPPING_BEGIN)
        .ok_or_else(|| format!("{}.wgsl has no `{MAPPING_BEGIN}`", lib.stem))?;
    let end = wgsl[begin..]
        .find(MAPPING_END)
        .map(|e| begin + e + MAPPING_END.len())
        .ok_or_else(|| format!("{}.wgsl has no `{MAPPING_END}`", lib.stem))?;
    Ok(format!(
        "{}{}{}",
        &wgsl[..begin],
        mapping_wgsl(lib),
        &wgsl[end..]
    ))
}
