//! The general kernel: the scalar solver's recursion on one (wavelength,
//! angle) pair per lane, for any stack, and its three loops: over a
//! (wavelength, angle) grid ([`batch_body`]), over arbitrary points, each
//! with its own wavelength, angle and thicknesses ([`points_body`]), and
//! over a [`Spectrum`]'s wavelengths at one angle ([`spectrum_body`], which
//! takes the non-dispersive kernel of [`constant`] when it can).

use num_complex::Complex64 as C64;

use super::arith::{one_way, sqrt_upper, Cv, Lanes, MAX_LANES};
use super::constant;
use super::sink::{Power, Sink, Store};
use super::spectrum::{Repeats, Spectrum, SHARED_SLOTS};
use crate::optics::solver::{solve, Response};

/// Solves one (wavelength, angle) pair of one stack per lane.
/// `lane_point(l)` gives lane l's N + 2 indices (ambient, layers, substrate)
/// and its wavelength, for the lanes the scalar solver takes over; the
/// preconditions are [`solve`]'s.
/// `media.medium(j)` gives medium j's n and n² in every lane (n² as `n * n`
/// computes it), `k0` is 2π over each lane's wavelength. `repeats` says
/// which media share one index (one material used by several layers, as in
/// a Bragg mirror); their q is computed once.
#[inline(always)]
fn solve_lanes<'a, V: Lanes>(
    media: &impl MediaLanes<V>,
    repeats: &Repeats,
    k0: V,
    lane_point: impl Fn(usize) -> (&'a [C64], f64),
    thicknesses: &impl ThicknessLanes<V>,
    cos_theta0: [f64; MAX_LANES],
) -> Power<V> {
    let last = thicknesses.layers() + 1;
    let one = V::splat(1.0);
    // Lanes whose answer the scalar solver gives instead: grazing here,
    // near-critical layers below.
    let mut scalar = cos_theta0.map(|c| c.is_nan() || c <= 0.0);
    let cos = V::from_array(cos_theta0.map(|c| c.min(1.0)));
    let n0 = media.medium(0).0.re;
    let beta_sq = n0.mul(n0).mul(one.sub(cos).mul(one.add(cos)));

    let shared_q = shared_normal_indices(media, repeats, beta_sq);

    let (n_sub, nsq_sub) = media.medium(last);
    let q_sub = normal_index(repeats.slot(last), &shared_q, nsq_sub, beta_sq);
    let top = [Cv::real(n0), Cv::real(n0.mul(n0)), Cv::real(n0.mul(cos))];
    let (power, near_critical) = recurse_lanes(
        media,
        (repeats, &shared_q),
        last,
        |j| thicknesses.layer(j),
        (k0, beta_sq),
        top,
        [n_sub, nsq_sub, q_sub],
    );

    for (l, s) in scalar.iter_mut().enumerate() {
        *s |= near_critical & (1 << l) != 0;
    }
    let out = to_power(&power, n0.mul(cos), n_sub, q_sub);
    if !scalar[..V::WIDTH].contains(&true) {
        return out;
    }
    let mut res = out.responses();
    for l in 0..V::WIDTH {
        if scalar[l] {
            let (indices, wavelength_nm) = lane_point(l);
            res[l] = solve(indices, thicknesses.lane(l), wavelength_nm, cos_theta0[l]);
        }
    }
    Power::from_responses(&res)
}

/// The scalar solver's recursion (`recurse_media`) in lanes, over the media
/// of `media` from `last` (the bottom half-space, given as (n, n², q) in
/// `bottom`) up to medium 0 (given as `top`): Γ and t of both polarizations,
/// and the lanes (bits) where a medium between them is near its critical
/// angle, which the scalar solver must take over. `shared` holds the q of
/// media that share one index (see [`Repeats`]), `thickness(j)` the
/// thickness of medium j + 1 in every lane, and `light` (k0, β²).
#[inline(always)]
pub(super) fn recurse_lanes<V: Lanes>(
    media: &impl MediaLanes<V>,
    (repeats, shared_q): (&Repeats, &[Cv<V>; SHARED_SLOTS]),
    last: usize,
    thickness: impl Fn(usize) -> V,
    (k0, beta_sq): (V, V),
    top: [Cv<V>; 3],
    [n_sub, nsq_sub, q_sub]: [Cv<V>; 3],
) -> (Amplitudes<V>, u32) {
    let zero = V::splat(0.0);
    let one = V::splat(1.0);
    let mut n_below = n_sub;
    let mut nsq_below = nsq_sub;
    let mut q_below = q_sub;
    let (mut gamma_s, mut gamma_p) = (Cv::real(zero), Cv::real(zero));
    let (mut ts, mut tp) = (Cv::real(one), Cv::real(one));
    let mut near_critical = 0u32;

    for j in (0..last).rev() {
        let (n_above, nsq_above, q_above) = if j == 0 {
            (top[0], top[1], top[2])
        } else {
            let (n, nsq) = media.medium(j);
            (
                n,
                nsq,
                normal_index(repeats.slot(j), shared_q, nsq, beta_sq),
            )
        };
        if j + 1 < last {
            let k0_d = k0.mul(thickness(j));
            let one_way = one_way(q_below.scale(k0_d));
            let round_trip = one_way.mul(one_way);
            gamma_s = gamma_s.mul(round_trip);
            gamma_p = gamma_p.mul(round_trip);
            ts = ts.mul(one_way);
            tp = tp.mul(one_way);
        }
        if j > 0 {
            // The scalar solver's near-critical test: |q|⁴ < 10⁻⁸ |n²|².
            let q2 = q_above.norm_sqr();
            near_critical |= V::bits(q2.mul(q2).lt(V::splat(1e-8).mul(nsq_above.norm_sqr())));
        }

        let x = q_above.mul(gamma_s.one_plus());
        let y = q_below.mul(gamma_s.one_minus());
        let inv_s = x.add(y).inv();
        gamma_s = x.sub(y).mul(inv_s);
        ts = ts.mul(q_above.scale(V::splat(2.0)).mul(inv_s));

        let x = nsq_below.mul(q_above).mul(gamma_p.one_plus());
        let y = nsq_above.mul(q_below).mul(gamma_p.one_minus());
        let inv_p = x.add(y).inv();
        gamma_p = x.sub(y).mul(inv_p);
        tp = tp.mul(
            n_above
                .scale(V::splat(2.0))
                .mul(n_below)
                .mul(q_above)
                .mul(inv_p),
        );

        n_below = n_above;
        nsq_below = nsq_above;
        q_below = q_above;
    }
    let amplitudes = Amplitudes {
        gamma_s,
        gamma_p,
        ts,
        tp,
    };
    (amplitudes, near_critical)
}

/// The recursion's result in four lanes: Γ at the top and the transmitted
/// amplitude t, for s and p.
pub(super) struct Amplitudes<V> {
    pub(super) gamma_s: Cv<V>,
    pub(super) gamma_p: Cv<V>,
    pub(super) ts: Cv<V>,
    pub(super) tp: Cv<V>,
}

/// Power, as the scalar solver's `to_power`: R = |Γ|², T from the Poynting
/// flux into the substrate over the incident one (q0 = n0 cos θ0).
#[inline(always)]
fn to_power<V: Lanes>(a: &Amplitudes<V>, q0: V, n_sub: Cv<V>, q_sub: Cv<V>) -> Power<V> {
    let one = V::splat(1.0);
    let conj_q = Cv {
        re: q_sub.re,
        im: q_sub.im.neg(),
    };
    let p_flux = conj_q.mul(n_sub).mul(n_sub).re.div(n_sub.norm_sqr());
    let inv_q0 = one.div(q0);
    Power {
        rs: a.gamma_s.norm_sqr(),
        rp: a.gamma_p.norm_sqr(),
        ts: a.ts.norm_sqr().mul(q_sub.re).mul(inv_q0),
        tp: a.tp.norm_sqr().mul(p_flux).mul(inv_q0),
    }
}

/// The q of every medium whose index another medium repeats, once each.
#[inline(always)]
fn shared_normal_indices<V: Lanes>(
    media: &impl MediaLanes<V>,
    repeats: &Repeats,
    beta_sq: V,
) -> [Cv<V>; SHARED_SLOTS] {
    let mut shared_q = [Cv::real(V::splat(0.0)); SHARED_SLOTS];
    for &(j, slot) in &repeats.first[..repeats.count] {
        shared_q[usize::from(slot)] = sqrt_upper(media.medium(usize::from(j)).1.sub_real(beta_sq));
    }
    shared_q
}

/// A medium's q: its material's shared value where it has one, else
/// sqrt_upper(n² − β²). A function, not a closure, so that it is always
/// inlined into the vector copies.
#[inline(always)]
fn normal_index<V: Lanes>(
    slot: Option<usize>,
    shared_q: &[Cv<V>; SHARED_SLOTS],
    nsq: Cv<V>,
    beta_sq: V,
) -> Cv<V> {
    match slot {
        Some(s) => shared_q[s],
        None => sqrt_upper(nsq.sub_real(beta_sq)),
    }
}

/// Where the general kernel reads each medium's n and n² (as `n * n`
/// computes it) in every lane. A trait rather than a closure: a closure is
/// compiled without the kernel copy's target features, and the intrinsics
/// in it would not be inlined.
pub(super) trait MediaLanes<V: Lanes> {
    fn medium(&self, j: usize) -> (Cv<V>, Cv<V>);
}

/// Each lane's indices from its own slice, gathered lane by lane.
pub(super) struct Gathered<'a>(pub(super) [&'a [C64]; MAX_LANES]);

impl<V: Lanes> MediaLanes<V> for Gathered<'_> {
    #[inline(always)]
    fn medium(&self, j: usize) -> (Cv<V>, Cv<V>) {
        let lane = |l: usize| self.0[l].get(j).copied().unwrap_or_default();
        let n = Cv {
            re: V::from_array(std::array::from_fn(|l| lane(l).re)),
            im: V::from_array(std::array::from_fn(|l| lane(l).im)),
        };
        (n, n.mul(n))
    }
}

/// The lanes from `start` on of a [`Spectrum`]'s rows, one load each.
pub(super) struct Laid<'a> {
    pub(super) spectrum: &'a Spectrum,
    pub(super) start: usize,
}

impl<V: Lanes> MediaLanes<V> for Laid<'_> {
    #[inline(always)]
    fn medium(&self, j: usize) -> (Cv<V>, Cv<V>) {
        let row = |quantity: usize| &self.spectrum.medium_row(j, quantity)[self.start..];
        (
            Cv {
                re: V::load(row(0)),
                im: V::load(row(1)),
            },
            Cv {
                re: V::load(row(2)),
                im: V::load(row(3)),
            },
        )
    }
}

/// Where the general kernel reads the layers' thicknesses: the same in
/// every lane, or each lane its own. A trait for the reason [`MediaLanes`]
/// is one.
trait ThicknessLanes<V: Lanes> {
    /// How many layers (N).
    fn layers(&self) -> usize;
    /// Layer j's thickness (0-based from the top) in every lane.
    fn layer(&self, j: usize) -> V;
    /// Lane l's N thicknesses, for the lanes the scalar solver takes over.
    fn lane(&self, l: usize) -> &[f64];
}

/// One set of thicknesses for every lane.
struct Shared<'a>(&'a [f64]);

impl<V: Lanes> ThicknessLanes<V> for Shared<'_> {
    #[inline(always)]
    fn layers(&self) -> usize {
        self.0.len()
    }
    #[inline(always)]
    fn layer(&self, j: usize) -> V {
        V::splat(self.0[j])
    }
    #[inline(always)]
    fn lane(&self, _l: usize) -> &[f64] {
        self.0
    }
}

/// Each lane's thicknesses from its own slice of `layers` values.
struct PerLane<'a> {
    layers: usize,
    lanes: [&'a [f64]; MAX_LANES],
}

impl<V: Lanes> ThicknessLanes<V> for PerLane<'_> {
    #[inline(always)]
    fn layers(&self) -> usize {
        self.layers
    }
    #[inline(always)]
    fn layer(&self, j: usize) -> V {
        V::from_array(std::array::from_fn(|l| {
            self.lanes[l].get(j).copied().unwrap_or_default()
        }))
    }
    #[inline(always)]
    fn lane(&self, l: usize) -> &[f64] {
        self.lanes[l]
    }
}

/// The kernel's loop over [`Lanes::WIDTH`] output points at a time. Point
/// `i` of `out` is wavelength `i / cos_theta0.len()` at angle
/// `i % cos_theta0.len()`; a last partial group repeats its final point in
/// the unused lanes.
#[inline(always)]
pub(super) fn batch_body<V: Lanes>(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    out: &mut [Response],
) {
    let media = thicknesses_nm.len() + 2;
    let n_angles = cos_theta0.len();
    let total = out.len();
    for start in (0..total).step_by(V::WIDTH) {
        let mut idx: [&[C64]; MAX_LANES] = [&[]; MAX_LANES];
        let mut wl = [0.0; MAX_LANES];
        let mut cos = [0.0; MAX_LANES];
        for l in 0..V::WIDTH {
            let i = (start + l).min(total - 1);
            let (w, a) = (i / n_angles, i % n_angles);
            idx[l] = &indices[w * media..(w + 1) * media];
            wl[l] = wavelengths_nm[w];
            cos[l] = cos_theta0[a];
        }
        let k0 = V::splat(std::f64::consts::TAU).div(V::from_array(wl));
        let gathered = Gathered(idx);
        let point = |l: usize| (idx[l], wl[l]);
        let res = solve_lanes::<V>(
            &gathered,
            &Repeats::NONE,
            k0,
            point,
            &Shared(thicknesses_nm),
            cos,
        );
        Store(&mut *out).take(start, &res);
    }
}

/// The kernel's loop over arbitrary points, [`Lanes::WIDTH`] at a time:
/// point i has its own N + 2 indices (`indices[i(N+2)..]`), N thicknesses
/// (`thicknesses_nm[iN..]`), wavelength and cos θ0, so no two lanes need
/// share anything. A last partial group repeats its final point in the
/// unused lanes.
#[inline(always)]
pub(super) fn points_body<V: Lanes>(
    layers: usize,
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    out: &mut [Response],
) {
    let media = layers + 2;
    let total = out.len();
    for start in (0..total).step_by(V::WIDTH) {
        let mut idx: [&[C64]; MAX_LANES] = [&[]; MAX_LANES];
        let mut thick: [&[f64]; MAX_LANES] = [&[]; MAX_LANES];
        let mut wl = [0.0; MAX_LANES];
        let mut cos = [0.0; MAX_LANES];
        for l in 0..V::WIDTH {
            let i = (start + l).min(total - 1);
            idx[l] = &indices[i * media..(i + 1) * media];
            thick[l] = &thicknesses_nm[i * layers..(i + 1) * layers];
            wl[l] = wavelengths_nm[i];
            cos[l] = cos_theta0[i];
        }
        let k0 = V::splat(std::f64::consts::TAU).div(V::from_array(wl));
        let point = |l: usize| (idx[l], wl[l]);
        let thicknesses = PerLane {
            layers,
            lanes: thick,
        };
        let res = solve_lanes::<V>(&Gathered(idx), &Repeats::NONE, k0, point, &thicknesses, cos);
        Store(&mut *out).take(start, &res);
    }
}

/// The non-dispersive kernel over every wavelength of a [`Spectrum`] at one
/// angle, interfaces laid out with room for `M` media; false, having done
/// nothing, where the general kernel must run instead.
#[inline(always)]
fn constant_body<V: Lanes, const M: usize>(
    spectrum: &Spectrum,
    indices: &[C64],
    thicknesses_nm: &[f64],
    cos_theta0: f64,
    sink: &mut impl Sink<V>,
) -> bool {
    let media = spectrum.media();
    let Some(f) = constant::Interfaces::<M>::new(&indices[..media], thicknesses_nm, cos_theta0)
    else {
        return false;
    };
    if let Some(one) = constant::OneLayer::<V>::new(&f) {
        for start in (0..spectrum.wavelengths()).step_by(V::WIDTH) {
            let k0 = V::load(&spectrum.k0()[start..]);
            sink.take(start, &one.solve(k0));
        }
        return true;
    }
    for start in (0..spectrum.wavelengths()).step_by(V::WIDTH) {
        let k0 = V::load(&spectrum.k0()[start..]);
        sink.take(start, &constant::solve_lanes::<V, M>(&f, k0));
    }
    true
}

/// Every wavelength of a [`Spectrum`] at one angle, [`Lanes::WIDTH`] per
/// vector, handed to `sink` in order.
#[inline(always)]
pub(super) fn spectrum_body<V: Lanes>(
    spectrum: &Spectrum,
    indices: &[C64],
    thicknesses_nm: &[f64],
    cos_theta0: f64,
    sink: &mut impl Sink<V>,
) {
    let media = spectrum.media();
    let total = spectrum.wavelengths();
    if spectrum.is_non_dispersive() {
        let done = if media <= constant::FEW_MEDIA {
            constant_body::<V, { constant::FEW_MEDIA }>(
                spectrum,
                indices,
                thicknesses_nm,
                cos_theta0,
                sink,
            )
        } else {
            constant_body::<V, { constant::MAX_MEDIA }>(
                spectrum,
                indices,
                thicknesses_nm,
                cos_theta0,
                sink,
            )
        };
        if done {
            return;
        }
    }
    for start in (0..total).step_by(V::WIDTH) {
        let laid = Laid { spectrum, start };
        // A lane's own indices and wavelength, which only the lanes handed
        // to the scalar solver need: looked up then, not for every vector.
        let point = |l: usize| {
            let w = (start + l).min(total - 1);
            (
                &indices[w * media..(w + 1) * media],
                spectrum.wavelengths_nm()[w],
            )
        };
        let res = solve_lanes::<V>(
            &laid,
            spectrum.repeats(),
            V::load(&spectrum.k0()[start..]),
            point,
            &Shared(thicknesses_nm),
            [cos_theta0; MAX_LANES],
        );
        sink.take(start, &res);
    }
}
