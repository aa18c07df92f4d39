// irid_film_rough, GLSL ES 3.00 (WebGL2): GENERATED from irid_film_rough.wgsl by naga 30 (cargo run -p irid-gpu --bin gen-shaders); do not edit.
// Interface, bindings and upload: docs/gpu.md.
// Prepend `#version 300 es`. irid_rough is a combined sampler (bilinear, clamp to
// edge, no mipmaps): bind with gl.uniform1i; the IridRoughParamsBlock uniform
// block with gl.uniformBlockBinding.

precision highp float;
precision highp int;

struct IridRoughParams {
    vec4 v[4];
};
uniform highp sampler2D irid_rough;

layout(std140) uniform IridRoughParamsBlock { IridRoughParams irid_rough_params; };

vec2 irid_rough_xy(float thickness_nm, float cos_theta) {
    float x = 0.0;
    float y = 0.0;
    vec4 domain = irid_rough_params.v[1];
    vec4 warp = irid_rough_params.v[2];
    float t_span = (domain.y - domain.x);
    if ((t_span > 0.0)) {
        x = clamp(((thickness_nm - domain.x) / t_span), 0.0, 1.0);
    }
    if ((warp.z > 1.5)) {
        float _e26 = x;
        x = sqrt(_e26);
    }
    float c = clamp(cos_theta, domain.z, domain.w);
    float cos_crit = warp.x;
    float y_crit = warp.y;
    if ((cos_crit < 0.0)) {
        float c_span = (domain.w - domain.z);
        if ((c_span > 0.0)) {
            y = ((c - domain.z) / c_span);
        }
    } else {
        if ((c >= cos_crit)) {
            y = (y_crit + ((1.0 - y_crit) * sqrt(((c - cos_crit) / (domain.w - cos_crit)))));
        } else {
            y = (y_crit - (y_crit * sqrt(((cos_crit - c) / (cos_crit - domain.z)))));
        }
    }
    float _e62 = x;
    float _e63 = y;
    return vec2(_e62, _e63);
}

vec2 irid_rough_uv(float slice, vec2 xy) {
    vec4 header = irid_rough_params.v[0];
    vec4 slices = irid_rough_params.v[3];
    float row = floor(((slice + 0.5) / header.w));
    float column = (slice - (row * header.w));
    float _e25 = irid_rough_params.v[2].w;
    vec2 origin = ((vec2(column, row) * slices.zw) + vec2(_e25));
    vec2 texel = ((origin + vec2(0.5)) + (xy * (slices.xy - vec2(1.0))));
    return (texel / header.xy);
}

vec3 irid_film_rough(float thickness_nm_1, float cos_theta_1, float roughness) {
    vec2 _e3 = irid_rough_xy(thickness_nm_1, cos_theta_1);
    float n = irid_rough_params.v[0].z;
    float s = (sqrt(clamp(roughness, 0.0, 1.0)) * (n - 1.0));
    float s0_ = min(floor(s), (n - 2.0));
    float w = (s - s0_);
    vec2 _e23 = irid_rough_uv(s0_, _e3);
    vec4 a = textureLod(irid_rough, vec2(_e23), 0.0);
    vec2 _e30 = irid_rough_uv((s0_ + 1.0), _e3);
    vec4 b = textureLod(irid_rough, vec2(_e30), 0.0);
    return ((a.xyz * (1.0 - w)) + (b.xyz * w));
}
