// irid_film, HLSL (Shader Model 5.1): GENERATED from irid_film.wgsl by naga 30 (cargo run -p irid-gpu --bin gen-shaders); do not edit.
// Interface, bindings and upload: docs/gpu.md.
// Textures at t0 and t1, the sampler (bilinear, clamp to edge) at s0, the
// parameters in cbuffer irid_params at b0.

struct IridFilm {
    float3 reflectance;
    int _pad1_0;
    float3 transmittance;
    int _end_pad_0;
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

Texture2D<float4> irid_reflectance : register(t0);
Texture2D<float4> irid_transmittance : register(t1);
SamplerState irid_sampler : register(s0);
cbuffer irid_params : register(b0) { IridParams irid_params; }

float2 irid_film_uv(float thickness_nm, float cos_theta)
{
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
    return float2(u, v);
}

IridFilm ConstructIridFilm(float3 arg0, float3 arg1) {
    IridFilm ret = (IridFilm)0;
    ret.reflectance = arg0;
    ret.transmittance = arg1;
    return ret;
}

IridFilm irid_film(float thickness_nm_1, float cos_theta_1)
{
    const float2 _e2 = irid_film_uv(thickness_nm_1, cos_theta_1);
    float4 r = irid_reflectance.SampleLevel(irid_sampler, _e2, 0.0);
    float4 t = irid_transmittance.SampleLevel(irid_sampler, _e2, 0.0);
    const IridFilm iridfilm = ConstructIridFilm(r.xyz, t.xyz);
    return iridfilm;
}
