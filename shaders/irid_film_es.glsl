// irid_film, GLSL ES 3.00 (WebGL2): GENERATED from irid_film.wgsl by naga 30 (cargo run -p irid-gpu --bin gen-shaders); do not edit.
// Interface, bindings and upload: docs/gpu.md.
// Prepend `#version 300 es`. Textures are combined samplers (bilinear, clamp to
// edge, no mipmaps): bind with gl.uniform1i; the IridParamsBlock uniform block
// with gl.uniformBlockBinding.

precision highp float;
precision highp int;

struct IridFilm {
    vec3 reflectance;
    vec3 transmittance;
};
struct IridParams {
    vec4 v[25];
};
uniform highp sampler2D irid_reflectance;

uniform highp sampler2D irid_transmittance;

layout(std140) uniform IridParamsBlock { IridParams irid_params; };

int irid_film_chart(float thickness_nm, float cos_theta, int side) {
    vec4 header = irid_params.v[0];
    if ((side == 0)) {
        return int(header.z);
    }
    return int(header.w);
}

vec2 irid_film_uv(int chart, float thickness_nm_1, float cos_theta_1) {
    float x = 0.0;
    float y = 0.0;
    int k = (1 + (3 * chart));
    vec4 domain = irid_params.v[k];
    vec4 warp = irid_params.v[(k + 1)];
    vec4 rect = irid_params.v[(k + 2)];
    float t_span = (domain.y - domain.x);
    if ((t_span > 0.0)) {
        x = clamp(((thickness_nm_1 - domain.x) / t_span), 0.0, 1.0);
    }
    if ((warp.z > 1.5)) {
        float _e39 = x;
        x = sqrt(_e39);
    }
    float c = clamp(cos_theta_1, domain.z, domain.w);
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
    float _e79 = x;
    float _e80 = y;
    vec2 texel = ((rect.xy + vec2(0.5)) + (vec2(_e79, _e80) * (rect.zw - vec2(1.0))));
    vec4 _e91 = irid_params.v[0];
    return (texel / _e91.xy);
}

IridFilm irid_film(float thickness_nm_2, float cos_theta_2, int side_1) {
    int _e3 = irid_film_chart(thickness_nm_2, cos_theta_2, side_1);
    vec2 _e4 = irid_film_uv(_e3, thickness_nm_2, cos_theta_2);
    vec4 r = textureLod(irid_reflectance, vec2(_e4), 0.0);
    vec4 t = textureLod(irid_transmittance, vec2(_e4), 0.0);
    return IridFilm(r.xyz, t.xyz);
}
