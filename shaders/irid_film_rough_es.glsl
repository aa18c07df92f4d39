// irid_film_rough, GLSL ES 3.00 (WebGL2): GENERATED from irid_film_rough.wgsl by naga 30 (cargo run -p irid-gpu --bin gen-shaders); do not edit.
// Interface, bindings and upload: docs/gpu.md.
// Prepend `#version 300 es`. irid_rough is a combined sampler (bilinear, clamp to
// edge, no mipmaps): bind with gl.uniform1i; the IridRoughParamsBlock uniform
// block with gl.uniformBlockBinding.

precision highp float;
precision highp int;

struct IridRoughParams {
    vec4 v[132];
};
uniform highp sampler2D irid_rough;

layout(std140) uniform IridRoughParamsBlock { IridRoughParams irid_rough_params; };

float irid_film_rough_optical(vec4 q1_, float c) {
    return sqrt(max((1.0 - (q1_.z * (1.0 - (c * c)))), (q1_.w * q1_.w)));
}

float irid_film_rough_warp_p(float p, float p0_) {
    if ((p0_ > 0.0)) {
        return log((1.0 + (max(p, 0.0) / p0_)));
    }
    return p;
}

float irid_film_rough_warp_c(float c_1, float anchor, float offset, float sign_) {
    float g = 0.0;
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

vec2 irid_film_rough_chart_texel(int k, float d, float c_2) {
    vec2 xy = vec2(0.0, 0.0);
    float sign_1 = -1.0;
    float phi = 0.0;
    int at_1 = (4 + (4 * k));
    vec4 rect = irid_rough_params.v[at_1];
    vec4 q1_1 = irid_rough_params.v[(at_1 + 1)];
    vec4 q2_ = irid_rough_params.v[(at_1 + 2)];
    vec4 q3_ = irid_rough_params.v[(at_1 + 3)];
    if ((q1_1.y < 0.5)) {
        float cc = min(max(c_2, q3_.x), q3_.y);
        float _e40 = irid_film_rough_optical(q1_1, cc);
        float p_1 = (d * _e40);
        float _e44 = irid_film_rough_warp_p(q2_.y, q2_.x);
        float _e47 = irid_film_rough_warp_p(q2_.z, q2_.x);
        if ((_e47 > _e44)) {
            float _e51 = irid_film_rough_warp_p(p_1, q2_.x);
            xy.x = clamp(((_e51 - _e44) / (_e47 - _e44)), 0.0, 1.0);
        }
        if ((q3_.x >= q3_.z)) {
            sign_1 = 1.0;
        }
        float _e67 = sign_1;
        float _e68 = irid_film_rough_warp_c(q3_.x, q3_.z, q3_.w, _e67);
        float _e72 = sign_1;
        float _e73 = irid_film_rough_warp_c(q3_.y, q3_.z, q3_.w, _e72);
        if ((_e73 > _e68)) {
            float _e78 = sign_1;
            float _e79 = irid_film_rough_warp_c(cc, q3_.z, q3_.w, _e78);
            xy.y = clamp(((_e79 - _e68) / (_e73 - _e68)), 0.0, 1.0);
        }
    } else {
        float _e86 = irid_film_rough_optical(q1_1, c_2);
        float pp = ((d * _e86) / q2_.x);
        float rho = sqrt(((pp * pp) + (c_2 * c_2)));
        if ((rho > 0.0)) {
            phi = atan(pp, c_2);
        }
        float _e99 = phi;
        xy = vec2(clamp((_e99 / 1.5707964), 0.0, 1.0), clamp((rho / q2_.y), 0.0, 1.0));
    }
    vec2 _e115 = xy;
    return ((rect.xy + vec2(0.5)) + (_e115 * (rect.zw - vec2(1.0))));
}

vec2 irid_film_rough_texel(float thickness_nm, float cos_theta, int side) {
    float s = 0.0;
    int chosen = -1;
    int last = -1;
    int k_1 = 0;
    bool local = false;
    vec4 header = irid_rough_params.v[2];
    vec4 range = irid_rough_params.v[3];
    if ((side != 0)) {
        s = header.w;
    }
    float d_1 = min(max(thickness_nm, range.x), range.y);
    float c_3 = clamp(cos_theta, 0.0, 1.0);
    bool loop_init = true;
    while(true) {
        if (!loop_init) {
            int _e89 = k_1;
            k_1 = (_e89 + 1);
        }
        loop_init = false;
        int _e29 = k_1;
        if ((_e29 < 32)) {
        } else {
            break;
        }
        {
            int _e32 = k_1;
            if (!((float(_e32) >= header.z))) {
                int _e39 = chosen;
                local = (_e39 >= 0);
            } else {
                local = true;
            }
            bool _e43 = local;
            if (_e43) {
                break;
            }
            int _e44 = k_1;
            int at_2 = (4 + (4 * _e44));
            vec4 q1_2 = irid_rough_params.v[(at_2 + 1)];
            float _e56 = s;
            if ((q1_2.x != _e56)) {
                continue;
            }
            if ((q1_2.y > 0.5)) {
                vec4 q2_1 = irid_rough_params.v[(at_2 + 2)];
                float _e67 = irid_film_rough_optical(q1_2, c_3);
                float pp_1 = ((d_1 * _e67) / q2_1.x);
                if ((sqrt(((pp_1 * pp_1) + (c_3 * c_3))) < q2_1.y)) {
                    int _e77 = k_1;
                    chosen = _e77;
                }
                continue;
            }
            int _e78 = k_1;
            last = _e78;
            float _e85 = irid_rough_params.v[(at_2 + 3)].y;
            if ((c_3 <= _e85)) {
                int _e87 = k_1;
                chosen = _e87;
            }
        }
    }
    int _e91 = chosen;
    if ((_e91 < 0)) {
        int _e94 = last;
        chosen = _e94;
    }
    int _e95 = chosen;
    if ((_e95 < 0)) {
        return vec2(0.5, 0.5);
    }
    int _e101 = chosen;
    vec2 _e102 = irid_film_rough_chart_texel(_e101, d_1, c_3);
    return _e102;
}

vec2 irid_film_rough_uv(float slice, vec2 texel) {
    vec4 tiling = irid_rough_params.v[0];
    vec4 pitch = irid_rough_params.v[1];
    float row = floor(((slice + 0.5) / tiling.w));
    float column = (slice - (row * tiling.w));
    vec2 origin = ((vec2(column, row) * pitch.xy) + vec2(pitch.z));
    return ((origin + texel) / tiling.xy);
}

vec3 irid_film_rough(float thickness_nm_1, float cos_theta_1, float roughness) {
    vec2 _e4 = irid_film_rough_texel(thickness_nm_1, cos_theta_1, 0);
    float n = irid_rough_params.v[0].z;
    float s_1 = (sqrt(clamp(roughness, 0.0, 1.0)) * (n - 1.0));
    float s0_ = min(floor(s_1), (n - 2.0));
    float w = (s_1 - s0_);
    vec2 _e24 = irid_film_rough_uv(s0_, _e4);
    vec4 a = textureLod(irid_rough, vec2(_e24), 0.0);
    vec2 _e31 = irid_film_rough_uv((s0_ + 1.0), _e4);
    vec4 b = textureLod(irid_rough, vec2(_e31), 0.0);
    return ((a.xyz * (1.0 - w)) + (b.xyz * w));
}
