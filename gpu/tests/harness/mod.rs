//! Runs `irid_film` (or any function with its signature) in a compute
//! shader on a real graphics API through wgpu, on the textures of an
//! export: the same bindings a host sets up (docs/gpu.md).

#![allow(dead_code)]

use std::time::{Duration, Instant};

use irid::export::Export;
use wgpu::util::DeviceExt;

/// A device on a real (hardware or software) Vulkan driver.
pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
}

/// The Vulkan adapter, or None (with a note) when there is none. With
/// IRID_REQUIRE_GPU=1 (CI) a missing adapter is a failure, not a skip.
pub fn gpu() -> Option<Gpu> {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::VULKAN;
    let instance = wgpu::Instance::new(desc);
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        ..Default::default()
    }));
    let adapter = match adapter {
        Ok(a) => a,
        Err(e) => {
            let required = std::env::var("IRID_REQUIRE_GPU").is_ok_and(|v| v == "1");
            assert!(
                !required,
                "IRID_REQUIRE_GPU=1 but no Vulkan adapter: {e} (install mesa-vulkan-drivers for lavapipe)"
            );
            eprintln!("no Vulkan adapter ({e}): GPU test skipped; IRID_REQUIRE_GPU=1 makes this a failure");
            return None;
        }
    };
    let info = adapter.get_info();
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("irid tests"),
        required_limits: adapter.limits(),
        ..Default::default()
    }))
    .expect("device");
    Some(Gpu {
        device,
        queue,
        info,
    })
}

/// A shader source for the pipeline: WGSL, or Vulkan GLSL (through naga's
/// GLSL front end).
pub enum Source {
    Wgsl(String),
    Glsl(String),
}

/// The compute harness: `irid_film` at every point for the side in
/// `irid_repeat.y`, six floats out.
pub const WGSL_HARNESS: &str = r#"
@group(1) @binding(0) var<storage, read> irid_points: array<vec2<f32>>;
@group(1) @binding(1) var<storage, read_write> irid_results: array<f32>;
@group(1) @binding(2) var<uniform> irid_repeat: vec4<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&irid_points) {
        return;
    }
    var p = irid_points[i];
    var r = vec3<f32>(0.0);
    var t = vec3<f32>(0.0);
    // irid_repeat.x calls per point (timing), each at a slightly moved
    // point so that no call can be hoisted out of the loop.
    for (var k = 0u; k < irid_repeat.x; k++) {
        let f = FILM_FUNCTION(p.x + f32(k) * 1e-3, p.y, i32(irid_repeat.y));
        r += f.reflectance;
        t += f.transmittance;
    }
    let n = f32(max(irid_repeat.x, 1u));
    r /= n;
    t /= n;
    irid_results[6u * i + 0u] = r.x;
    irid_results[6u * i + 1u] = r.y;
    irid_results[6u * i + 2u] = r.z;
    irid_results[6u * i + 3u] = t.x;
    irid_results[6u * i + 4u] = t.y;
    irid_results[6u * i + 5u] = t.z;
}
"#;

/// The same harness in Vulkan GLSL.
pub const GLSL_HARNESS: &str = r#"
layout(local_size_x = 64) in;
layout(set = 1, binding = 0) readonly buffer IridPoints { vec2 irid_points[]; };
layout(set = 1, binding = 1) buffer IridResults { float irid_results[]; };
layout(set = 1, binding = 2) uniform IridRepeat { uvec4 irid_repeat; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(irid_points.length())) {
        return;
    }
    vec2 p = irid_points[i];
    vec3 r = vec3(0.0);
    vec3 t = vec3(0.0);
    for (uint k = 0u; k < irid_repeat.x; k++) {
        IridFilm f = irid_film(p.x + float(k) * 1e-3, p.y, int(irid_repeat.y));
        r += f.reflectance;
        t += f.transmittance;
    }
    float n = float(max(irid_repeat.x, 1u));
    r /= n;
    t /= n;
    irid_results[6u * i + 0u] = r.x;
    irid_results[6u * i + 1u] = r.y;
    irid_results[6u * i + 2u] = r.z;
    irid_results[6u * i + 3u] = t.x;
    irid_results[6u * i + 4u] = t.y;
    irid_results[6u * i + 5u] = t.z;
}
"#;

/// A WGSL compute shader: `library` (defining `function`) and the harness.
pub fn wgsl_program(library: &str, function: &str) -> Source {
    Source::Wgsl(format!(
        "{library}\n{}",
        WGSL_HARNESS.replace("FILM_FUNCTION", function)
    ))
}

/// A Vulkan GLSL compute shader from the generated GLSL 4.50 (or ES 3.00)
/// code. The generated code uses combined samplers (`uniform sampler2D
/// irid_reflectance;`), which OpenGL, WebGL2 and Vulkan accept but WebGPU
/// (and so naga's GLSL front end) does not: the test declares separate
/// textures and the sampler in their place and makes each name stand for the
/// combined sampler, leaving every line of the generated functions as it is.
pub fn glsl_program(generated: &str) -> Source {
    let mut body = String::new();
    let mut replaced = 0;
    for line in generated.lines() {
        let declares = |name: &str| {
            line.contains("uniform")
                && line.contains("sampler2D")
                && line.trim_end().ends_with(&format!(" {name};"))
        };
        if declares("irid_reflectance") || declares("irid_transmittance") {
            replaced += 1;
            continue;
        }
        if line.starts_with("#version") || line.starts_with("precision ") {
            continue;
        }
        // The parameter block at set 0, binding 3 (GLSL 4.50 gives the
        // binding, ES 3.00 none).
        let line = line
            .replace(
                "layout(std140, binding = 3) uniform",
                "layout(std140) uniform",
            )
            .replace(
                "layout(std140) uniform",
                "layout(std140, set = 0, binding = 3) uniform",
            );
        body.push_str(&line);
        body.push('\n');
    }
    assert_eq!(replaced, 2, "the generated GLSL declares both textures");
    Source::Glsl(format!(
        "#version 450\n\
         layout(set = 0, binding = 0) uniform texture2D irid_reflectance_texture;\n\
         layout(set = 0, binding = 1) uniform texture2D irid_transmittance_texture;\n\
         layout(set = 0, binding = 2) uniform sampler irid_sampler;\n\
         #define irid_reflectance sampler2D(irid_reflectance_texture, irid_sampler)\n\
         #define irid_transmittance sampler2D(irid_transmittance_texture, irid_sampler)\n\
         {body}\n{GLSL_HARNESS}"
    ))
}

/// An export's textures and parameters uploaded as a host does.
pub struct Bound {
    pub group: wgpu::BindGroup,
    pub layout: wgpu::BindGroupLayout,
}

fn f16_bytes(texels: &[[f32; 4]]) -> Vec<u8> {
    texels
        .iter()
        .flat_map(|t| t.iter().flat_map(|&v| half::f16::from_f32(v).to_le_bytes()))
        .collect()
}

/// An export directory as a host reads it: film.json's uniform array and
/// the two EXR files (rows in file order).
pub struct Files {
    pub uniform: Vec<f32>,
    pub reflectance: irid::export::Texture,
    pub transmittance: irid::export::Texture,
}

pub fn read_dir(dir: &std::path::Path) -> Files {
    let film: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("film.json")).unwrap()).unwrap();
    let uniform: Vec<f32> = film["uniform_f32"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap() as f32)
        .collect();
    assert_eq!(uniform.len(), 4 * irid::export::UNIFORM_VEC4);
    let read = |name: &str| {
        let texture = read_exr(&dir.join(name));
        assert_eq!(
            texture.width,
            film["texture"]["width"].as_u64().unwrap() as usize
        );
        assert_eq!(
            texture.height,
            film["texture"]["height"].as_u64().unwrap() as usize
        );
        texture
    };
    Files {
        uniform,
        reflectance: read("reflectance.exr"),
        transmittance: read("transmittance.exr"),
    }
}

/// An RGBA EXR texture, rows in file order.
pub fn read_exr(path: &std::path::Path) -> irid::export::Texture {
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |resolution, _| {
            (
                resolution.width(),
                vec![[0.0f32; 4]; resolution.width() * resolution.height()],
            )
        },
        |(width, texels), pos, (r, g, b, a): (f32, f32, f32, f32)| {
            texels[pos.y() * *width + pos.x()] = [r, g, b, a];
        },
    )
    .unwrap();
    let size = image.layer_data.size;
    let (_, texels) = image.layer_data.channel_data.pixels;
    irid::export::Texture {
        width: size.width(),
        height: size.height(),
        texels,
    }
}

/// A texture uploaded as RGBA16F, one mip level.
pub fn upload(gpu: &Gpu, label: &str, t: &irid::export::Texture) -> wgpu::TextureView {
    gpu.device
        .create_texture_with_data(
            &gpu.queue,
            &wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: t.width as u32,
                    height: t.height as u32,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba16Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            &f16_bytes(&t.texels),
        )
        .create_view(&wgpu::TextureViewDescriptor::default())
}

/// The sampler docs/gpu.md asks for: bilinear, clamp to edge.
pub fn bilinear_sampler(gpu: &Gpu, label: &str) -> wgpu::Sampler {
    gpu.device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some(label),
        address_mode_u: wgpu::AddressMode::ClampToEdge,
        address_mode_v: wgpu::AddressMode::ClampToEdge,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    })
}

/// Binds an export's textures and parameters (see [`bind`]).
pub fn bind_export(gpu: &Gpu, export: &Export) -> Bound {
    bind(
        gpu,
        &Files {
            uniform: export.atlas.uniform_f32().to_vec(),
            reflectance: export.reflectance.clone(),
            transmittance: export.transmittance.clone(),
        },
    )
}

/// Uploads the textures (RGBA16F, one mip level), a bilinear clamp-to-edge
/// sampler and the uniform array as it is: bind group 0 of docs/gpu.md.
pub fn bind(gpu: &Gpu, files: &Files) -> Bound {
    let reflectance = upload(gpu, "irid_reflectance", &files.reflectance);
    let transmittance = upload(gpu, "irid_transmittance", &files.transmittance);
    let sampler = bilinear_sampler(gpu, "irid_sampler");
    bind_group(
        gpu,
        "irid film",
        &[(0, &reflectance), (1, &transmittance)],
        (2, &sampler),
        (3, &files.uniform),
    )
}

/// Bind group 0 of a shader library: each texture at its binding, the
/// sampler at its binding, the uniform array (as it is) at its binding.
pub fn bind_group(
    gpu: &Gpu,
    label: &str,
    textures: &[(u32, &wgpu::TextureView)],
    sampler: (u32, &wgpu::Sampler),
    uniform: (u32, &[f32]),
) -> Bound {
    let device = &gpu.device;
    let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(uniform.1),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty,
        count: None,
    };
    let tex_ty = wgpu::BindingType::Texture {
        sample_type: wgpu::TextureSampleType::Float { filterable: true },
        view_dimension: wgpu::TextureViewDimension::D2,
        multisampled: false,
    };
    let mut layout_entries: Vec<_> = textures.iter().map(|&(b, _)| entry(b, tex_ty)).collect();
    layout_entries.push(entry(
        sampler.0,
        wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
    ));
    layout_entries.push(entry(
        uniform.0,
        wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
    ));
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &layout_entries,
    });
    let mut entries: Vec<_> = textures
        .iter()
        .map(|&(binding, view)| wgpu::BindGroupEntry {
            binding,
            resource: wgpu::BindingResource::TextureView(view),
        })
        .collect();
    entries.push(wgpu::BindGroupEntry {
        binding: sampler.0,
        resource: wgpu::BindingResource::Sampler(sampler.1),
    });
    entries.push(wgpu::BindGroupEntry {
        binding: uniform.0,
        resource: params.as_entire_binding(),
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &layout,
        entries: &entries,
    });
    Bound { group, layout }
}

/// A compiled compute pipeline over the film bindings (group 0) and the
/// harness buffers (group 1).
pub struct Program {
    pipeline: wgpu::ComputePipeline,
    io_layout: wgpu::BindGroupLayout,
}

pub fn program(gpu: &Gpu, film_layout: &wgpu::BindGroupLayout, source: Source) -> Program {
    let device = &gpu.device;
    let source = match source {
        Source::Wgsl(text) => wgpu::ShaderSource::Wgsl(text.into()),
        Source::Glsl(text) => wgpu::ShaderSource::Glsl {
            shader: text.into(),
            stage: naga::ShaderStage::Compute,
            defines: &[],
        },
    };
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("irid harness"),
        source,
    });
    let buffer = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let io_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("harness io"),
        entries: &[
            buffer(0, wgpu::BufferBindingType::Storage { read_only: true }),
            buffer(1, wgpu::BufferBindingType::Storage { read_only: false }),
            buffer(2, wgpu::BufferBindingType::Uniform),
        ],
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(film_layout), Some(&io_layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("irid harness"),
        layout: Some(&layout),
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    if let Some(e) = pollster::block_on(scope.pop()) {
        panic!("shader or pipeline rejected: {e}");
    }
    Program {
        pipeline,
        io_layout,
    }
}

/// Runs the program at `points` (thickness nm, cos θ) for light from
/// `side` (0 front, 1 back), `repeat` calls per point; returns six floats
/// per point and the GPU wall time.
pub fn run(
    gpu: &Gpu,
    program: &Program,
    film: &Bound,
    points: &[[f32; 2]],
    repeat: u32,
    side: u32,
) -> (Vec<[f32; 6]>, Duration) {
    let device = &gpu.device;
    let points_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("points"),
        contents: bytemuck::cast_slice(points),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let size = (points.len() * 6 * 4) as u64;
    let results = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("results"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let repeat_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("repeat"),
        contents: bytemuck::cast_slice(&[repeat, side, 0, 0]),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let io = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &program.io_layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: points_buf.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: results.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: repeat_buf.as_entire_binding(),
            },
        ],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&program.pipeline);
        pass.set_bind_group(0, &film.group, &[]);
        pass.set_bind_group(1, &io, &[]);
        pass.dispatch_workgroups((points.len() as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&results, 0, &readback, 0, size);
    let started = Instant::now();
    gpu.queue.submit([encoder.finish()]);
    device
        .poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        })
        .expect("poll");
    let elapsed = started.elapsed();
    let slice = readback.slice(..);
    slice.map_async(wgpu::MapMode::Read, |r| r.expect("map"));
    device
        .poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        })
        .expect("poll");
    let data = slice.get_mapped_range().expect("mapped results");
    let floats: &[f32] = bytemuck::cast_slice(&data);
    let out = floats
        .chunks_exact(6)
        .map(|c| std::array::from_fn(|k| c[k]))
        .collect();
    (out, elapsed)
}
