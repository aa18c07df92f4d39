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
    float thickness_min_nm;
    float thickness_max_nm;
    float cos_min;
    float cos_max;
    float cos_crit;
    float y_crit;
    float size_u;
    float size_v;
    float thickness_power;
};
uniform highp sampler2D irid_reflectance;

uniform highp sampler2D irid_transmittance;

layout(std140) uniform IridParamsBlock { IridParams irid_params; };

vec2 irid_film_uv(float thickness_nm, float cos_theta) {
    float x = 0.0;
    float y = 0.0;
    IridParams p = irid_params;
    float t_span = (p.thickness_max_nm - p.thickness_min_nm);
    if ((t_span > 0.0)) {
        x = clamp(((thickness_nm - p.thickness_min_nm) / t_span), 0.0, 1.0);
    }
    if ((p.thickness_power > 1.5)) {
        float _e20 = x;
        x = sqrt(_e20);
    }
    float c = clamp(cos_theta, p.cos_min, p.cos_max);
    if ((p.cos_crit < 0.0)) {
        float c_span = (p.cos_max - p.cos_min);
        if ((c_span > 0.0)) {
            y = ((c - p.cos_min) / c_span);
        }
    } else {
        if ((c >= p.cos_crit)) {
            y = (p.y_crit + ((1.0 - p.y_crit) * sqrt(((c - p.cos_crit) / (p.cos_max - p.cos_crit)))));
        } else {
            y = (p.y_crit - (p.y_crit * sqrt(((p.cos_crit - c) / (p.cos_crit - p.cos_min)))));
        }
    }
    float _e64 = x;
    float u = (((_e64 * (p.size_u - 1.0)) + 0.5) / p.size_u);
    float _e73 = y;
    float v = (((_e73 * (p.size_v - 1.0)) + 0.5) / p.size_v);
    return vec2(u, v);
}

IridFilm irid_film(float thickness_nm_1, float cos_theta_1) {
    vec2 _e2 = irid_film_uv(thickness_nm_1, cos_theta_1);
    vec4 r = textureLod(irid_reflectance, vec2(_e2), 0.0);
    vec4 t = textureLod(irid_transmittance, vec2(_e2), 0.0);
    return IridFilm(r.xyz, t.xyz);
}
