// The KHR_materials_iridescence reference model (Belcour & Barla 2017 as the
// glTF specification writes it: Schlick Fresnel, no polarization, phase
// shifts of 0 or π from comparing indices, two Airy-series terms, Gaussian
// fits of the colour-matching functions), rewritten in WGSL from irid's CPU
// version (src/analytic.rs, Variant::Gltf) for the speed comparison with
// irid_film. Test code: not a shader irid ships.

const BB_PI: f32 = 3.14159265;
const BB_TAU: f32 = 6.28318531;

struct BbFilm {
    outside_ior: f32,
    film_ior: f32,
    // The substrate's normal-incidence reflectance against air, per channel.
    base_f0: vec3<f32>,
}

fn bb_schlick(f0: vec3<f32>, cos_theta: f32) -> vec3<f32> {
    let m = clamp(1.0 - cos_theta, 0.0, 1.0);
    let m2 = m * m;
    return f0 + (1.0 - f0) * (m2 * m2 * m);
}

fn bb_f0_between(n_t: vec3<f32>, n_i: f32) -> vec3<f32> {
    let r = (n_t - n_i) / (n_t + n_i);
    return r * r;
}

fn bb_ior_from_f0(f0: vec3<f32>) -> vec3<f32> {
    let s = sqrt(clamp(f0, vec3<f32>(0.0), vec3<f32>(0.9999)));
    return (1.0 + s) / (1.0 - s);
}

// The spectral integral of e^{i 2π opd k} against x̄, ȳ, z̄ (Gaussian fits,
// normalized to equal-energy white): real parts in .re, imaginary in .im.
struct BbSensitivity {
    re: vec3<f32>,
    im: vec3<f32>,
}

fn bb_lobe(a: f32, mu: f32, v: f32, p: f32) -> vec2<f32> {
    let amp = a * sqrt(BB_TAU * v) * exp(-v * p * p) / 1.0685e-7;
    return amp * vec2<f32>(cos(mu * p), sin(mu * p));
}

fn bb_sensitivity(opd_nm: f32) -> BbSensitivity {
    let p = BB_TAU * opd_nm * 1e-9;
    let x = bb_lobe(5.4856e-13, 1.6810e6, 4.3278e9, p) + bb_lobe(9.7470e-14, 2.2399e6, 4.5282e9, p);
    let y = bb_lobe(4.4201e-13, 1.7953e6, 9.3046e9, p);
    let z = bb_lobe(5.2481e-13, 2.2084e6, 6.6121e9, p);
    return BbSensitivity(vec3<f32>(x.x, y.x, z.x), vec3<f32>(x.y, y.y, z.y));
}

// Linear-sRGB reflectance (no transmittance: the model has none).
fn belcour_barla_gltf(film: BbFilm, thickness_nm: f32, cos_theta_in: f32) -> vec3<f32> {
    if cos_theta_in <= 0.0 {
        return vec3<f32>(1.0);
    }
    let cos_theta = min(cos_theta_in, 1.0);
    let n1 = film.outside_ior;
    let n2 = film.film_ior;
    let sin2_theta2 = (n1 / n2) * (n1 / n2) * (1.0 - cos_theta * cos_theta);
    if sin2_theta2 >= 1.0 {
        return vec3<f32>(1.0);
    }
    let cos_theta2 = sqrt(1.0 - sin2_theta2);
    let r12 = bb_schlick(bb_f0_between(vec3<f32>(n2), n1), cos_theta).x;
    let t121 = 1.0 - r12;
    let phi12 = select(0.0, BB_PI, n2 < n1);
    let phi21 = BB_PI - phi12;
    let opd_nm = 2.0 * n2 * thickness_nm * cos_theta2;

    let base = bb_ior_from_f0(film.base_f0);
    let r23 = bb_schlick(bb_f0_between(base, n2), cos_theta2);
    let phi23 = select(vec3<f32>(0.0), vec3<f32>(BB_PI), base < vec3<f32>(n2));
    let r123 = clamp(r12 * r23, vec3<f32>(1e-5), vec3<f32>(0.9999));
    let rs = t121 * t121 * r23 / (1.0 - r123);
    let c0 = r12 + rs;
    let rho = sqrt(r123);
    let phase = phi21 + phi23;

    // Per channel c, the XYZ of the oscillating part: Σ_m 2 c_m Re(e^{i m phase_c} S_m).
    var x = vec3<f32>(0.0);
    var y = vec3<f32>(0.0);
    var z = vec3<f32>(0.0);
    var cm = rs - t121;
    for (var m = 1; m <= 2; m++) {
        cm *= rho;
        let s = bb_sensitivity(f32(m) * opd_nm);
        let c = cos(f32(m) * phase);
        let sn = sin(f32(m) * phase);
        x += 2.0 * cm * (c * s.re.x - sn * s.im.x);
        y += 2.0 * cm * (c * s.re.y - sn * s.im.y);
        z += 2.0 * cm * (c * s.re.z - sn * s.im.z);
    }
    // XYZ to linear sRGB, row c applied to channel c's XYZ.
    let rgb = c0
        + vec3<f32>(3.2404542, -0.9692660, 0.0556434) * x
        + vec3<f32>(-1.5371385, 1.8760108, -0.2040259) * y
        + vec3<f32>(-0.4985314, 0.0415560, 1.0572252) * z;
    return max(rgb, vec3<f32>(0.0));
}
