//! Colour derivatives: the exact colour of a stack (the 1 nm sum
//! [`stack_colors`](super::stack_colors) integrates, refined where its
//! fringes need it) and its derivative by every layer's thickness, and
//! the CIEDE2000 difference from a target colour with its derivative by
//! the colour, so that colour objectives can be optimized smoothly.
//!
//! The colour is linear in the spectrum, so its derivative is the same
//! weighted sum of the spectrum's derivatives
//! ([`optics::gradient`](crate::optics::gradient)). ΔE00 goes through
//! linear sRGB → XYZ → Lab → CIEDE2000, each differentiated exactly in
//! forward mode ([`Dual`]). ΔE00 has no derivative where it is 0 (it is a
//! distance) or where the hue of a neutral colour is undefined: there the
//! derivative is taken as 0.

use super::ciede2000::{LAB_EPSILON, LAB_KAPPA};
use super::dual::Dual;
use super::refine::Refinement;
use super::space::{mat_vec, srgb};
use super::{Sampling, SpectralIntegrator, White};
use crate::cancel::Cancel;
use crate::error::{Error, Result};
use crate::optics::gradient::{solve_stack_grid_with_gradient, GradientGrid};
use crate::optics::{Stack, StackGrid};

/// A stack's colour at one angle and its derivative by each layer's
/// thickness (per nm, top layer first).
#[derive(Clone, Debug, PartialEq)]
pub struct ColorGradient {
    /// Linear sRGB of the unpolarized reflectance, as [`stack_colors`](super::stack_colors).
    pub reflectance_rgb: [f64; 3],
    /// Linear sRGB of the unpolarized transmittance.
    pub transmittance_rgb: [f64; 3],
    /// ∂reflectance_rgb/∂d_j, one per layer.
    pub d_reflectance_rgb: Vec<[f64; 3]>,
    /// ∂transmittance_rgb/∂d_j, one per layer.
    pub d_transmittance_rgb: Vec<[f64; 3]>,
    /// CIE XYZ of the reflectance (Y = 1 for a perfect reflector).
    pub reflectance_xyz: [f64; 3],
    /// CIE XYZ of the transmittance.
    pub transmittance_xyz: [f64; 3],
    /// ∂reflectance_xyz/∂d_j.
    pub d_reflectance_xyz: Vec<[f64; 3]>,
    /// ∂transmittance_xyz/∂d_j.
    pub d_transmittance_xyz: Vec<[f64; 3]>,
}

impl ColorGradient {
    /// ΔE00 of the reflected colour from `target_rgb` (linear sRGB) and
    /// its derivative by each layer's thickness.
    pub fn reflectance_delta_e00(&self, target_rgb: [f64; 3]) -> (f64, Vec<f64>) {
        chain(self.reflectance_rgb, &self.d_reflectance_rgb, target_rgb)
    }

    /// ΔE00 of the transmitted colour from `target_rgb` and its derivative
    /// by each layer's thickness.
    pub fn transmittance_delta_e00(&self, target_rgb: [f64; 3]) -> (f64, Vec<f64>) {
        chain(
            self.transmittance_rgb,
            &self.d_transmittance_rgb,
            target_rgb,
        )
    }
}

fn chain(rgb: [f64; 3], d_rgb: &[[f64; 3]], target_rgb: [f64; 3]) -> (f64, Vec<f64>) {
    let (de, by_rgb) = delta_e00_with_gradient(rgb, target_rgb);
    let by_layer = d_rgb
        .iter()
        .map(|d| (0..3).map(|c| by_rgb[c] * d[c]).sum())
        .collect();
    (de, by_layer)
}

/// The colour of `stack` at cos θ0 `cos_theta0` under `white`, with the
/// exact (1 nm) sampling, and its derivative by every layer's thickness.
pub fn color_with_gradient(stack: &Stack, cos_theta0: f64, white: White) -> Result<ColorGradient> {
    if !(cos_theta0 > 0.0 && cos_theta0 <= 1.0) {
        return Err(Error::invalid(
            "cos_theta0",
            format!("{cos_theta0} is outside (0, 1]"),
        ));
    }
    let integrator = SpectralIntegrator::with_white(Sampling::Exact, white);
    let mut colors = colors_with_gradient_at(stack, &integrator, &[cos_theta0], Cancel::never())?;
    Ok(colors.remove(0))
}

/// [`color_with_gradient`] at each angle (degrees, in [0, 90)) by any
/// integrator: the colours [`stack_colors`](super::stack_colors) gives,
/// with their derivatives.
pub fn colors_with_gradient(
    stack: &Stack,
    integrator: &SpectralIntegrator,
    angles_deg: &[f64],
) -> Result<Vec<ColorGradient>> {
    colors_with_gradient_cancellable(stack, integrator, angles_deg, Cancel::never())
}

/// [`colors_with_gradient`], stopping with [`Error::Cancelled`] once
/// `cancel` is set: it looks at the flag before each angle.
pub fn colors_with_gradient_cancellable(
    stack: &Stack,
    integrator: &SpectralIntegrator,
    angles_deg: &[f64],
    cancel: &Cancel,
) -> Result<Vec<ColorGradient>> {
    if let Some(a) = angles_deg.iter().find(|a| !(**a >= 0.0 && **a < 90.0)) {
        return Err(Error::invalid(
            "angle",
            format!("{a} is outside [0, 90) degrees"),
        ));
    }
    let cos_theta0: Vec<f64> = angles_deg.iter().map(|a| a.to_radians().cos()).collect();
    colors_with_gradient_at(stack, integrator, &cos_theta0, cancel)
}

fn colors_with_gradient_at(
    stack: &Stack,
    integrator: &SpectralIntegrator,
    cos_theta0: &[f64],
    cancel: &Cancel,
) -> Result<Vec<ColorGradient>> {
    let grid = StackGrid::new(stack, integrator.wavelengths_nm())?;
    let thicknesses = stack.thicknesses_nm();
    let refinement = Refinement::new_cancellable(stack, None, integrator, cancel)?;
    cos_theta0
        .iter()
        .map(|&c| {
            cancel.check()?;
            let m = refinement.sub_steps(0.0, c);
            let (solved, by) = if m > 1 {
                let level = refinement.level(m)?;
                (
                    solve_stack_grid_with_gradient(&level.grid, &thicknesses, &[c])?,
                    &level.integrator,
                )
            } else {
                (
                    solve_stack_grid_with_gradient(&grid, &thicknesses, &[c])?,
                    integrator,
                )
            };
            Ok(integrate(&solved, by))
        })
        .collect()
}

/// The colour of a one-angle gradient grid and of its derivatives.
fn integrate(solved: &GradientGrid, by: &SpectralIntegrator) -> ColorGradient {
    let w = solved.wavelengths;
    let r: Vec<f64> = solved.response.iter().map(|x| x.r()).collect();
    let t: Vec<f64> = solved.response.iter().map(|x| x.t()).collect();
    let half_sum = |a: &[f64], b: &[f64]| -> Vec<f64> {
        a.iter().zip(b).map(|(x, y)| 0.5 * (x + y)).collect()
    };
    let mut out = ColorGradient {
        reflectance_rgb: by.rgb(&r),
        transmittance_rgb: by.rgb(&t),
        reflectance_xyz: by.xyz(&r),
        transmittance_xyz: by.xyz(&t),
        d_reflectance_rgb: Vec::with_capacity(solved.layers),
        d_transmittance_rgb: Vec::with_capacity(solved.layers),
        d_reflectance_xyz: Vec::with_capacity(solved.layers),
        d_transmittance_xyz: Vec::with_capacity(solved.layers),
    };
    for l in 0..solved.layers {
        let span = l * w..(l + 1) * w;
        let dr = half_sum(&solved.d_rs[span.clone()], &solved.d_rp[span.clone()]);
        let dt = half_sum(&solved.d_ts[span.clone()], &solved.d_tp[span]);
        out.d_reflectance_rgb.push(by.rgb(&dr));
        out.d_transmittance_rgb.push(by.rgb(&dt));
        out.d_reflectance_xyz.push(by.xyz(&dr));
        out.d_transmittance_xyz.push(by.xyz(&dt));
    }
    out
}

/// CIEDE2000 between linear-sRGB `rgb` and `target_rgb` (as
/// [`delta_e2000_rgb`](super::delta_e2000_rgb)) and its derivative by
/// each component of `rgb`.
pub fn delta_e00_with_gradient(rgb: [f64; 3], target_rgb: [f64; 3]) -> (f64, [f64; 3]) {
    let m = srgb();
    let xyz: [Dual; 3] = std::array::from_fn(|row| {
        (0..3).fold(Dual::constant(0.0), |acc, c| {
            acc + Dual::input(rgb[c], c) * m.rgb_to_xyz[row][c]
        })
    });
    let lab1 = lab(xyz, m.white_xyz);
    let lab2 = super::ciede2000::lab(mat_vec(&m.rgb_to_xyz, target_rgb), m.white_xyz);
    let de = delta_e2000(lab1, lab2.map(Dual::constant));
    (de.v, de.d)
}

/// CIE Lab of a dual XYZ (as `ciede2000::lab`).
fn lab(xyz: [Dual; 3], white_xyz: [f64; 3]) -> [Dual; 3] {
    let f = |t: Dual| {
        if t.v > LAB_EPSILON {
            t.cbrt()
        } else {
            (t * LAB_KAPPA + 16.0) / 116.0
        }
    };
    let [fx, fy, fz] = [0, 1, 2].map(|k| f(xyz[k] / white_xyz[k]));
    [fy * 116.0 - 16.0, (fx - fy) * 500.0, (fy - fz) * 200.0]
}

/// CIEDE2000 (k_L = k_C = k_H = 1) of dual Lab colours, the equations of
/// `ciede2000::delta_e2000` (Sharma, Wu and Dalal 2005).
fn delta_e2000(lab1: [Dual; 3], lab2: [Dual; 3]) -> Dual {
    const POW25_7: f64 = 6_103_515_625.0;
    let deg = std::f64::consts::PI / 180.0;
    let [l1, a1, b1] = lab1;
    let [l2, a2, b2] = lab2;
    let c_bar = ((a1 * a1 + b1 * b1).sqrt() + (a2 * a2 + b2 * b2).sqrt()) * 0.5;
    let c_bar7 = c_bar.powi(7);
    let g = (1.0 - (c_bar7 / (c_bar7 + POW25_7)).sqrt()) * 0.5;
    let (a1p, a2p) = ((1.0 + g) * a1, (1.0 + g) * a2);
    let (c1p, c2p) = ((a1p * a1p + b1 * b1).sqrt(), (a2p * a2p + b2 * b2).sqrt());
    let hue = |b: Dual, ap: Dual| {
        if b.v == 0.0 && ap.v == 0.0 {
            Dual::constant(0.0)
        } else {
            let h = b.atan2(ap) / deg;
            if h.v < 0.0 {
                h + 360.0
            } else {
                h
            }
        }
    };
    let (h1p, h2p) = (hue(b1, a1p), hue(b2, a2p));
    let dl = l2 - l1;
    let dc = c2p - c1p;
    let neutral = c1p.v * c2p.v == 0.0;
    let dh_deg = h2p - h1p;
    let dh = if neutral {
        Dual::constant(0.0)
    } else if dh_deg.v.abs() <= 180.0 {
        dh_deg
    } else if dh_deg.v > 180.0 {
        dh_deg - 360.0
    } else {
        dh_deg + 360.0
    };
    let big_dh = 2.0 * (c1p * c2p).sqrt() * (dh * (0.5 * deg)).sin_cos().0;
    let l_bar = (l1 + l2) * 0.5;
    let cp_bar = (c1p + c2p) * 0.5;
    let h_sum = h1p + h2p;
    let hp_bar = if neutral {
        h_sum
    } else if dh_deg.v.abs() <= 180.0 {
        h_sum * 0.5
    } else if h_sum.v < 360.0 {
        (h_sum + 360.0) * 0.5
    } else {
        (h_sum - 360.0) * 0.5
    };
    let cos_term = |k: f64, shift_deg: f64| ((hp_bar * k - shift_deg) * deg).sin_cos().1;
    let t =
        1.0 - 0.17 * cos_term(1.0, 30.0) + 0.24 * cos_term(2.0, 0.0) + 0.32 * cos_term(3.0, -6.0)
            - 0.20 * cos_term(4.0, 63.0);
    let l50 = (l_bar - 50.0) * (l_bar - 50.0);
    let s_l = 1.0 + 0.015 * l50 / (l50 + 20.0).sqrt();
    let s_c = 1.0 + 0.045 * cp_bar;
    let s_h = 1.0 + 0.015 * cp_bar * t;
    let x = (hp_bar - 275.0) / 25.0;
    let d_theta = 30.0 * (-(x * x)).exp();
    let cp_bar7 = cp_bar.powi(7);
    let r_c = 2.0 * (cp_bar7 / (cp_bar7 + POW25_7)).sqrt();
    let r_t = -r_c * (d_theta * (2.0 * deg)).sin_cos().0;
    let (tl, tc, th) = (dl / s_l, dc / s_c, big_dh / s_h);
    (tl * tl + tc * tc + th * th + r_t * tc * th).sqrt()
}
