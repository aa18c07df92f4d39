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
    float4 v[25];
};

Texture2D<float4> irid_reflectance : register(t0);
Texture2D<float4> irid_transmittance : register(t1);
SamplerState irid_sampler : register(s0);
cbuffer irid_params : register(b0) { IridParams irid_params; }

int naga_f2i32(float value) {
    return int(clamp(value, -2147483600.0, 2147483500.0));
}

int irid_film_chart(float thickness_nm, float cos_theta, int side)
{
    float4 header = irid_params.v[0];
    if ((side == int(0))) {
        return naga_f2i32(header.z);
    }
    return naga_f2i32(header.w);
}

float2 irid_film_uv(int chart, float thickness_nm_1, float cos_theta_1)
{
    float x = 0.0;
    float y = 0.0;

    int k = asint(asuint(int(1)) + asuint(asint(asuint(int(3)) * asuint(chart))));
    float4 domain = irid_params.v[k];
    float4 warp = irid_params.v[asint(asuint(k) + asuint(int(1)))];
    float4 rect = irid_params.v[asint(asuint(k) + asuint(int(2)))];
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
    float2 texel = ((rect.xy + (0.5).xx) + (float2(_e79, _e80) * (rect.zw - (1.0).xx)));
    float4 _e91 = irid_params.v[0];
    return (texel / _e91.xy);
}

IridFilm ConstructIridFilm(float3 arg0, float3 arg1) {
    IridFilm ret = (IridFilm)0;
    ret.reflectance = arg0;
    ret.transmittance = arg1;
    return ret;
}

IridFilm irid_film(float thickness_nm_2, float cos_theta_2, int side_1)
{
    const int _e3 = irid_film_chart(thickness_nm_2, cos_theta_2, side_1);
    const float2 _e4 = irid_film_uv(_e3, thickness_nm_2, cos_theta_2);
    float4 r = irid_reflectance.SampleLevel(irid_sampler, _e4, 0.0);
    float4 t = irid_transmittance.SampleLevel(irid_sampler, _e4, 0.0);
    const IridFilm iridfilm = ConstructIridFilm(r.xyz, t.xyz);
    return iridfilm;
}
