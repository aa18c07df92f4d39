//! Exact derivatives of R and T by every layer's thickness, from one extra
//! sweep of the solver's own recursion (not finite differences).
//!
//! Thickness enters the recursion only through each layer's phase: the
//! round-trip factor e^{2i k0 q d} in Γ form, the layer matrix of a
//! near-critical layer in field form. The coherent derivative
//! ([`coherent`]) records each step's local derivative on the way up and
//! multiplies them on one sweep back down (reverse mode), so all N
//! derivatives cost about one more recursion. Mixed stacks ([`mixed`])
//! differentiate the incoherent power sums in forward mode, taking each
//! coherent group's amplitude derivatives from the coherent sweep.
//!
//! Every derivative is per nm of the layer's thickness, layers top down.
//! The method and its checks are in docs/inverse.md.

mod coherent;
mod mixed;

use num_complex::Complex64 as C64;

use super::incoherent::Coherence;
use super::lanes;
use super::solver::{grazing, normal_index, sin_sq, solve_amplitudes, Amplitudes, Response};
use super::stack::{Stack, StackGrid};
use crate::error::Result;
pub use coherent::AmplitudeGradient;
use coherent::{recurse_media_gradient, Step};

/// The derivatives of one [`Response`] by one parameter of each layer (top
/// layer first): its thickness in nm where [`solve_with_gradient`] returns
/// it, its n or k in an [`IndexGradient`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ResponseGradient {
    /// ∂R_s/∂d_j.
    pub rs: Vec<f64>,
    /// ∂R_p/∂d_j.
    pub rp: Vec<f64>,
    /// ∂T_s/∂d_j.
    pub ts: Vec<f64>,
    /// ∂T_p/∂d_j.
    pub tp: Vec<f64>,
}

impl ResponseGradient {
    /// All derivatives zero, for `layers` layers.
    pub fn zeros(layers: usize) -> ResponseGradient {
        ResponseGradient {
            rs: vec![0.0; layers],
            rp: vec![0.0; layers],
            ts: vec![0.0; layers],
            tp: vec![0.0; layers],
        }
    }

    /// ∂R/∂d_j of unpolarized light.
    pub fn r(&self, layer: usize) -> f64 {
        0.5 * (self.rs[layer] + self.rp[layer])
    }

    /// ∂T/∂d_j of unpolarized light.
    pub fn t(&self, layer: usize) -> f64 {
        0.5 * (self.ts[layer] + self.tp[layer])
    }
}

/// The derivatives of one [`Response`] by a uniform shift of each layer's
/// complex refractive index N = n + ik (k > 0 absorbs): ∂/∂n and ∂/∂k at
/// fixed thicknesses, angle and wavelength. For a dispersive layer this is
/// the derivative by a shift of its whole n or k curve.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IndexGradient {
    /// ∂/∂n_j.
    pub n: ResponseGradient,
    /// ∂/∂k_j.
    pub k: ResponseGradient,
}

impl IndexGradient {
    /// All derivatives zero, for `layers` layers.
    pub fn zeros(layers: usize) -> IndexGradient {
        IndexGradient {
            n: ResponseGradient::zeros(layers),
            k: ResponseGradient::zeros(layers),
        }
    }
}

/// Scratch reused across the points of a grid
/// ([`solve_grid_point_with_gradient`]); `Workspace::default()` makes one.
#[derive(Default)]
pub struct Workspace {
    tape: Vec<Step>,
    amplitudes: Vec<AmplitudeGradient>,
    by_index: Vec<AmplitudeGradient>,
}

/// R and T of a coherent or mixed stack given as `indices` (ambient, N
/// layers, substrate) and N `thicknesses_nm`, with their derivatives by
/// each thickness: [`solve_incoherent`](super::solve_incoherent)'s
/// arguments and answer. Errors where an incoherent layer lases.
pub(crate) fn solve_indices_with_gradient(
    indices: &[C64],
    thicknesses_nm: &[f64],
    coherence: &Coherence,
    wavelength_nm: f64,
    cos_theta0: f64,
    work: &mut Workspace,
) -> std::result::Result<(Response, ResponseGradient), super::Diverged> {
    if !coherence.is_coherent() {
        return mixed::solve_mixed_with_gradient(
            indices,
            thicknesses_nm,
            coherence,
            wavelength_nm,
            cos_theta0,
            &mut work.tape,
            false,
        )
        .map(|(response, gradient, _)| (response, gradient));
    }
    solve_indices_with_index_gradient(
        indices,
        thicknesses_nm,
        coherence,
        wavelength_nm,
        cos_theta0,
        work,
    )
    .map(|(response, gradient, _)| (response, gradient))
}

/// [`solve_indices_with_gradient`] with the derivatives by each layer's
/// n and k as well, from the same sweep.
pub(crate) fn solve_indices_with_index_gradient(
    indices: &[C64],
    thicknesses_nm: &[f64],
    coherence: &Coherence,
    wavelength_nm: f64,
    cos_theta0: f64,
    work: &mut Workspace,
) -> std::result::Result<(Response, ResponseGradient, IndexGradient), super::Diverged> {
    if !coherence.is_coherent() {
        return mixed::solve_mixed_with_gradient(
            indices,
            thicknesses_nm,
            coherence,
            wavelength_nm,
            cos_theta0,
            &mut work.tape,
            true,
        );
    }
    let layers = thicknesses_nm.len();
    if cos_theta0 <= 0.0 {
        return Ok((
            grazing(indices),
            ResponseGradient::zeros(layers),
            IndexGradient::zeros(layers),
        ));
    }
    let cos_theta0 = cos_theta0.min(1.0);
    let n0 = indices[0].re;
    let top = [
        C64::new(n0, 0.0),
        C64::new(n0 * n0, 0.0),
        C64::new(n0 * cos_theta0, 0.0),
    ];
    let beta_sq = n0 * n0 * sin_sq(cos_theta0);
    let q_sub = normal_index(indices[layers + 1], beta_sq);
    work.amplitudes.clear();
    work.amplitudes.resize(layers, AmplitudeGradient::default());
    work.by_index.clear();
    work.by_index
        .resize(layers + 2, AmplitudeGradient::default());
    let amp = recurse_media_gradient(
        layers + 2,
        |j| indices[j],
        |j| thicknesses_nm[j],
        wavelength_nm,
        beta_sq,
        top,
        q_sub,
        &mut work.tape,
        (&mut work.amplitudes, &mut work.by_index),
    );
    let response = super::solver::power(indices, cos_theta0, &amp);
    let mut gradient = ResponseGradient::zeros(layers);
    for (l, d) in work.amplitudes.iter().enumerate() {
        gradient.rs[l] = 2.0 * (amp.rs.conj() * d.rs).re;
        gradient.rp[l] = 2.0 * (amp.rp.conj() * d.rp).re;
        gradient.ts[l] = 2.0 * response.ts * d.log_ts.re;
        gradient.tp[l] = 2.0 * response.tp * d.log_tp.re;
    }
    // R and log t are holomorphic in N, so ∂/∂n = d/dN and ∂/∂k = i d/dN.
    let mut by_index = IndexGradient::zeros(layers);
    for (l, d) in work.by_index[1..=layers].iter().enumerate() {
        for (out, turn) in [(&mut by_index.n, ONE), (&mut by_index.k, I)] {
            out.rs[l] = 2.0 * (amp.rs.conj() * turn * d.rs).re;
            out.rp[l] = 2.0 * (amp.rp.conj() * turn * d.rp).re;
            out.ts[l] = 2.0 * response.ts * (turn * d.log_ts).re;
            out.tp[l] = 2.0 * response.tp * (turn * d.log_tp).re;
        }
    }
    Ok((response, gradient, by_index))
}

const ONE: C64 = C64::new(1.0, 0.0);
const I: C64 = C64::new(0.0, 1.0);

/// One stack (coherent or mixed/incoherent layers) at one wavelength and
/// cos θ0: R and T, and their derivatives by each layer's thickness in nm.
/// Fails, naming the layer, where an incoherent gain layer lases.
pub fn solve_with_gradient(
    stack: &Stack,
    wavelength_nm: f64,
    cos_theta0: f64,
) -> Result<(Response, ResponseGradient)> {
    stack.validate()?;
    let mut indices = Vec::with_capacity(stack.layers.len() + 2);
    stack.indices_at(wavelength_nm, &mut indices)?;
    solve_indices_with_gradient(
        &indices,
        &stack.thicknesses_nm(),
        &stack.coherence(),
        wavelength_nm,
        cos_theta0,
        &mut Workspace::default(),
    )
    .map_err(|d| d.error(wavelength_nm, cos_theta0))
}

/// R, T and their thickness derivatives over a wavelength × angle grid.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GradientGrid {
    /// N, the number of layers.
    pub layers: usize,
    /// The number of wavelengths.
    pub wavelengths: usize,
    /// The number of angles.
    pub angles: usize,
    /// R and T of wavelength w, angle a at `[w * angles + a]`.
    pub response: Vec<Response>,
    /// A coherent stack's r and t, laid out as `response` (the same forward
    /// sweep's, as [`solve_amplitudes`] gives them); empty for a stack with
    /// incoherent layers, whose phases are averaged out.
    pub amplitudes: Vec<Amplitudes>,
    /// ∂R_s/∂d of layer l (top down) at wavelength w, angle a at
    /// `[(l * wavelengths + w) * angles + a]`; likewise the others.
    pub d_rs: Vec<f64>,
    /// ∂R_p/∂d, laid out as `d_rs`.
    pub d_rp: Vec<f64>,
    /// ∂T_s/∂d, laid out as `d_rs`.
    pub d_ts: Vec<f64>,
    /// ∂T_p/∂d, laid out as `d_rs`.
    pub d_tp: Vec<f64>,
    /// ∂R_s, ∂R_p, ∂T_s, ∂T_p by each layer's n, each laid out as `d_rs`:
    /// filled by [`solve_stack_grid_with_index_gradient`], empty otherwise.
    pub by_n: [Vec<f64>; 4],
    /// The same by each layer's k.
    pub by_k: [Vec<f64>; 4],
}

impl GradientGrid {
    /// The position of (layer, wavelength, angle) in the `d_*` arrays.
    #[inline]
    pub fn at(&self, layer: usize, wavelength: usize, angle: usize) -> usize {
        (layer * self.wavelengths + wavelength) * self.angles + angle
    }

    fn zeros(layers: usize, wavelengths: usize, angles: usize, coherent: bool) -> GradientGrid {
        let points = wavelengths * angles;
        let zero = C64::new(0.0, 0.0);
        let no_amplitudes = Amplitudes {
            rs: zero,
            rp: zero,
            ts: zero,
            tp: zero,
        };
        GradientGrid {
            layers,
            wavelengths,
            angles,
            response: vec![Response::default(); points],
            amplitudes: vec![no_amplitudes; if coherent { points } else { 0 }],
            d_rs: vec![0.0; layers * points],
            d_rp: vec![0.0; layers * points],
            d_ts: vec![0.0; layers * points],
            d_tp: vec![0.0; layers * points],
            by_n: Default::default(),
            by_k: Default::default(),
        }
    }
}

/// R and T of `stack` at every (wavelength, cos θ0) pair with their
/// derivatives by every layer's thickness ([`GradientGrid`]'s layout).
/// Fails, naming the layer, where an incoherent gain layer lases.
pub fn solve_grid_with_gradient(
    stack: &Stack,
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
) -> Result<GradientGrid> {
    let grid = StackGrid::new(stack, wavelengths_nm)?;
    solve_stack_grid_with_gradient(&grid, grid.thicknesses_nm(), cos_theta0)
}

/// [`solve_grid_with_gradient`] over a [`StackGrid`] whose indices are
/// already evaluated, with the layer thicknesses given (e.g. the grid's
/// own with some varied), as a fit iterates.
///
/// # Panics
/// If `thicknesses_nm` does not have one thickness per layer of the grid.
pub fn solve_stack_grid_with_gradient(
    grid: &StackGrid,
    thicknesses_nm: &[f64],
    cos_theta0: &[f64],
) -> Result<GradientGrid> {
    solve_stack_grid_with_gradient_on(lanes::Path::Best, grid, thicknesses_nm, cos_theta0)
}

/// [`solve_stack_grid_with_gradient`] on a chosen copy of the lane kernel
/// (every point goes through the lanes, but for those at grazing incidence
/// or with a near-critical layer, and, in a mixed stack, those with an
/// opaque or lasing incoherent layer: these through the scalar gradient).
///
/// # Panics
/// If `thicknesses_nm` does not have one thickness per layer of the grid.
pub fn solve_stack_grid_with_gradient_on(
    path: lanes::Path,
    grid: &StackGrid,
    thicknesses_nm: &[f64],
    cos_theta0: &[f64],
) -> Result<GradientGrid> {
    let layers = grid.thicknesses_nm().len();
    assert_eq!(
        thicknesses_nm.len(),
        layers,
        "thicknesses_nm: one per layer"
    );
    let (wavelengths, angles) = (grid.wavelengths_nm().len(), cos_theta0.len());
    let coherent = grid.coherence().is_coherent();
    let mut out = GradientGrid::zeros(layers, wavelengths, angles, coherent);
    let mut work = Workspace::default();
    let mut points = Vec::new();
    {
        let GradientGrid {
            response,
            amplitudes,
            d_rs,
            d_rp,
            d_ts,
            d_tp,
            ..
        } = &mut out;
        let mut sink = lanes::GradientSink {
            response,
            amplitudes,
            d: [d_rs, d_rp, d_ts, d_tp],
            fallback: &mut points,
        };
        let args = (grid.indices(), thicknesses_nm, grid.wavelengths_nm());
        if coherent {
            lanes::gradient_grid_on(path, args.0, args.1, args.2, cos_theta0, &mut sink);
        } else {
            let coherence = grid.coherence();
            lanes::mixed_gradient_grid_on(
                path, args.0, args.1, coherence, args.2, cos_theta0, &mut sink,
            );
        }
    }
    for point in points {
        let (w, a) = (point / angles, point % angles);
        let (response, gradient) =
            solve_grid_point_with_gradient(grid, w, thicknesses_nm, cos_theta0[a], &mut work)?;
        out.response[point] = response;
        if coherent {
            let wavelength_nm = grid.wavelengths_nm()[w];
            out.amplitudes[point] = solve_amplitudes(
                grid.indices_at(w),
                thicknesses_nm,
                wavelength_nm,
                cos_theta0[a],
            );
        }
        for l in 0..layers {
            let i = out.at(l, w, a);
            out.d_rs[i] = gradient.rs[l];
            out.d_rp[i] = gradient.rp[l];
            out.d_ts[i] = gradient.ts[l];
            out.d_tp[i] = gradient.tp[l];
        }
    }
    Ok(out)
}

/// [`solve_stack_grid_with_gradient`] with the derivatives by every
/// layer's n and k as well ([`GradientGrid::by_n`], [`GradientGrid::by_k`]),
/// all from one reverse sweep per point on the scalar path (the lanes
/// differentiate thicknesses only).
///
/// # Panics
/// If `thicknesses_nm` does not have one thickness per layer of the grid.
pub fn solve_stack_grid_with_index_gradient(
    grid: &StackGrid,
    thicknesses_nm: &[f64],
    cos_theta0: &[f64],
) -> Result<GradientGrid> {
    let layers = grid.thicknesses_nm().len();
    assert_eq!(
        thicknesses_nm.len(),
        layers,
        "thicknesses_nm: one per layer"
    );
    let (wavelengths, angles) = (grid.wavelengths_nm().len(), cos_theta0.len());
    let coherent = grid.coherence().is_coherent();
    let mut out = GradientGrid::zeros(layers, wavelengths, angles, coherent);
    let size = out.d_rs.len();
    out.by_n = std::array::from_fn(|_| vec![0.0; size]);
    out.by_k = std::array::from_fn(|_| vec![0.0; size]);
    let mut work = Workspace::default();
    for w in 0..wavelengths {
        let wavelength_nm = grid.wavelengths_nm()[w];
        let indices = grid.indices_at(w);
        for (a, &c) in cos_theta0.iter().enumerate() {
            let (response, gradient, by_index) = solve_indices_with_index_gradient(
                indices,
                thicknesses_nm,
                grid.coherence(),
                wavelength_nm,
                c,
                &mut work,
            )
            .map_err(|d| d.error(wavelength_nm, c))?;
            let point = w * angles + a;
            out.response[point] = response;
            if coherent {
                out.amplitudes[point] = solve_amplitudes(indices, thicknesses_nm, wavelength_nm, c);
            }
            for l in 0..layers {
                let i = out.at(l, w, a);
                let parts = |g: &ResponseGradient| [g.rs[l], g.rp[l], g.ts[l], g.tp[l]];
                let [rs, rp, ts, tp] = parts(&gradient);
                (out.d_rs[i], out.d_rp[i], out.d_ts[i], out.d_tp[i]) = (rs, rp, ts, tp);
                for (q, (dn, dk)) in parts(&by_index.n)
                    .into_iter()
                    .zip(parts(&by_index.k))
                    .enumerate()
                {
                    out.by_n[q][i] = dn;
                    out.by_k[q][i] = dk;
                }
            }
        }
    }
    Ok(out)
}

/// [`solve_with_gradient`] with the derivatives by each layer's n and k
/// ([`IndexGradient`]) from the same sweep.
pub fn solve_with_index_gradient(
    stack: &Stack,
    wavelength_nm: f64,
    cos_theta0: f64,
) -> Result<(Response, ResponseGradient, IndexGradient)> {
    stack.validate()?;
    let mut indices = Vec::with_capacity(stack.layers.len() + 2);
    stack.indices_at(wavelength_nm, &mut indices)?;
    solve_indices_with_index_gradient(
        &indices,
        &stack.thicknesses_nm(),
        &stack.coherence(),
        wavelength_nm,
        cos_theta0,
        &mut Workspace::default(),
    )
    .map_err(|d| d.error(wavelength_nm, cos_theta0))
}

/// R, T and their derivatives at the `w`-th wavelength of `grid` and cos θ0
/// `cos_theta0`, with the layer thicknesses given: one point of
/// [`solve_stack_grid_with_gradient`], for callers that spread a grid's
/// points over threads (one [`Workspace`] each).
///
/// # Panics
/// If `thicknesses_nm` does not have one thickness per layer of the grid.
pub fn solve_grid_point_with_gradient(
    grid: &StackGrid,
    w: usize,
    thicknesses_nm: &[f64],
    cos_theta0: f64,
    work: &mut Workspace,
) -> Result<(Response, ResponseGradient)> {
    assert_eq!(
        thicknesses_nm.len(),
        grid.thicknesses_nm().len(),
        "thicknesses_nm: one per layer"
    );
    let wavelength_nm = grid.wavelengths_nm()[w];
    solve_indices_with_gradient(
        grid.indices_at(w),
        thicknesses_nm,
        grid.coherence(),
        wavelength_nm,
        cos_theta0,
        work,
    )
    .map_err(|d| d.error(wavelength_nm, cos_theta0))
}

#[cfg(test)]
mod tests;
