// irid_film_rough: a thin-film stack's reflectance pre-integrated over a
// GGX lobe (F_eff of docs/rough.md, light from the ambient), from the rough
// texture `irid export --rough` writes: an atlas of roughness slices. The
// source of truth: irid_film_rough.glsl, irid_film_rough_es.glsl and
// irid_film_rough.hlsl are generated from this file. It stands alone (its
// own bindings, beside irid_film's). Interface and upload: docs/gpu.md.

// film.json's "rough"."uniform_f32", uploaded as it is: an array of vec4.
//   v[0]: texture width, height (texels); slices; slices per row.
//   v[1]: thickness min nm, thickness max nm, cos min, cos max.
//   v[2]: cos_crit, y_crit, thickness power, gutter (texels).
//   v[3]: slice width, height (texels); pitch along x, along y (texels).
struct IridRoughParams {
    v: array<vec4<f32>, 4>,
}

@group(0) @binding(4) var irid_rough: texture_2d<f32>;
@group(0) @binding(5) var irid_rough_sampler: sampler;
@group(0) @binding(6) var<uniform> irid_rough_params: IridRoughParams;

// Where (thickness, cos θ) lies in a slice, in [0, 1]²: the closed form of
// irid_film's charts (docs/gpu.md), on the slices' own parameters.
fn irid_rough_xy(thickness_nm: f32, cos_theta: f32) -> vec2<f32> {
    let domain = irid_rough_params.v[1];
    let warp = irid_rough_params.v[2];
    let t_span = domain.y - domain.x;
    var x = 0.0;
    if t_span > 0.0 {
        x = clamp((thickness_nm - domain.x) / t_span, 0.0, 1.0);
    }
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
        y = y_crit + (1.0 - y_crit) * sqrt((c - cos_crit) / (domain.w - cos_crit));
    } else {
        y = y_crit - y_crit * sqrt((cos_crit - c) / (cos_crit - domain.z));
    }
    return vec2<f32>(x, y);
}

// The texture coordinate of chart point `xy` in slice `slice` (a whole
// number): slices lie in rows of v[0].w, each inside a gutter of edge
// copies, node i at the centre of its texel i. In f32 throughout (the half
// keeps the row off a rounding edge), so no float-to-int conversion helper
// is generated.
fn irid_rough_uv(slice: f32, xy: vec2<f32>) -> vec2<f32> {
    let header = irid_rough_params.v[0];
    let slices = irid_rough_params.v[3];
    let row = floor((slice + 0.5) / header.w);
    let column = slice - row * header.w;
    let origin = vec2<f32>(column, row) * slices.zw + irid_rough_params.v[2].w;
    let texel = origin + 0.5 + xy * (slices.xy - 1.0);
    return texel / header.xy;
}

// F_eff (linear RGB in the export's white) of the film at a thickness of
// the varying layer (nm), seen at a view angle whose cosine is taken in the
// ambient, for GGX roughness in [0, 1] (α = roughness²; clamped to the
// range): slice s holds roughness (s / (slices − 1))², so the slice
// position is √roughness · (slices − 1); one bilinear fetch in each of the
// two slices around it, blended linearly. At roughness 0 it is irid_film's front
// reflectance.
fn irid_film_rough(thickness_nm: f32, cos_theta: f32, roughness: f32) -> vec3<f32> {
    let xy = irid_rough_xy(thickness_nm, cos_theta);
    let n = irid_rough_params.v[0].z;
    let s = sqrt(clamp(roughness, 0.0, 1.0)) * (n - 1.0);
    let s0 = min(floor(s), n - 2.0);
    let w = s - s0;
    let a = textureSampleLevel(irid_rough, irid_rough_sampler, irid_rough_uv(s0, xy), 0.0);
    let b = textureSampleLevel(irid_rough, irid_rough_sampler, irid_rough_uv(s0 + 1.0, xy), 0.0);
    return a.rgb * (1.0 - w) + b.rgb * w;
}
