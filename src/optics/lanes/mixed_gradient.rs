//! The thickness derivatives of a stack with incoherent layers in lanes:
//! the scalar forward mode through the power sums (`optics::gradient`'s
//! mixed module) for one (wavelength, angle) pair per lane. Each coherent
//! group's amplitude derivatives come from the coherent gradient's sweep
//! ([`sweep`], [`backward`]) over the group, top down and bottom up; ρ and
//! τ carry one derivative per layer up through [`through_layer`]'s sums.
//!
//! Lanes the scalar gradient covers differently are listed for it to fill:
//! grazing incidence, a near-critical layer inside a group, a lossless
//! incoherent layer beyond its critical angle (opaque), a sum that does
//! not converge (lasing) or a result that is not finite.

use std::f64::consts::TAU;

use num_complex::Complex64 as C64;

use super::arith::{exp_any, sqrt_upper, Cv, Lanes, MAX_LANES};
use super::general::{Gathered, MediaLanes};
use super::gradient::{backward, sweep, GradientSink};
use super::incoherent::{incoherent_top, normal_index_sq, through_layer};
use crate::optics::incoherent::Coherence;
use crate::optics::solver::Response;

/// One group's r, t (s and p), from above or below, and per layer of the
/// group (top down) Re(conj r ∂r) and Re ∂log t, s and p (in a buffer the
/// caller keeps across blocks: no allocation per point).
struct GroupSide<'d, V> {
    r: [Cv<V>; 2],
    t: [Cv<V>; 2],
    d: &'d [[V; 4]],
}

/// The lanes' wavelengths at one angle.
struct Block<'a, V> {
    media: Gathered<'a>,
    thicknesses_nm: &'a [f64],
    k0: V,
    beta_sq: V,
}

impl<V: Lanes> Block<'_, V> {
    /// The group between media `top` and `bottom` (`top` < `bottom`), read
    /// top down or, `reversed`, bottom up, with the (n, n², q) of the media
    /// the recursion starts and ends at; its derivatives go into `d`.
    #[inline(always)]
    fn side<'d>(
        &self,
        (top, bottom, reversed): (usize, usize, bool),
        (first, end): ([Cv<V>; 3], [Cv<V>; 3]),
        tape: &mut [Cv<V>],
        d: &'d mut Vec<[V; 4]>,
    ) -> (GroupSide<'d, V>, u32) {
        let media = bottom - top + 1;
        let inner = |j: usize| {
            let (n, nsq) = self
                .media
                .medium(if reversed { bottom - j } else { top + j });
            [n, nsq, sqrt_upper(nsq.sub_real(self.beta_sq))]
        };
        let thickness =
            |j: usize| self.thicknesses_nm[if reversed { bottom - j - 2 } else { top + j }];
        let (gs, gp, t, near) = sweep(media, inner, thickness, self.k0, (first, end), tape);
        d.clear();
        d.resize(media - 2, [V::splat(0.0); 4]);
        backward(tape, media - 1, [gs, gp], d);
        if reversed {
            d.reverse();
        }
        (GroupSide { r: [gs, gp], t, d }, near)
    }
}

/// Crossing an incoherent layer and the group above it, one polarization.
struct Crossing<'a, V> {
    down: &'a GroupSide<'a, V>,
    up: &'a GroupSide<'a, V>,
    pass: V,
    d_pass: V,
    /// The incoherent layer's index among the layers (0-based).
    layer_index: usize,
    /// The layer index of the group's first finite medium.
    first_layer: usize,
}

impl<V: Lanes> Crossing<'_, V> {
    /// The scalar `Crossing::sums` for polarization `pol` (0 s, 1 p):
    /// the new (ρ, τ), their derivatives in `d`, and the converging lanes.
    #[inline(always)]
    fn sums(&self, pol: usize, (rho0, tau0): (V, V), d: &mut [[V; 4]]) -> ((V, V), u32) {
        let (g, u) = (self.down, self.up);
        let (r, t, r_up, t_up) = (g.r[pol], g.t[pol], u.r[pol], u.t[pol]);
        let (sums, ok) = through_layer((rho0, tau0), (r, t), (r_up, t_up), self.pass);
        let (one, two) = (V::splat(1.0), V::splat(2.0));
        let (b, c, e) = (t.mul(t_up).norm_sqr(), r_up.norm_sqr(), t.norm_sqr());
        let p = self.pass;
        let returned = p.mul(p).mul(rho0);
        let inv = one.div(one.sub(c.mul(returned)));
        let inv_sq = inv.mul(inv);
        let epti2 = e.mul(p).mul(tau0).mul(inv_sq);
        let group = self.first_layer..self.first_layer + g.d.len();
        for (l, dl) in d.iter_mut().enumerate() {
            if group.contains(&l) {
                continue; // Set below, from the group's own derivatives.
            }
            let mut d_returned = p.mul(p).mul(dl[pol]);
            let mut d_p = V::splat(0.0);
            if l == self.layer_index {
                d_p = self.d_pass;
                d_returned = d_returned.add(two.mul(p).mul(d_p).mul(rho0));
            }
            let dr = b.mul(d_returned).mul(inv_sq);
            let dt = e
                .mul(d_p)
                .mul(tau0)
                .add(e.mul(p).mul(dl[2 + pol]))
                .mul(inv)
                .add(epti2.mul(c).mul(d_returned));
            dl[pol] = dr;
            dl[2 + pol] = dt;
        }
        for (i, (dd, du)) in g.d.iter().zip(u.d).enumerate() {
            let dl = &mut d[self.first_layer + i];
            let da = two.mul(dd[pol]);
            let db = two.mul(b).mul(dd[2 + pol].add(du[2 + pol]));
            let dc = two.mul(du[pol]);
            let de = two.mul(e).mul(dd[2 + pol]);
            dl[pol] = da
                .add(db.mul(returned).mul(inv))
                .add(b.mul(returned).mul(returned).mul(dc).mul(inv_sq));
            dl[2 + pol] = de
                .mul(p)
                .mul(tau0)
                .mul(inv)
                .add(epti2.mul(dc).mul(returned));
        }
        (sums, ok)
    }
}

/// The buffers a block of lanes works in, kept across blocks: the tape,
/// the groups' derivatives seen from above and from below, and the
/// block's own per layer.
struct Scratch<V> {
    tape: Vec<Cv<V>>,
    down: Vec<[V; 4]>,
    up: Vec<[V; 4]>,
    d: Vec<[V; 4]>,
}

/// R, T and their derivatives (per layer: ∂Rs, ∂Rp, ∂Ts, ∂Tp, into
/// `scratch.d`) of one block of lanes, and the lanes to leave to the
/// scalar gradient.
#[inline(always)]
fn solve_block<V: Lanes>(
    block: &Block<'_, V>,
    coherence: &Coherence,
    cos: V,
    scratch: &mut Scratch<V>,
) -> ([V; 4], u32) {
    let Scratch {
        tape,
        down: down_d,
        up: up_d,
        d,
    } = scratch;
    let layers = block.thicknesses_nm.len();
    let last = layers + 1;
    let zero = V::splat(0.0);
    let n0: V = MediaLanes::<V>::medium(&block.media, 0).0.re;
    let q0 = n0.mul(cos);
    let (n0_sq, q0_sq) = (n0.mul(n0), q0.mul(q0));
    let (n_sub, nsq_sub) = block.media.medium(last);
    let q_sub = sqrt_upper(normal_index_sq(nsq_sub, n0_sq, q0_sq));
    let mut scalar = 0u32;
    let (mut below, mut bottom) = (last, [n_sub, nsq_sub, q_sub]);
    let mut state: Option<[(V, V); 2]> = None;
    d.fill([zero; 4]);
    let incoherent = coherence.incoherent_layers().iter().rev().copied();
    for m in incoherent.chain(std::iter::once(0)) {
        let top = if m == 0 {
            [Cv::real(n0), Cv::real(n0_sq), Cv::real(q0)]
        } else {
            let (top, opaque) = incoherent_top(&block.media, m, n0_sq, q0_sq);
            scalar |= opaque;
            top
        };
        let (down, near) = block.side((m, below, false), (top, bottom), tape, down_d);
        scalar |= near;
        state = Some(match state {
            None => {
                for (i, dd) in down.d.iter().enumerate() {
                    let dl = &mut d[m + i];
                    for pol in 0..2 {
                        dl[pol] = V::splat(2.0).mul(dd[pol]);
                        let tau = down.t[pol].norm_sqr();
                        dl[2 + pol] = V::splat(2.0).mul(tau).mul(dd[2 + pol]);
                    }
                }
                [0, 1].map(|pol| (down.r[pol].norm_sqr(), down.t[pol].norm_sqr()))
            }
            Some(sums) => {
                let (up, near) = block.side((m, below, true), (bottom, top), tape, up_d);
                let k0d = block.k0.mul(V::splat(block.thicknesses_nm[below - 1]));
                let pass = exp_any(V::splat(-2.0).mul(k0d).mul(bottom[2].im));
                let d_pass = V::splat(-2.0).mul(block.k0).mul(bottom[2].im).mul(pass);
                let cross = Crossing {
                    down: &down,
                    up: &up,
                    pass,
                    d_pass,
                    layer_index: below - 1,
                    first_layer: m,
                };
                let (s, ok_s) = cross.sums(0, sums[0], d);
                let (p, ok_p) = cross.sums(1, sums[1], d);
                scalar |= near | (!(ok_s & ok_p) & V::ALL);
                [s, p]
            }
        });
        (below, bottom) = (m, top);
    }
    let [(rs, ts), (rp, tp)] = state.expect("the ambient closes the recursion");
    let conj_q = Cv {
        re: q_sub.re,
        im: q_sub.im.neg(),
    };
    let p_flux = conj_q.mul(n_sub).mul(n_sub).re.div(n_sub.norm_sqr());
    let flux = [q_sub.re.div(q0), p_flux.div(q0)];
    for dl in d.iter_mut() {
        dl[2] = dl[2].mul(flux[0]);
        dl[3] = dl[3].mul(flux[1]);
    }
    let power = [rs, rp, ts.mul(flux[0]), tp.mul(flux[1])];
    let inf = V::splat(f64::INFINITY);
    for x in power {
        scalar |= !V::bits(x.abs().lt(inf)) & V::ALL;
    }
    (power, scalar)
}

/// The body of the mixed lanes gradient: every (wavelength, angle) point
/// of a stack with incoherent layers, `indices` wavelength-major (N + 2
/// per wavelength), into `sink` (its `amplitudes` unused).
#[inline(always)]
pub(super) fn mixed_gradient_body<V: Lanes>(
    indices: &[C64],
    thicknesses_nm: &[f64],
    coherence: &Coherence,
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    sink: &mut GradientSink<'_>,
) {
    let layers = thicknesses_nm.len();
    let media = layers + 2;
    let (wavelengths, angles) = (wavelengths_nm.len(), cos_theta0.len());
    let mut scratch = Scratch {
        tape: vec![Cv::real(V::splat(0.0)); 8 * (layers + 1)],
        down: Vec::with_capacity(layers),
        up: Vec::with_capacity(layers),
        d: vec![[V::splat(0.0); 4]; layers],
    };
    for (a, &c) in cos_theta0.iter().enumerate() {
        if c.is_nan() || c <= 0.0 {
            sink.fallback
                .extend((0..wavelengths).map(|w| w * angles + a));
            continue;
        }
        let cos = V::splat(c.min(1.0));
        for w0 in (0..wavelengths).step_by(V::WIDTH) {
            let lane_w = |l: usize| (w0 + l).min(wavelengths - 1);
            let mut idx: [&[C64]; MAX_LANES] = [&[]; MAX_LANES];
            let mut wl = [1.0; MAX_LANES];
            for l in 0..V::WIDTH {
                let w = lane_w(l);
                idx[l] = &indices[w * media..(w + 1) * media];
                wl[l] = wavelengths_nm[w];
            }
            let k0 = V::splat(TAU).div(V::from_array(wl));
            let one = V::splat(1.0);
            let n0: V = MediaLanes::<V>::medium(&Gathered(idx), 0).0.re;
            let block = Block {
                media: Gathered(idx),
                thicknesses_nm,
                k0,
                beta_sq: n0.mul(n0).mul(one.sub(cos).mul(one.add(cos))),
            };
            let (power, scalar) = solve_block(&block, coherence, cos, &mut scratch);
            let count = V::WIDTH.min(wavelengths - w0);
            write_block(sink, (w0, count, a, angles), power, scalar, &scratch.d);
        }
    }
}

/// Writes the block's lanes that are not left to the scalar gradient, and
/// lists those that are.
#[inline(always)]
fn write_block<V: Lanes>(
    sink: &mut GradientSink<'_>,
    (w0, count, a, angles): (usize, usize, usize, usize),
    power: [V; 4],
    scalar: u32,
    d: &[[V; 4]],
) {
    let wavelengths = sink.response.len() / angles;
    let arrays = power.map(|x| x.to_array());
    let responses: [Response; MAX_LANES] = std::array::from_fn(|l| Response {
        rs: arrays[0][l],
        rp: arrays[1][l],
        ts: arrays[2][l],
        tp: arrays[3][l],
    });
    for (l, response) in responses[..count].iter().enumerate() {
        let point = (w0 + l) * angles + a;
        if scalar & (1 << l) != 0 {
            sink.fallback.push(point);
        } else {
            sink.response[point] = *response;
        }
    }
    for (layer, dl) in d.iter().enumerate() {
        let parts = dl.map(|x| x.to_array());
        let base = (layer * wavelengths + w0) * angles + a;
        for (out, part) in sink.d.iter_mut().zip(&parts) {
            for (l, value) in part[..count].iter().enumerate() {
                if scalar & (1 << l) == 0 {
                    out[base + l * angles] = *value;
                }
            }
        }
    }
}
