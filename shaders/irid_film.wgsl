// irid_film: a thin-film stack's reflectance and transmittance, seen from
// either side, from the two atlas textures `irid export` writes. The source
// of truth: irid_film.glsl, irid_film_es.glsl and irid_film.hlsl are
// generated from this file. Interface, bindings and upload: docs/gpu.md.

struct IridFilm {
    reflectance: vec3<f32>,
    transmittance: vec3<f32>,
}

// film.json's "uniform_f32", uploaded as it is: an array of vec4, which
// std140, std430, WGSL and HLSL all lay out alike.
//   v[0]: atlas width, height (texels); the chart of the front side, of the back.
//   chart k, from v[1 + 3k]:
//     (thickness min nm, thickness max nm, cos min, cos max),
//     (cos_crit, y_crit, thickness power, 0),
//     (x0, y0, width, height): its rectangle of texels.
struct IridParams {
    v: array<vec4<f32>, 25>,
}

@group(0) @binding(0) var irid_reflectance: texture_2d<f32>;
@group(0) @binding(1) var irid_transmittance: texture_2d<f32>;
@group(0) @binding(2) var irid_sampler: sampler;
@group(0) @binding(3) var<uniform> irid_params: IridParams;

// The chart a lookup reads, in closed form: today the side's own (side 0,
// light from the ambient; anything else, light from the substrate).
fn irid_film_chart(thickness_nm: f32, cos_theta: f32, side: i32) -> i32 {
    let header = irid_params.v[0];
    if side == 0 {
        return i32(header.z);
    }
    return i32(header.w);
}

// Where (thickness, cos θ) lies in a chart, in texture coordinates: node i
// of an axis of N nodes sits at the centre of the chart's texel i, and the
// coordinates are clamped to the chart's first and last node, so bilinear
// filtering interpolates between that chart's nodes only.
fn irid_film_uv(chart: i32, thickness_nm: f32, cos_theta: f32) -> vec2<f32> {
    let k = 1 + 3 * chart;
    let domain = irid_params.v[k];
    let warp = irid_params.v[k + 1];
    let rect = irid_params.v[k + 2];
    let t_span = domain.y - domain.x;
    var x = 0.0;
    if t_span > 0.0 {
        x = clamp((thickness_nm - domain.x) / t_span, 0.0, 1.0);
    }
    // Thickness power 2: nodes crowd quadratically towards the minimum.
    if warp.z > 1.5 {
        x = sqrt(x);
    }
    let c = clamp(cos_theta, domain.z, domain.w);
    let cos_crit = warp.x;
    let y_crit = warp.y;
    var y = 0.0;
    if cos_crit < 0.0 {
        let c_span = domain.w - domain.z;
        if c_span > 0.0 {
            y = (c - domain.z) / c_span;
        }
    } else if c >= cos_crit {
        // Nodes crowd quadratically towards cos_crit: at a critical angle,
        // R's square-root kink becomes a corner on a node; at grazing
        // incidence a thin film's fastest changes get the finest nodes.
        y = y_crit + (1.0 - y_crit) * sqrt((c - cos_crit) / (domain.w - cos_crit));
    } else {
        y = y_crit - y_crit * sqrt((cos_crit - c) / (cos_crit - domain.z));
    }
    let texel = rect.xy + 0.5 + vec2<f32>(x, y) * (rect.zw - 1.0);
    return texel / irid_params.v[0].xy;
}

// Reflectance and transmittance (linear RGB in the export's white) of the
// film at a thickness of the varying layer (nm), for light arriving from
// `side` (0: the ambient, the stack as written; 1: the substrate, the
// stack reversed) at an incidence angle whose cosine is taken in that
// medium. One fetch per texture.
fn irid_film(thickness_nm: f32, cos_theta: f32, side: i32) -> IridFilm {
    let chart = irid_film_chart(thickness_nm, cos_theta, side);
    let uv = irid_film_uv(chart, thickness_nm, cos_theta);
    let r = textureSampleLevel(irid_reflectance, irid_sampler, uv, 0.0);
    let t = textureSampleLevel(irid_transmittance, irid_sampler, uv, 0.0);
    return IridFilm(r.rgb, t.rgb);
}
