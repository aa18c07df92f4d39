// irid_film_rough, HLSL (Shader Model 5.1): GENERATED from irid_film_rough.wgsl by naga 30 (cargo run -p irid-gpu --bin gen-shaders); do not edit.
// Interface, bindings and upload: docs/gpu.md.
// The texture at t2, the sampler (bilinear, clamp to edge) at s1, the
// parameters in cbuffer irid_rough_params at b1 (beside irid_film's).

struct IridRoughParams {
    float4 v[132];
};

Texture2D<float4> irid_rough : register(t2);
SamplerState irid_rough_sampler : register(s1);
cbuffer irid_rough_params : register(b1) { IridRoughParams irid_rough_params; }

float irid_film_rough_optical(float4 q1_, float c)
{
    return sqrt(max((1.0 - (q1_.z * (1.0 - (c * c)))), (q1_.w * q1_.w)));
}

float irid_film_rough_warp_p(float p, float p0_)
{
    if ((p0_ > 0.0)) {
        return log((1.0 + (max(p, 0.0) / p0_)));
    }
    return p;
}

float irid_film_rough_warp_c(float c_1, float anchor, float offset, float sign_)
{
    float g = (float)0;

    float t = abs((c_1 - anchor));
    g = t;
    if ((offset > 0.0)) {
        g = log((t + offset));
    } else {
        if ((offset == 0.0)) {
            g = sqrt(t);
        }
    }
    float _e14 = g;
    return (sign_ * _e14);
}

float2 irid_film_rough_chart_texel(int k, float d, float c_2)
{
    float2 xy = float2(0.0, 0.0);
    float sign_1 = -1.0;
    float phi = 0.0;

    int at_2 = asint(asuint(int(4)) + asuint(asint(asuint(int(4)) * asuint(k))));
    float4 rect = irid_rough_params.v[at_2];
    float4 q1_1 = irid_rough_params.v[asint(asuint(at_2) + asuint(int(1)))];
    float4 q2_ = irid_rough_params.v[asint(asuint(at_2) + asuint(int(2)))];
    float4 q3_ = irid_rough_params.v[asint(asuint(at_2) + asuint(int(3)))];
    if ((q1_1.y < 0.5)) {
        float cc = min(max(c_2, q3_.x), q3_.y);
        const float _e40 = irid_film_rough_optical(q1_1, cc);
        float p_1 = (d * _e40);
        const float _e44 = irid_film_rough_warp_p(q2_.y, q2_.x);
        const float _e47 = irid_film_rough_warp_p(q2_.z, q2_.x);
        if ((_e47 > _e44)) {
            const float _e51 = irid_film_rough_warp_p(p_1, q2_.x);
            xy.x = clamp(((_e51 - _e44) / (_e47 - _e44)), 0.0, 1.0);
        }
        if ((q3_.x >= q3_.z)) {
            sign_1 = 1.0;
        }
        float _e67 = sign_1;
        const float _e68 = irid_film_rough_warp_c(q3_.x, q3_.z, q3_.w, _e67);
        float _e72 = sign_1;
        const float _e73 = irid_film_rough_warp_c(q3_.y, q3_.z, q3_.w, _e72);
        if ((_e73 > _e68)) {
            float _e78 = sign_1;
            const float _e79 = irid_film_rough_warp_c(cc, q3_.z, q3_.w, _e78);
            xy.y = clamp(((_e79 - _e68) / (_e73 - _e68)), 0.0, 1.0);
        }
    } else {
        const float _e86 = irid_film_rough_optical(q1_1, c_2);
        float pp = ((d * _e86) / q2_.x);
        float rho = sqrt(((pp * pp) + (c_2 * c_2)));
        if ((rho > 0.0)) {
            phi = atan2(pp, c_2);
        }
        float _e99 = phi;
        xy = float2(clamp((_e99 / 1.5707964), 0.0, 1.0), clamp((rho / q2_.y), 0.0, 1.0));
    }
    float2 _e115 = xy;
    return ((rect.xy + (0.5).xx) + (_e115 * (rect.zw - (1.0).xx)));
}

float2 irid_film_rough_texel(float thickness_nm, float cos_theta, int side)
{
    float s = 0.0;
    int chosen = int(-1);
    int last = int(-1);
    int k_1 = int(0);
    bool local = (bool)0;

    float4 header = irid_rough_params.v[2];
    float4 range = irid_rough_params.v[3];
    if ((side != int(0))) {
        s = header.w;
    }
    float d_1 = min(max(thickness_nm, range.x), range.y);
    float c_3 = clamp(cos_theta, 0.0, 1.0);
    uint2 loop_bound = uint2(4294967295u, 4294967295u);
    bool loop_init = true;
    while(true) {
        if (all(loop_bound == uint2(0u, 0u))) { break; }
        loop_bound -= uint2(loop_bound.y == 0u, 1u);
        if (!loop_init) {
            int _e89 = k_1;
            k_1 = asint(asuint(_e89) + asuint(int(1)));
        }
        loop_init = false;
        int _e29 = k_1;
        if ((_e29 < int(32))) {
        } else {
            break;
        }
        {
            int _e32 = k_1;
            if (!((float(_e32) >= header.z))) {
                int _e39 = chosen;
                local = (_e39 >= int(0));
            } else {
                local = true;
            }
            bool _e43 = local;
            if (_e43) {
                break;
            }
            int _e44 = k_1;
            int at_3 = asint(asuint(int(4)) + asuint(asint(asuint(int(4)) * asuint(_e44))));
            float4 q1_2 = irid_rough_params.v[asint(asuint(at_3) + asuint(int(1)))];
            float _e56 = s;
            if ((q1_2.x != _e56)) {
                continue;
            }
            if ((q1_2.y > 0.5)) {
                float4 q2_1 = irid_rough_params.v[asint(asuint(at_3) + asuint(int(2)))];
                const float _e67 = irid_film_rough_optical(q1_2, c_3);
                float pp_1 = ((d_1 * _e67) / q2_1.x);
                if ((sqrt(((pp_1 * pp_1) + (c_3 * c_3))) < q2_1.y)) {
                    int _e77 = k_1;
                    chosen = _e77;
                }
                continue;
            }
            int _e78 = k_1;
            last = _e78;
            float _e85 = irid_rough_params.v[asint(asuint(at_3) + asuint(int(3)))].y;
            if ((c_3 <= _e85)) {
                int _e87 = k_1;
                chosen = _e87;
            }
        }
    }
    int _e91 = chosen;
    if ((_e91 < int(0))) {
        int _e94 = last;
        chosen = _e94;
    }
    int _e95 = chosen;
    if ((_e95 < int(0))) {
        return float2(0.5, 0.5);
    }
    int _e101 = chosen;
    const float2 _e102 = irid_film_rough_chart_texel(_e101, d_1, c_3);
    return _e102;
}

float2 irid_film_rough_uv(float slice, float2 texel)
{
    float4 tiling = irid_rough_params.v[0];
    float4 pitch = irid_rough_params.v[1];
    float row = floor(((slice + 0.5) / tiling.w));
    float column = (slice - (row * tiling.w));
    float2 origin = ((float2(column, row) * pitch.xy) + (pitch.z).xx);
    return ((origin + texel) / tiling.xy);
}

float3 irid_film_rough(float thickness_nm_1, float cos_theta_1, float roughness)
{
    const float2 _e4 = irid_film_rough_texel(thickness_nm_1, cos_theta_1, int(0));
    float n = irid_rough_params.v[0].z;
    float s_1 = (sqrt(clamp(roughness, 0.0, 1.0)) * (n - 1.0));
    float s0_ = min(floor(s_1), (n - 2.0));
    float w = (s_1 - s0_);
    const float2 _e24 = irid_film_rough_uv(s0_, _e4);
    float4 a = irid_rough.SampleLevel(irid_rough_sampler, _e24, 0.0);
    const float2 _e31 = irid_film_rough_uv((s0_ + 1.0), _e4);
    float4 b = irid_rough.SampleLevel(irid_rough_sampler, _e31, 0.0);
    return ((a.xyz * (1.0 - w)) + (b.xyz * w));
}
