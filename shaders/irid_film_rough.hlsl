// irid_film_rough, HLSL (Shader Model 5.1): GENERATED from irid_film_rough.wgsl by naga 30 (cargo run -p irid-gpu --bin gen-shaders); do not edit.
// Interface, bindings and upload: docs/gpu.md.
// The texture at t2, the sampler (bilinear, clamp to edge) at s1, the
// parameters in cbuffer irid_rough_params at b1 (beside irid_film's).

struct IridRoughParams {
    float4 v[4];
};

Texture2D<float4> irid_rough : register(t2);
SamplerState irid_rough_sampler : register(s1);
cbuffer irid_rough_params : register(b1) { IridRoughParams irid_rough_params; }

float2 irid_rough_xy(float thickness_nm, float cos_theta)
{
    float x = 0.0;
    float y = 0.0;

    float4 domain = irid_rough_params.v[1];
    float4 warp = irid_rough_params.v[2];
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
    return float2(_e62, _e63);
}

float2 irid_rough_uv(float slice, float2 xy)
{
    float4 header = irid_rough_params.v[0];
    float4 slices = irid_rough_params.v[3];
    float row = floor(((slice + 0.5) / header.w));
    float column = (slice - (row * header.w));
    float _e25 = irid_rough_params.v[2].w;
    float2 origin = ((float2(column, row) * slices.zw) + (_e25).xx);
    float2 texel = ((origin + (0.5).xx) + (xy * (slices.xy - (1.0).xx)));
    return (texel / header.xy);
}

float3 irid_film_rough(float thickness_nm_1, float cos_theta_1, float roughness)
{
    const float2 _e3 = irid_rough_xy(thickness_nm_1, cos_theta_1);
    float n = irid_rough_params.v[0].z;
    float s = (sqrt(clamp(roughness, 0.0, 1.0)) * (n - 1.0));
    float s0_ = min(floor(s), (n - 2.0));
    float w = (s - s0_);
    const float2 _e23 = irid_rough_uv(s0_, _e3);
    float4 a = irid_rough.SampleLevel(irid_rough_sampler, _e23, 0.0);
    const float2 _e30 = irid_rough_uv((s0_ + 1.0), _e3);
    float4 b = irid_rough.SampleLevel(irid_rough_sampler, _e30, 0.0);
    return ((a.xyz * (1.0 - w)) + (b.xyz * w));
}
