//! The thickness derivatives of a coherent stack's R and T in lanes: the
//! reverse-mode sweep of `optics::gradient` (see its coherent module) for
//! one (wavelength, angle) pair per lane, Γ form only. Lanes at grazing
//! incidence or with a near-critical layer (which the scalar recursion
//! crosses in field form) are listed for the scalar gradient to fill.
//!
//! Per lane and polarization the forward sweep records, for each layer,
//! its round trip e^{2iδ}, i k0 q and the Γ it leaves, and for each
//! interface ∂Γ'/∂Γ = 4ab/(x + y)² and ∂log t'/∂Γ = −(a − b)/(x + y); the
//! backward sweep multiplies them from the top down.

use std::f64::consts::TAU;

use num_complex::Complex64 as C64;

use super::arith::{one_way, sqrt_upper, Cv, Lanes, MAX_LANES};
use crate::optics::solver::{Amplitudes, Response};

/// Where the lanes write: R and T (and the amplitudes they come from) at
/// `[w * angles + a]`, each derivative at `[(layer * wavelengths + w) *
/// angles + a]`, and the points (w * angles + a) they leave to the scalar
/// gradient.
pub struct GradientSink<'a> {
    /// R and T per point.
    pub response: &'a mut [Response],
    /// r and t per point (the forward sweep's Γ at the top and product of
    /// the transmission factors, as `solve_amplitudes` gives them).
    pub amplitudes: &'a mut [Amplitudes],
    /// ∂Rs, ∂Rp, ∂Ts, ∂Tp by each layer's thickness.
    pub d: [&'a mut [f64]; 4],
    /// Points the lanes did not solve (grazing, near-critical layers).
    pub fallback: &'a mut Vec<usize>,
}

/// The indices of medium `j` at the lanes' wavelengths `w0..w0 + WIDTH`
/// (the last wavelength repeated past the end).
#[inline(always)]
fn gather<V: Lanes>(
    indices: &[C64],
    media: usize,
    wavelengths: usize,
    w0: usize,
    j: usize,
) -> Cv<V> {
    let mut re = [0.0; MAX_LANES];
    let mut im = [0.0; MAX_LANES];
    for l in 0..V::WIDTH {
        let w = (w0 + l).min(wavelengths - 1);
        let n = indices[w * media + j];
        re[l] = n.re;
        im[l] = n.im;
    }
    Cv {
        re: V::from_array(re),
        im: V::from_array(im),
    }
}

/// An interface in Γ form (x = a(1 + Γ), y = b(1 − Γ)): the new Γ, the
/// shared reciprocal 1/(x + y), ∂Γ'/∂Γ = 4ab/(x + y)² and
/// ∂log t'/∂Γ = (b − a)/(x + y).
#[inline(always)]
fn interface<V: Lanes>(gamma: Cv<V>, a: Cv<V>, b: Cv<V>) -> [Cv<V>; 4] {
    let x = a.mul(gamma.one_plus());
    let y = b.mul(gamma.one_minus());
    let inv = x.add(y).inv();
    let jac = a.mul(b).scale(V::splat(4.0)).mul(inv).mul(inv);
    let log_t = b.sub(a).mul(inv);
    [x.sub(y).mul(inv), inv, jac, log_t]
}

/// i z.
#[inline(always)]
fn times_i<V: Lanes>(z: Cv<V>) -> Cv<V> {
    Cv {
        re: z.im.neg(),
        im: z.re,
    }
}

/// Re(conj(a) b): half of ∂|a|² for a change b of a.
#[inline(always)]
fn re_conj_mul<V: Lanes>(a: Cv<V>, b: Cv<V>) -> V {
    a.re.mul_add(b.re, a.im.mul(b.im))
}

/// The body of the lanes gradient: every (wavelength, angle) point of a
/// coherent stack, `indices` wavelength-major (N + 2 per wavelength).
#[inline(always)]
pub(super) fn gradient_body<V: Lanes>(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    sink: &mut GradientSink<'_>,
) {
    let layers = thicknesses_nm.len();
    let (wavelengths, angles) = (wavelengths_nm.len(), cos_theta0.len());
    // Per layer: round trip, i k0 q, Γs and Γp after it; per interface:
    // Js, Ks, Jp, Kp (see the module's text). Slot j holds layer j + 1's
    // and then interface j's.
    let mut tape = vec![Cv::real(V::splat(0.0)); 8 * (layers + 1)];
    let mut d_layers = vec![[V::splat(0.0); 4]; layers];
    for (a, &c) in cos_theta0.iter().enumerate() {
        if c.is_nan() || c <= 0.0 {
            sink.fallback
                .extend((0..wavelengths).map(|w| w * angles + a));
            continue;
        }
        for w0 in (0..wavelengths).step_by(V::WIDTH) {
            let mut wl = [1.0; MAX_LANES];
            for (l, x) in wl.iter_mut().enumerate().take(V::WIDTH) {
                *x = wavelengths_nm[(w0 + l).min(wavelengths - 1)];
            }
            let block = Block {
                indices,
                media: layers + 2,
                wavelengths,
                w0,
            };
            let (power, near_critical) = block.forward(
                thicknesses_nm,
                V::splat(TAU).div(V::from_array(wl)),
                V::splat(c.min(1.0)),
                &mut tape,
            );
            backward(
                &tape,
                layers + 1,
                [power.gamma_s, power.gamma_p],
                &mut d_layers,
            );
            let count = V::WIDTH.min(wavelengths - w0);
            write_block(
                sink,
                (w0, count, a, angles),
                &power,
                near_critical,
                &d_layers,
            );
        }
    }
}

/// The lanes' wavelengths: `w0..w0 + WIDTH` of the grid.
struct Block<'a> {
    indices: &'a [C64],
    media: usize,
    wavelengths: usize,
    w0: usize,
}

/// What the forward sweep leaves: Γ at the top, t and R and T.
struct BlockPower<V> {
    gamma_s: Cv<V>,
    gamma_p: Cv<V>,
    /// t_s, t_p.
    t: [Cv<V>; 2],
    /// Rs, Rp, Ts, Tp.
    power: [V; 4],
}

impl Block<'_> {
    /// Medium `j`'s n, n² and q.
    #[inline(always)]
    fn medium<V: Lanes>(&self, j: usize, beta_sq: V) -> (Cv<V>, Cv<V>, Cv<V>) {
        let n = gather::<V>(self.indices, self.media, self.wavelengths, self.w0, j);
        let nsq = n.mul(n);
        (n, nsq, sqrt_upper(nsq.sub_real(beta_sq)))
    }

    /// The forward sweep (the scalar recursion in Γ form), recording the
    /// tape: R, T, Γ at the top, and the lanes with a near-critical layer.
    #[inline(always)]
    fn forward<V: Lanes>(
        &self,
        thicknesses_nm: &[f64],
        k0: V,
        cos: V,
        tape: &mut [Cv<V>],
    ) -> (BlockPower<V>, u32) {
        let one = V::splat(1.0);
        let last = self.media - 1;
        let n0 = gather::<V>(self.indices, self.media, self.wavelengths, self.w0, 0).re;
        let beta_sq = n0.mul(n0).mul(one.sub(cos).mul(one.add(cos)));
        let (n_sub, nsq_sub, q_sub) = self.medium(last, beta_sq);
        let top = [Cv::real(n0), Cv::real(n0.mul(n0)), Cv::real(n0.mul(cos))];
        let run = sweep(
            self.media,
            |j| {
                let (n, nsq, q) = self.medium(j, beta_sq);
                [n, nsq, q]
            },
            |j| thicknesses_nm[j],
            k0,
            (top, [n_sub, nsq_sub, q_sub]),
            tape,
        );
        let (gamma_s, gamma_p, [ts, tp], near_critical) = run;
        // Power, as the scalar solver's `to_power`.
        let inv_q0 = one.div(n0.mul(cos));
        let conj_q = Cv {
            re: q_sub.re,
            im: q_sub.im.neg(),
        };
        let p_flux = conj_q.mul(n_sub).mul(n_sub).re.div(n_sub.norm_sqr());
        let power = [
            gamma_s.norm_sqr(),
            gamma_p.norm_sqr(),
            ts.norm_sqr().mul(q_sub.re).mul(inv_q0),
            tp.norm_sqr().mul(p_flux).mul(inv_q0),
        ];
        let out = BlockPower {
            gamma_s,
            gamma_p,
            t: [ts, tp],
            power,
        };
        (out, near_critical)
    }
}

/// One coherent run of `media` media in Γ form, the scalar recursion's
/// forward sweep, recording the tape for [`backward`]: `inner(j)` gives the
/// (n, n², q) of medium j strictly between the two ends (`ends`: the top's
/// and the bottom's), `thickness(j)` that of medium j + 1. Returns Γs, Γp
/// at the top, t_s, t_p, and the lanes with a near-critical inner medium.
#[inline(always)]
pub(super) fn sweep<V: Lanes>(
    media: usize,
    inner: impl Fn(usize) -> [Cv<V>; 3],
    thickness: impl Fn(usize) -> f64,
    k0: V,
    (top, bottom): ([Cv<V>; 3], [Cv<V>; 3]),
    tape: &mut [Cv<V>],
) -> (Cv<V>, Cv<V>, [Cv<V>; 2], u32) {
    let (one, two) = (V::splat(1.0), V::splat(2.0));
    let last = media - 1;
    let [mut n_below, mut nsq_below, mut q_below] = bottom;
    let (mut gamma_s, mut gamma_p) = (Cv::real(V::splat(0.0)), Cv::real(V::splat(0.0)));
    let (mut ts, mut tp) = (Cv::real(one), Cv::real(one));
    let mut near_critical = 0u32;
    for j in (0..last).rev() {
        let [n_above, nsq_above, q_above] = if j == 0 { top } else { inner(j) };
        let slot = &mut tape[8 * j..8 * j + 8];
        if j + 1 < last {
            let one_way = one_way(q_below.scale(k0.mul(V::splat(thickness(j)))));
            let round_trip = one_way.mul(one_way);
            gamma_s = gamma_s.mul(round_trip);
            gamma_p = gamma_p.mul(round_trip);
            ts = ts.mul(one_way);
            tp = tp.mul(one_way);
            slot[..4].copy_from_slice(&[round_trip, times_i(q_below.scale(k0)), gamma_s, gamma_p]);
        }
        if j > 0 {
            let q2 = q_above.norm_sqr();
            near_critical |= V::bits(q2.mul(q2).lt(V::splat(1e-8).mul(nsq_above.norm_sqr())));
        }
        let [g, inv_s, js, ks] = interface(gamma_s, q_above, q_below);
        gamma_s = g;
        ts = ts.mul(q_above.scale(two).mul(inv_s));
        let [g, inv_p, jp, kp] = interface(gamma_p, nsq_below.mul(q_above), nsq_above.mul(q_below));
        gamma_p = g;
        tp = tp.mul(n_above.scale(two).mul(n_below).mul(q_above).mul(inv_p));
        slot[4..].copy_from_slice(&[js, ks, jp, kp]);
        (n_below, nsq_below, q_below) = (n_above, nsq_above, q_above);
    }
    (gamma_s, gamma_p, [ts, tp], near_critical)
}

/// Writes one block's R, T and derivatives (∂R = 2 Re(conj Γ ∂Γ),
/// ∂T = 2 T Re(∂log t)) for its `count` lanes at angle `a`, and lists the
/// lanes with a near-critical layer for the scalar gradient.
#[inline(always)]
fn write_block<V: Lanes>(
    sink: &mut GradientSink<'_>,
    (w0, count, a, angles): (usize, usize, usize, usize),
    power: &BlockPower<V>,
    near_critical: u32,
    d_layers: &[[V; 4]],
) {
    let two = V::splat(2.0);
    let wavelengths = sink.response.len() / angles;
    let arrays = [
        power.power[0].to_array(),
        power.power[1].to_array(),
        power.power[2].to_array(),
        power.power[3].to_array(),
    ];
    let responses: [Response; MAX_LANES] = std::array::from_fn(|l| Response {
        rs: arrays[0][l],
        rp: arrays[1][l],
        ts: arrays[2][l],
        tp: arrays[3][l],
    });
    let amplitudes = lane_amplitudes(power);
    for (l, response) in responses[..count].iter().enumerate() {
        let point = (w0 + l) * angles + a;
        if near_critical & (1 << l) != 0 {
            sink.fallback.push(point);
        } else {
            sink.response[point] = *response;
            sink.amplitudes[point] = amplitudes[l];
        }
    }
    for (layer, d) in d_layers.iter().enumerate() {
        let parts = [
            d[0].mul(two).to_array(),
            d[1].mul(two).to_array(),
            d[2].mul(two).mul(power.power[2]).to_array(),
            d[3].mul(two).mul(power.power[3]).to_array(),
        ];
        let base = (layer * wavelengths + w0) * angles + a;
        for (out, part) in sink.d.iter_mut().zip(&parts) {
            for (l, value) in part[..count].iter().enumerate() {
                out[base + l * angles] = *value;
            }
        }
    }
}

/// The block's r and t, lane by lane.
#[inline(always)]
fn lane_amplitudes<V: Lanes>(power: &BlockPower<V>) -> [Amplitudes; MAX_LANES] {
    let parts = [power.gamma_s, power.gamma_p, power.t[0], power.t[1]]
        .map(|z| (z.re.to_array(), z.im.to_array()));
    let at = |k: usize, l: usize| C64::new(parts[k].0[l], parts[k].1[l]);
    std::array::from_fn(|l| Amplitudes {
        rs: at(0, l),
        rp: at(1, l),
        ts: at(2, l),
        tp: at(3, l),
    })
}

/// The backward sweep: for each layer, Re(conj Γ_top ∂Γ_top) and
/// Re(∂log t) by its thickness, s and p, into `out[layer]`.
#[inline(always)]
pub(super) fn backward<V: Lanes>(tape: &[Cv<V>], last: usize, top: [Cv<V>; 2], out: &mut [[V; 4]]) {
    let zero = Cv::real(V::splat(0.0));
    let one = Cv::real(V::splat(1.0));
    let (mut g_s, mut h_s, mut g_p, mut h_p) = (one, zero, one, zero);
    for j in 0..last {
        let slot = &tape[8 * j..8 * j + 8];
        h_s = h_s.mul(slot[4]).add(slot[5]);
        g_s = g_s.mul(slot[4]);
        h_p = h_p.mul(slot[6]).add(slot[7]);
        g_p = g_p.mul(slot[6]);
        if j + 1 < last {
            let (round_trip, ik0q) = (slot[0], slot[1]);
            let dw_s = ik0q.mul(slot[2]).scale(V::splat(2.0));
            let dw_p = ik0q.mul(slot[3]).scale(V::splat(2.0));
            out[j] = [
                re_conj_mul(top[0], g_s.mul(dw_s)),
                re_conj_mul(top[1], g_p.mul(dw_p)),
                h_s.mul(dw_s).add(ik0q).re,
                h_p.mul(dw_p).add(ik0q).re,
            ];
            g_s = g_s.mul(round_trip);
            h_s = h_s.mul(round_trip);
            g_p = g_p.mul(round_trip);
            h_p = h_p.mul(round_trip);
        }
    }
}
