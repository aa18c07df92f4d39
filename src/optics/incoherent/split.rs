//! A stack with incoherent layers split around one coherent layer, for the
//! baker's thickness sweep: the layer's coherent group (between the nearest
//! incoherent media above and below it) split as the coherent two-port
//! splits a whole stack, and the incoherent power sums above and below the
//! group, which do not depend on the layer's thickness. The sweep then
//! forms the group's four power coefficients from the layer's phase factor
//! and closes the sums (see [`Surroundings`](crate::optics::twoport)).

use num_complex::Complex64 as C64;

use super::{carrying_index, climb, flux_factors, one_pass, sqrt_upper, Coherence, Light, View};
use crate::optics::solver::{normal_index, Amplitudes};

/// The parts of a split: the group's sub-stacks' amplitudes and what
/// surrounds the group, per polarization (s, p).
pub(crate) struct Parts {
    /// A (the group's top medium down to the varying layer's medium), from
    /// above and from below.
    pub(crate) above: Amplitudes,
    pub(crate) above_up: Amplitudes,
    /// B (the varying layer's medium down to the group's bottom medium),
    /// from above and from below.
    pub(crate) below: Amplitudes,
    pub(crate) below_up: Amplitudes,
    /// q of the varying layer.
    pub(crate) q_layer: C64,
    pub(crate) env: Env,
}

/// The incoherent sums around the group, per polarization. Above it (the
/// ambient down to the group's top medium, crossed once more): R = r +
/// tt ρ_g / (1 − rb ρ_g) and T = t τ_g / (1 − rb ρ_g), ρ_g and τ_g the
/// group's with everything below it. Below it: ρ_b and τ_b, seen from the
/// group's bottom medium, with its round trip and pass.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Env {
    pub(crate) r: [f64; 2],
    pub(crate) tt: [f64; 2],
    pub(crate) rb: [f64; 2],
    /// Includes the substrate's Poynting factor over the incident flux.
    pub(crate) t: [f64; 2],
    pub(crate) rho_below: [f64; 2],
    pub(crate) tau_below: [f64; 2],
}

/// Splits the stack around `layer` (1-based, coherent) at one wavelength
/// and cos θ0 in (0, 1]. `None` when the response does not depend on the
/// layer in this form: an opaque incoherent layer above it, or sums that
/// diverge (the baker then evaluates node by node, where the solver gives
/// the constant, or the lasing point).
pub(crate) fn split(
    indices: &[C64],
    thicknesses_nm: &[f64],
    coherence: &Coherence,
    layer: usize,
    wavelength_nm: f64,
    cos_theta0: f64,
) -> Option<Parts> {
    debug_assert!(coherence.is_layer_coherent(layer));
    let light = Light::new(wavelength_nm, indices[0].re, cos_theta0.min(1.0));
    let last = indices.len() - 1;
    let stack = View::stack(indices, thicknesses_nm);
    let incoherent = coherence.incoherent_layers();
    let (above, below): (Vec<usize>, Vec<usize>) = incoherent.iter().partition(|&&m| m < layer);

    // Every incoherent medium above must carry power, else nothing the
    // layer does reaches the ambient.
    let mut carried = Vec::with_capacity(above.len());
    for &m in &above {
        carried.push(carrying_index(
            indices[m],
            light.normal_index_sq(indices[m]),
        )?);
    }
    let n0 = C64::new(light.n0, 0.0);
    let ambient = [n0, n0 * n0, C64::new(light.q0, 0.0)];
    let (s, top) = match (above.last(), carried.last()) {
        (Some(&s), Some(&q)) => (s, [indices[s], indices[s] * indices[s], q]),
        _ => (0, ambient),
    };
    let n_sub = indices[last];
    let q_sub = sqrt_upper(light.normal_index_sq(n_sub));
    let e = below.first().copied().unwrap_or(last);
    let z_e = light.normal_index_sq(indices[e]);
    let (q_e, opaque_e) = if e == last {
        (q_sub, false)
    } else {
        carrying_index(indices[e], z_e).map_or((sqrt_upper(z_e), true), |q| (q, false))
    };
    let bottom = [indices[e], indices[e] * indices[e], q_e];
    let n_layer = indices[layer];
    let q_layer = normal_index(n_layer, light.beta_sq);
    let varying = [n_layer, n_layer * n_layer, q_layer];

    let reversed = View::stack(indices, thicknesses_nm).run(0, last, true);
    let parts = |env| Parts {
        above: stack.group(s, layer, &light, top, q_layer),
        above_up: reversed.group(last - layer, last - s, &light, varying, top[2]),
        below: stack.group(layer, e, &light, varying, q_e),
        below_up: reversed.group(last - e, last - layer, &light, bottom, q_layer),
        q_layer,
        env,
    };

    let flux = flux_factors(n_sub, q_sub, light.q0);
    let mut env = Env {
        r: [0.0; 2],
        tt: [1.0; 2],
        rb: [0.0; 2],
        t: flux,
        rho_below: [0.0; 2],
        tau_below: [1.0; 2],
    };
    if s > 0 {
        let thickness_nm = thicknesses_nm[s - 1];
        above_sums(
            stack,
            &above,
            &light,
            (ambient, top),
            s,
            thickness_nm,
            &mut env,
        )?;
    }
    if e < last {
        if opaque_e {
            env.tau_below = [0.0; 2];
        } else {
            let from = climb(
                stack.run(e, last, false),
                below[1..].iter().map(|m| m - e),
                &light,
                bottom,
                q_sub,
            )
            .ok()?;
            let pass = one_pass(light.k0, q_e, thicknesses_nm[e - 1]);
            for (k, &(rho, tau)) in from.sums.iter().enumerate() {
                env.rho_below[k] = rho * pass * pass;
                env.tau_below[k] = if from.opaque { 0.0 } else { tau * pass };
            }
        }
    }
    Some(parts(env))
}

/// The sums of the stack above the incoherent medium `s` (the last one
/// above the varying layer, `thickness_nm` thick), climbed down and up
/// through the incoherent media of `above` over it, with the passes
/// through `s`, into `env` (whose `t` holds the substrate's flux factors
/// on entry). `None` when a sum diverges.
fn above_sums(
    stack: View,
    above: &[usize],
    light: &Light,
    (ambient, top): ([C64; 3], [C64; 3]),
    s: usize,
    thickness_nm: f64,
    env: &mut Env,
) -> Option<()> {
    let inner = |&m: &usize| (m < s).then_some(m);
    let down = climb(
        stack.run(0, s, false),
        above.iter().filter_map(inner),
        light,
        ambient,
        top[2],
    )
    .ok()?;
    let up = climb(
        stack.run(0, s, true),
        above.iter().rev().filter_map(inner).map(|m| s - m),
        light,
        top,
        ambient[2],
    )
    .ok()?;
    let pass = one_pass(light.k0, top[2], thickness_nm);
    let flux = env.t;
    let sums = down.sums.iter().zip(&up.sums).zip(&flux);
    for (k, ((&(r, t), &(rb, tb)), flux)) in sums.enumerate() {
        env.r[k] = r;
        env.tt[k] = t * tb * pass * pass;
        env.rb[k] = rb * pass * pass;
        env.t[k] = t * pass * flux;
    }
    Some(())
}
