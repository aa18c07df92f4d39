//! Stacks with incoherent layers in lanes: the point solver's recursion
//! ([`solve_incoherent`](crate::optics::incoherent::solve_incoherent)) on
//! one (wavelength, angle) pair per lane, each coherent group solved by the
//! general kernel's recursion ([`recurse_lanes`]) over a view of the stack,
//! top down or bottom up. Its results go to the same sinks as the coherent
//! kernels', so a spectrum folded into a colour has the bits of integrating
//! the stored one.
//!
//! What the lanes do not cover is handed, lane by lane, to the point solver,
//! which then gives that lane's answer: grazing incidence; a layer at or
//! near its critical angle inside a group; a lossless incoherent layer
//! beyond its critical angle (opaque); and a point where an incoherent
//! layer lases or a sum overflows (the point solver's +∞).

use num_complex::Complex64 as C64;

use super::arith::{exp_any, sqrt_upper, Cv, Lanes, MAX_LANES};
use super::general::{grid_lanes, recurse_lanes, Amplitudes, Gathered, Laid, MediaLanes};
use super::sink::{Power, Sink, Store};
use super::spectrum::{Repeats, Spectrum, SHARED_SLOTS};
use crate::optics::incoherent::{solve_mixed, Coherence};
use crate::optics::solver::Response;

/// Media `first..=last` of a stack as the lanes read them, top down, or
/// bottom up when `reversed` (the view's medium 0 is then `last`).
struct Run<'a, M> {
    media: &'a M,
    first: usize,
    last: usize,
    reversed: bool,
}

impl<V: Lanes, M: MediaLanes<V>> MediaLanes<V> for Run<'_, M> {
    #[inline(always)]
    fn medium(&self, j: usize) -> (Cv<V>, Cv<V>) {
        self.media.medium(if self.reversed {
            self.last - j
        } else {
            self.first + j
        })
    }
}

/// n² − β² as the point solver forms it for the substrate and incoherent
/// media: (n² − n0²) + q0².
#[inline(always)]
pub(super) fn normal_index_sq<V: Lanes>(nsq: Cv<V>, n0_sq: V, q0_sq: V) -> Cv<V> {
    Cv {
        re: nsq.re.sub(n0_sq).add(q0_sq),
        im: nsq.im,
    }
}

/// What every group's recursion shares: 2π/λ and β² in lanes.
struct Light<V> {
    k0: V,
    beta_sq: V,
    /// No media share a q inside a group: the recursion computes each.
    shared: [Cv<V>; SHARED_SLOTS],
}

/// ρ and τ of both polarizations (the point solver's `climb` state).
type Sums<V> = [(V, V); 2];

/// The point solver's `through_layer` for one polarization: `down` the
/// group's r, t from above, `up` its r', t' from below, `pass` the layer's
/// P. Returns the new (ρ, τ) and the lanes where the sum converges.
#[inline(always)]
pub(super) fn through_layer<V: Lanes>(
    (rho, tau): (V, V),
    (down_r, down_t): (Cv<V>, Cv<V>),
    (up_r, up_t): (Cv<V>, Cv<V>),
    pass: V,
) -> ((V, V), u32) {
    let one = V::splat(1.0);
    let returned = pass.mul(pass).mul(rho);
    let round_trip = up_r.norm_sqr().mul(returned);
    let converges =
        V::bits(round_trip.lt(one)) & V::bits(returned.abs().lt(V::splat(f64::INFINITY)));
    let inv = one.div(one.sub(round_trip));
    let rho = down_r
        .norm_sqr()
        .add(down_t.mul(up_t).norm_sqr().mul(returned).mul(inv));
    let tau = down_t.norm_sqr().mul(pass).mul(tau).mul(inv);
    ((rho, tau), converges)
}

/// The incoherent medium `m` as the top of a group: its index, the index
/// squared and its normal index on the branch that carries power forward
/// (Re q > 0); and the lanes (bits) where it is lossless and evanescent,
/// so opaque: the point solver's case.
#[inline(always)]
pub(super) fn incoherent_top<V: Lanes>(
    media: &impl MediaLanes<V>,
    m: usize,
    n0_sq: V,
    q0_sq: V,
) -> ([Cv<V>; 3], u32) {
    let zero = V::splat(0.0);
    let (n, nsq) = media.medium(m);
    let z = normal_index_sq(nsq, n0_sq, q0_sq);
    let opaque = V::bits(n.im.eq(zero)) & !V::bits(zero.lt(z.re)) & V::ALL;
    let q = sqrt_upper(z);
    let flip = q.re.lt(zero);
    let q = Cv {
        re: V::select(flip, q.re.neg(), q.re),
        im: V::select(flip, q.im.neg(), q.im),
    };
    ([n, nsq, q], opaque)
}

/// Solves one (wavelength, angle) pair of a stack with incoherent layers
/// per lane; `media`, `k0` and `lane_point` as for the general kernel.
#[inline(always)]
fn solve_lanes<'a, V: Lanes>(
    media: &impl MediaLanes<V>,
    k0: V,
    lane_point: impl Fn(usize) -> (&'a [C64], f64),
    thicknesses_nm: &[f64],
    coherence: &Coherence,
    cos_theta0: [f64; MAX_LANES],
) -> Power<V> {
    let last = thicknesses_nm.len() + 1;
    let (zero, one) = (V::splat(0.0), V::splat(1.0));
    // Lanes the point solver takes over (bits).
    let mut scalar = cos_theta0[..V::WIDTH]
        .iter()
        .enumerate()
        .fold(0u32, |b, (l, &c)| {
            b | (u32::from(c.is_nan() || c <= 0.0) << l)
        });
    let cos = V::from_array(cos_theta0.map(|c| c.min(1.0)));
    let n0 = media.medium(0).0.re;
    let q0 = n0.mul(cos);
    let light = Light {
        k0,
        beta_sq: n0.mul(n0).mul(one.sub(cos).mul(one.add(cos))),
        shared: [Cv::real(zero); SHARED_SLOTS],
    };
    let (n0_sq, q0_sq) = (n0.mul(n0), q0.mul(q0));
    let (n_sub, nsq_sub) = media.medium(last);
    let q_sub = sqrt_upper(normal_index_sq(nsq_sub, n0_sq, q0_sq));

    // The recursion climbs from the substrate, one group at a time: the
    // incoherent medium at the bottom of the group being added.
    let mut below = last;
    let mut bottom = [n_sub, nsq_sub, q_sub];
    let mut state: Option<Sums<V>> = None;
    let incoherent = coherence.incoherent_layers().iter().rev().copied();
    for m in incoherent.chain(std::iter::once(0)) {
        let top = if m == 0 {
            [Cv::real(n0), Cv::real(n0_sq), Cv::real(q0)]
        } else {
            let (top, opaque) = incoherent_top(media, m, n0_sq, q0_sq);
            scalar |= opaque;
            top
        };
        let (down, near) = group(
            media,
            &light,
            thicknesses_nm,
            (m, below, false),
            top,
            bottom,
        );
        scalar |= near;
        state = Some(match state {
            None => [
                (down.gamma_s.norm_sqr(), down.ts.norm_sqr()),
                (down.gamma_p.norm_sqr(), down.tp.norm_sqr()),
            ],
            Some([s, p]) => {
                let (up, near) =
                    group(media, &light, thicknesses_nm, (m, below, true), bottom, top);
                let d = V::splat(thicknesses_nm[below - 1]);
                let pass = exp_any(V::splat(-2.0).mul(k0.mul(d)).mul(bottom[2].im));
                let (s, ok_s) =
                    through_layer(s, (down.gamma_s, down.ts), (up.gamma_s, up.ts), pass);
                let (p, ok_p) =
                    through_layer(p, (down.gamma_p, down.tp), (up.gamma_p, up.tp), pass);
                scalar |= near | (!(ok_s & ok_p) & V::ALL);
                [s, p]
            }
        });
        below = m;
        bottom = top;
    }
    let [(rs, ts), (rp, tp)] = state.expect("the ambient closes the recursion");
    let conj_q = Cv {
        re: q_sub.re,
        im: q_sub.im.neg(),
    };
    let p_flux = conj_q.mul(n_sub).mul(n_sub).re.div(n_sub.norm_sqr());
    let out = Power {
        rs,
        rp,
        ts: ts.mul(q_sub.re).div(q0),
        tp: tp.mul(p_flux).div(q0),
    };
    let inf = V::splat(f64::INFINITY);
    for x in [out.rs, out.rp, out.ts, out.tp] {
        scalar |= !V::bits(x.abs().lt(inf)) & V::ALL;
    }
    if scalar == 0 {
        return out;
    }
    let mut res = out.responses();
    for (l, r) in res.iter_mut().enumerate().take(V::WIDTH) {
        if scalar & (1 << l) != 0 {
            let (indices, wavelength_nm) = lane_point(l);
            *r = solve_mixed(
                indices,
                thicknesses_nm,
                coherence,
                wavelength_nm,
                cos_theta0[l],
            );
        }
    }
    Power::from_responses(&res)
}

/// The amplitudes of the coherent group between media `top` and `bottom`
/// (`run`: their positions, `top` < `bottom`, and whether it is read from
/// the bottom up, the first medium given being then the bottom one), with
/// `first` and `end` the (n, n², q) of the media the recursion starts and
/// ends at; and the lanes where a layer in it is near its critical angle.
#[inline(always)]
fn group<V: Lanes>(
    media: &impl MediaLanes<V>,
    light: &Light<V>,
    thicknesses_nm: &[f64],
    (top, bottom, reversed): (usize, usize, bool),
    first: [Cv<V>; 3],
    end: [Cv<V>; 3],
) -> (Amplitudes<V>, u32) {
    let run = Run {
        media,
        first: top,
        last: bottom,
        reversed,
    };
    let thickness = |j: usize| {
        V::splat(if reversed {
            thicknesses_nm[bottom - j - 2]
        } else {
            thicknesses_nm[top + j]
        })
    };
    recurse_lanes(
        &run,
        (&Repeats::NONE, &light.shared),
        bottom - top,
        thickness,
        (light.k0, light.beta_sq),
        first,
        end,
    )
}

/// Every wavelength of `spectrum` at one angle, [`Lanes::WIDTH`] per vector,
/// handed to `sink` in order.
#[inline(always)]
pub(super) fn spectrum_body<V: Lanes>(
    spectrum: &Spectrum,
    indices: &[C64],
    thicknesses_nm: &[f64],
    coherence: &Coherence,
    cos_theta0: f64,
    sink: &mut impl Sink<V>,
) {
    let media = spectrum.media();
    let total = spectrum.wavelengths();
    for start in (0..total).step_by(V::WIDTH) {
        let laid = Laid { spectrum, start };
        let point = |l: usize| {
            let w = (start + l).min(total - 1);
            (
                &indices[w * media..(w + 1) * media],
                spectrum.wavelengths_nm()[w],
            )
        };
        let res = solve_lanes::<V>(
            &laid,
            V::load(&spectrum.k0()[start..]),
            point,
            thicknesses_nm,
            coherence,
            [cos_theta0; MAX_LANES],
        );
        sink.take(start, &res);
    }
}

/// Every (wavelength, angle) pair, wavelength-major, into `out`: point `i`
/// is wavelength `i / cos_theta0.len()` at angle `i % cos_theta0.len()`.
#[inline(always)]
pub(super) fn batch_body<V: Lanes>(
    indices: &[C64],
    thicknesses_nm: &[f64],
    coherence: &Coherence,
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    out: &mut [Response],
) {
    let media = thicknesses_nm.len() + 2;
    let total = out.len();
    for start in (0..total).step_by(V::WIDTH) {
        let (idx, wl, cos) =
            grid_lanes::<V>(indices, media, wavelengths_nm, cos_theta0, start, total);
        let k0 = V::splat(std::f64::consts::TAU).div(V::from_array(wl));
        let point = |l: usize| (idx[l], wl[l]);
        let res = solve_lanes::<V>(&Gathered(idx), k0, point, thicknesses_nm, coherence, cos);
        Store(&mut *out).take(start, &res);
    }
}
