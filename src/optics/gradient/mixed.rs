//! The derivative of the incoherent recursion ([`climb`]) of a whole stack
//! with respect to every layer's thickness, in forward mode at the power
//! level: each coherent group's amplitude derivatives come from the taped
//! coherent recursion, and ρ, τ carry one derivative per layer up through
//! [`through_layer`]'s sums. There are as many groups as incoherent layers
//! plus one, so this costs about two coherent sweeps of the stack plus
//! N per group.
//!
//! [`climb`]: super::super::incoherent::climb
//! [`through_layer`]: super::super::incoherent::through_layer

use num_complex::Complex64 as C64;

use super::super::incoherent::{
    carrying_index, flux_factors, one_pass, solve_incoherent, through_layer, Coherence, Diverged,
    Light,
};
use super::super::solver::{grazing, sqrt_upper, Amplitudes, Response};
use super::coherent::{recurse_media_gradient, AmplitudeGradient, Step};
use super::{IndexGradient, ResponseGradient};

/// ρ and τ of one polarization and their derivatives by every parameter:
/// each layer's thickness (`0..N`), n (`N..2N`) and k (`2N..3N`).
struct Sums {
    rho: f64,
    tau: f64,
    d_rho: Vec<f64>,
    d_tau: Vec<f64>,
}

/// d|r|² from r and dr; d|t|² from |t|² and d log t.
fn d_norm_sqr(r: C64, dr: C64) -> f64 {
    2.0 * (r.conj() * dr).re
}

/// One coherent group (stack media `top..=bottom`) from above and from
/// below, with the derivatives of both by each parameter it depends on:
/// (parameter, from above, from below).
struct Group {
    down: Amplitudes,
    up: Amplitudes,
    own: Vec<(usize, AmplitudeGradient, AmplitudeGradient)>,
}

/// `d` turned by i: the derivative by k from the one by N.
fn times_i(d: &AmplitudeGradient) -> AmplitudeGradient {
    let i = C64::new(0.0, 1.0);
    AmplitudeGradient {
        rs: i * d.rs,
        rp: i * d.rp,
        log_ts: i * d.log_ts,
        log_tp: i * d.log_tp,
    }
}

fn group(
    indices: &[C64],
    thicknesses_nm: &[f64],
    (top, bottom): (usize, usize),
    light: &Light,
    (top_medium, bottom_medium): ([C64; 3], [C64; 3]),
    tape: &mut Vec<Step>,
    with_index: bool,
) -> Group {
    let media = bottom - top + 1;
    let layers = thicknesses_nm.len();
    let mut d_down = vec![AmplitudeGradient::default(); media - 2];
    let mut d_up = d_down.clone();
    let mut n_down = vec![AmplitudeGradient::default(); media];
    let mut n_up = n_down.clone();
    let down = recurse_media_gradient(
        media,
        |j| indices[top + j],
        |j| thicknesses_nm[top + j],
        light.wavelength_nm,
        light.beta_sq,
        top_medium,
        bottom_medium[2],
        tape,
        (&mut d_down, &mut n_down),
    );
    let up = recurse_media_gradient(
        media,
        |j| indices[bottom - j],
        |j| thicknesses_nm[bottom - j - 2],
        light.wavelength_nm,
        light.beta_sq,
        bottom_medium,
        top_medium[2],
        tape,
        (&mut d_up, &mut n_up),
    );
    d_up.reverse();
    n_up.reverse();
    let mut own: Vec<_> = (d_down.into_iter().zip(d_up).enumerate())
        .map(|(i, (d, u))| (top + i, d, u))
        .collect();
    // Medium top + j is layer top + j − 1; the ambient and substrate have
    // no parameters.
    for (j, (d, u)) in n_down.iter().zip(&n_up).enumerate() {
        let medium = top + j;
        if !with_index || medium == 0 || medium > layers {
            continue;
        }
        own.push((layers + medium - 1, *d, *u));
        own.push((2 * layers + medium - 1, times_i(d), times_i(u)));
    }
    Group { down, up, own }
}

/// [`solve_incoherent`](super::super::solve_incoherent) with the
/// derivative of R and T (s and p) by each layer's thickness, and by its
/// n and k when `with_index` (else those come back zero, and the sums
/// carry a third of the parameters).
pub(crate) fn solve_mixed_with_gradient(
    indices: &[C64],
    thicknesses_nm: &[f64],
    coherence: &Coherence,
    wavelength_nm: f64,
    cos_theta0: f64,
    tape: &mut Vec<Step>,
    with_index: bool,
) -> Result<(Response, ResponseGradient, IndexGradient), Diverged> {
    let layers = thicknesses_nm.len();
    if cos_theta0 <= 0.0 {
        return Ok((
            grazing(indices),
            ResponseGradient::zeros(layers),
            IndexGradient::zeros(layers),
        ));
    }
    let light = Light::new(wavelength_nm, indices[0].re, cos_theta0.min(1.0));
    let n_sub = indices[layers + 1];
    let q_sub = sqrt_upper(light.normal_index_sq(n_sub));
    let n0 = C64::new(light.n0, 0.0);
    let top_medium = [n0, n0 * n0, C64::new(light.q0, 0.0)];

    let (mut below, mut n_below, mut q_below) = (layers + 1, n_sub, q_sub);
    let mut state: Option<[Sums; 2]> = None;
    let mut opaque = false;
    let incoherent = coherence.incoherent_layers();
    for &m in incoherent.iter().rev().chain(std::iter::once(&0)) {
        let (n, q) = if m == 0 {
            (top_medium[0], top_medium[2])
        } else {
            let n = indices[m];
            let z = light.normal_index_sq(n);
            match carrying_index(n, z) {
                Some(q) => (n, q),
                None => {
                    (state, opaque) = (None, true);
                    (below, n_below, q_below) = (m, n, sqrt_upper(z));
                    continue;
                }
            }
        };
        let top = if m == 0 { top_medium } else { [n, n * n, q] };
        let g = group(
            indices,
            thicknesses_nm,
            (m, below),
            &light,
            (top, [n_below, n_below * n_below, q_below]),
            tape,
            with_index,
        );
        state = Some(match state {
            None => first_sums(&g, if with_index { 3 * layers } else { layers }),
            Some([s, p]) => {
                let (pass, d_pass) = pass_with_derivatives(
                    light.k0,
                    (n_below, q_below),
                    (below - 1, thicknesses_nm[below - 1]),
                    if with_index { layers } else { 0 },
                );
                let cross = Crossing {
                    group: &g,
                    pass,
                    d_pass,
                    layer: below,
                };
                [cross.sums(s, Pol::S)?, cross.sums(p, Pol::P)?]
            }
        });
        (below, n_below, q_below) = (m, n, q);
    }
    let [s, p] = state.expect("the ambient closes the recursion");
    let [flux_s, flux_p] = if opaque {
        [0.0, 0.0]
    } else {
        flux_factors(n_sub, q_sub, light.q0)
    };
    let response = Response {
        rs: s.rho,
        rp: p.rho,
        ts: s.tau * flux_s,
        tp: p.tau * flux_p,
    };
    if !response.is_finite() {
        // Finite round trips whose gain still overflows the sum: the
        // forward solver names the layer.
        let diverged = solve_incoherent(
            indices,
            thicknesses_nm,
            coherence,
            wavelength_nm,
            cos_theta0,
        )
        .err()
        .unwrap_or(Diverged {
            layer: incoherent[0],
            round_trip: f64::INFINITY,
        });
        return Err(diverged);
    }
    let (gradient, by_index) = split_parameters(&s, &p, layers, [flux_s, flux_p]);
    Ok((response, gradient, by_index))
}

/// An incoherent layer's pass P = e^{−2 k0 d Im q} (layer `l`, thickness
/// `d`, index N and q) and its derivatives by the layer's thickness, and by
/// its n and k when `layers` (the stack's count) is not 0: dq/dN = N/q and
/// ∂/∂k = i ∂/∂N. Unused entries name parameter usize::MAX, which is none.
fn pass_with_derivatives(
    k0: f64,
    (n, q): (C64, C64),
    (l, d): (usize, f64),
    layers: usize,
) -> (f64, [(usize, f64); 3]) {
    let pass = one_pass(k0, q, d);
    let dq = n / q;
    let decay = -2.0 * k0 * pass;
    let (n_at, k_at) = if layers > 0 {
        (layers + l, 2 * layers + l)
    } else {
        (usize::MAX, usize::MAX)
    };
    (
        pass,
        [
            (l, decay * q.im),
            (n_at, decay * d * dq.im),
            (k_at, decay * d * dq.re),
        ],
    )
}

/// The per-parameter derivatives of the top sums as R and T derivatives:
/// the thickness block, and the n and k blocks, τ's times the flux factors.
fn split_parameters(
    s: &Sums,
    p: &Sums,
    layers: usize,
    [flux_s, flux_p]: [f64; 2],
) -> (ResponseGradient, IndexGradient) {
    let block = |v: &[f64], b: usize, scale: f64| -> Vec<f64> {
        match v.get(b * layers..(b + 1) * layers) {
            Some(part) => part.iter().map(|d| d * scale).collect(),
            None => vec![0.0; layers],
        }
    };
    let gradient_of = |b: usize| ResponseGradient {
        rs: block(&s.d_rho, b, 1.0),
        rp: block(&p.d_rho, b, 1.0),
        ts: block(&s.d_tau, b, flux_s),
        tp: block(&p.d_tau, b, flux_p),
    };
    let by_index = IndexGradient {
        n: gradient_of(1),
        k: gradient_of(2),
    };
    (gradient_of(0), by_index)
}

/// ρ and τ seen from the incoherent medium above the lowest group (the
/// group's own |r|² and |t|²), with their derivatives by its parameters
/// (`params` of them).
fn first_sums(g: &Group, params: usize) -> [Sums; 2] {
    let start = |r: C64, t: C64| Sums {
        rho: r.norm_sqr(),
        tau: t.norm_sqr(),
        d_rho: vec![0.0; params],
        d_tau: vec![0.0; params],
    };
    let mut sums = [start(g.down.rs, g.down.ts), start(g.down.rp, g.down.tp)];
    for (l, d, _) in &g.own {
        sums[0].d_rho[*l] += d_norm_sqr(g.down.rs, d.rs);
        sums[0].d_tau[*l] += 2.0 * sums[0].tau * d.log_ts.re;
        sums[1].d_rho[*l] += d_norm_sqr(g.down.rp, d.rp);
        sums[1].d_tau[*l] += 2.0 * sums[1].tau * d.log_tp.re;
    }
    sums
}

#[derive(Clone, Copy)]
enum Pol {
    S,
    P,
}

/// Crossing an incoherent layer and the group above it.
struct Crossing<'a> {
    group: &'a Group,
    pass: f64,
    /// The derivatives of P by the parameters it depends on: the layer's
    /// thickness, n and k.
    d_pass: [(usize, f64); 3],
    /// The incoherent layer's number (1-based), for [`Diverged`].
    layer: usize,
}

impl Crossing<'_> {
    /// ρ' = A + B P²ρ/(1 − C P²ρ), τ' = E P τ/(1 − C P²ρ), with A = |r|²,
    /// B = |t t'|², C = |r'|², E = |t|² of the group, and their derivatives.
    fn sums(&self, sums: Sums, pol: Pol) -> Result<Sums, Diverged> {
        let g = self.group;
        let pick = |a: &Amplitudes| match pol {
            Pol::S => (a.rs, a.ts),
            Pol::P => (a.rp, a.tp),
        };
        let pick_d = |d: &AmplitudeGradient| match pol {
            Pol::S => (d.rs, d.log_ts),
            Pol::P => (d.rp, d.log_tp),
        };
        let (r, t) = pick(&g.down);
        let (r_up, t_up) = pick(&g.up);
        let (rho, tau) = through_layer(
            (sums.rho, sums.tau),
            (r, t),
            (r_up, t_up),
            self.pass,
            self.layer,
        )?;
        let (b, c, e) = ((t * t_up).norm_sqr(), r_up.norm_sqr(), t.norm_sqr());
        let (p, rho0, tau0) = (self.pass, sums.rho, sums.tau);
        let returned = p * p * rho0;
        let inv = 1.0 / (1.0 - c * returned);
        // Derivatives through ρ, τ below and through P.
        let mut d_rho = sums.d_rho;
        let mut d_tau = sums.d_tau;
        for l in 0..d_rho.len() {
            let d_p = self
                .d_pass
                .iter()
                .find(|(k, _)| *k == l)
                .map_or(0.0, |(_, d)| *d);
            let d_returned = p * p * d_rho[l] + 2.0 * p * d_p * rho0;
            let dr = b * d_returned * inv * inv;
            let dt = (e * d_p * tau0 + e * p * d_tau[l]) * inv
                + e * p * tau0 * inv * inv * c * d_returned;
            d_rho[l] = dr;
            d_tau[l] = dt;
        }
        // Derivatives through the group's own amplitudes.
        for (l, dd, du) in &g.own {
            let (dr, dlt) = pick_d(dd);
            let (dr_up, dlt_up) = pick_d(du);
            let da = d_norm_sqr(r, dr);
            let db = 2.0 * b * (dlt + dlt_up).re;
            let dc = d_norm_sqr(r_up, dr_up);
            let de = 2.0 * e * dlt.re;
            d_rho[*l] += da + db * returned * inv + b * returned * returned * dc * inv * inv;
            d_tau[*l] += de * p * tau0 * inv + e * p * tau0 * inv * inv * dc * returned;
        }
        Ok(Sums {
            rho,
            tau,
            d_rho,
            d_tau,
        })
    }
}
