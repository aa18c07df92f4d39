// irid_film: a thin-film stack's reflectance and transmittance from the two
// textures `irid export` writes. The source of truth: irid_film.glsl,
// irid_film_es.glsl and irid_film.hlsl are generated from this file.
// Interface, bindings and upload: docs/gpu.md.

struct IridFilm {
    reflectance: vec3<f32>,
    transmittance: vec3<f32>,
}

// The values film.json lists under "params". Only f32 fields, so the layout
// is the same under std140, std430, WGSL and HLSL constant-buffer rules.
struct IridParams {
    thickness_min_nm: f32,
    thickness_max_nm: f32,
    cos_min: f32,
    cos_max: f32,
    // The cos θ angle nodes crowd towards (a dense-side stack's critical
    // angle, or cos_min for grazing incidence); < 0: uniform in cos θ.
    cos_crit: f32,
    y_crit: f32,
    size_u: f32,
    size_v: f32,
    // 1: thickness nodes uniform; 2: crowding quadratically towards the
    // minimum thickness.
    thickness_power: f32,
}

@group(0) @binding(0) var irid_reflectance: texture_2d<f32>;
@group(0) @binding(1) var irid_transmittance: texture_2d<f32>;
@group(0) @binding(2) var irid_sampler: sampler;
@group(0) @binding(3) var<uniform> irid_params: IridParams;

// Where (thickness, cos θ) lies in the textures: node i of an axis of N
// nodes sits at the texel centre (i + 0.5) / N, so bilinear filtering with
// clamp-to-edge interpolates between nodes and clamps outside the domain.
fn irid_film_uv(thickness_nm: f32, cos_theta: f32) -> vec2<f32> {
    let p = irid_params;
    let t_span = p.thickness_max_nm - p.thickness_min_nm;
    var x = 0.0;
    if t_span > 0.0 {
        x = clamp((thickness_nm - p.thickness_min_nm) / t_span, 0.0, 1.0);
    }
    if p.thickness_power > 1.5 {
        x = sqrt(x);
    }
    let c = clamp(cos_theta, p.cos_min, p.cos_max);
    var y = 0.0;
    if p.cos_crit < 0.0 {
        let c_span = p.cos_max - p.cos_min;
        if c_span > 0.0 {
            y = (c - p.cos_min) / c_span;
        }
    } else if c >= p.cos_crit {
        // Nodes crowd quadratically towards cos_crit: at a critical angle,
        // R's square-root kink becomes a corner on a node; at grazing
        // incidence a thin film's fastest changes get the finest nodes.
        y = p.y_crit + (1.0 - p.y_crit) * sqrt((c - p.cos_crit) / (p.cos_max - p.cos_crit));
    } else {
        y = p.y_crit - p.y_crit * sqrt((p.cos_crit - c) / (p.cos_crit - p.cos_min));
    }
    let u = (x * (p.size_u - 1.0) + 0.5) / p.size_u;
    let v = (y * (p.size_v - 1.0) + 0.5) / p.size_v;
    return vec2<f32>(u, v);
}

// Reflectance and transmittance (linear RGB in the export's white) of the
// film at a thickness of the varying layer (nm) and the cosine of the
// incidence angle in the ambient medium.
fn irid_film(thickness_nm: f32, cos_theta: f32) -> IridFilm {
    let uv = irid_film_uv(thickness_nm, cos_theta);
    let r = textureSampleLevel(irid_reflectance, irid_sampler, uv, 0.0);
    let t = textureSampleLevel(irid_transmittance, irid_sampler, uv, 0.0);
    return IridFilm(r.rgb, t.rgb);
}
