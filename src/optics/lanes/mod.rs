//! The solver of [`super::solver`] on four (wavelength, angle) pairs of one
//! stack at once: every complex quantity of the recursion is held as four
//! real parts and four imaginary parts, so that with AVX2 one instruction
//! advances all four lanes.
//!
//! The arithmetic is the scalar recursion's (the same products and sums in
//! the same order, the same branch of every square root). It departs from
//! [`solve`] only where speed asks: e^x, sin and cos come from a range
//! reduction and a polynomial instead of the C library, and a complex
//! reciprocal takes one division and two products instead of two divisions.
//! Each is within an ulp or a few; `tests/batched.rs` holds the lanes to the
//! scalar solver within 10⁻¹² over random and hard stacks.
//! What the lanes do not cover is handed, lane by lane, to the scalar solver,
//! which then gives that lane's answer exactly:
//! - grazing incidence (cos θ0 ≤ 0), which has its own closed form;
//! - a layer at or near its own critical angle (the scalar solver's field
//!   form, [`near_critical`](super::solver) there);
//!
//! For one layer of one lane only, the one-way phase factor of a layer whose
//! decay underflows (e^x below 2^−1022) or whose phase exceeds the
//! reduction's exact range ([`PHASE_LIMIT`]) is computed with the C library.
//!
//! Gain layers and evanescent gaps need nothing of their own: the branch
//! Im q ≥ 0 keeps every factor bounded, exactly as in the scalar solver.
//!
//! The kernel is generic over its lane type: [`avx2::Avx2`] (one AVX2
//! register per quantity, chosen at run time when the CPU has it) or
//! [`Portable`] (an array). Both perform the same IEEE operations in the same
//! order (Rust never fuses a multiply and an add on its own), so they agree
//! bit for bit.

mod arith;
mod constant;
mod sink;

#[cfg(target_arch = "x86_64")]
use arith::avx2;
pub use arith::LANES;
use arith::{one_way, sqrt_upper, Cv, Lanes, Portable};
use sink::{Integrate, Power, Sink, Store};
pub use sink::{SpectralWeights, WeightedPower};

use num_complex::Complex64 as C64;

use super::solver::{solve, Response};

/// Solves four (wavelength, angle) pairs of one stack. `indices[l]` holds
/// lane l's N + 2 indices (ambient, layers, substrate) at `wavelength_nm[l]`;
/// the preconditions are [`solve`]'s.
/// `medium(j)` gives medium j's n and n² in every lane (n² as `n * n`
/// computes it), `k0` is 2π over each lane's wavelength. `repeats` says
/// which media share one index (one material used by several layers, as in
/// a Bragg mirror); their q is computed once.
#[inline(always)]
fn solve_lanes<V: Lanes>(
    medium: impl Fn(usize) -> (Cv<V>, Cv<V>),
    repeats: &Repeats,
    k0: V,
    indices: [&[C64]; LANES],
    thicknesses_nm: &[f64],
    wavelength_nm: [f64; LANES],
    cos_theta0: [f64; LANES],
) -> Power<V> {
    let last = thicknesses_nm.len() + 1;
    for lane in &indices {
        assert_eq!(lane.len(), last + 1, "indices: N + 2 per lane");
    }
    let zero = V::splat(0.0);
    let one = V::splat(1.0);
    // Lanes whose answer the scalar solver gives instead: grazing here,
    // near-critical layers below.
    let mut scalar = cos_theta0.map(|c| c.is_nan() || c <= 0.0);
    let cos = V::from_array(cos_theta0.map(|c| c.min(1.0)));
    let n0 = medium(0).0.re;
    let beta_sq = n0.mul(n0).mul(one.sub(cos).mul(one.add(cos)));

    let shared_q = shared_normal_indices(&medium, repeats, beta_sq);

    let (n_sub, nsq_sub) = medium(last);
    let mut n_below = n_sub;
    let mut nsq_below = nsq_sub;
    let q_sub = normal_index(repeats.slot(last), &shared_q, nsq_sub, beta_sq);
    let mut q_below = q_sub;
    let (mut gamma_s, mut gamma_p) = (Cv::real(zero), Cv::real(zero));
    let (mut ts, mut tp) = (Cv::real(one), Cv::real(one));
    let mut near_critical = 0u32;

    for j in (0..last).rev() {
        let (n_above, nsq_above, q_above) = if j == 0 {
            (Cv::real(n0), Cv::real(n0.mul(n0)), Cv::real(n0.mul(cos)))
        } else {
            let (n, nsq) = medium(j);
            (
                n,
                nsq,
                normal_index(repeats.slot(j), &shared_q, nsq, beta_sq),
            )
        };
        if j + 1 < last {
            let k0_d = k0.mul(V::splat(thicknesses_nm[j]));
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

    for (l, s) in scalar.iter_mut().enumerate() {
        *s |= near_critical & (1 << l) != 0;
    }
    let power = Amplitudes {
        gamma_s,
        gamma_p,
        ts,
        tp,
    };
    let out = to_power(&power, n0.mul(cos), n_sub, q_sub);
    if !scalar.contains(&true) {
        return out;
    }
    let mut res = out.responses();
    for l in 0..LANES {
        if scalar[l] {
            res[l] = solve(indices[l], thicknesses_nm, wavelength_nm[l], cos_theta0[l]);
        }
    }
    Power::from_responses(&res)
}

/// The recursion's result in four lanes: Γ at the top and the transmitted
/// amplitude t, for s and p.
struct Amplitudes<V> {
    gamma_s: Cv<V>,
    gamma_p: Cv<V>,
    ts: Cv<V>,
    tp: Cv<V>,
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
    medium: &impl Fn(usize) -> (Cv<V>, Cv<V>),
    repeats: &Repeats,
    beta_sq: V,
) -> [Cv<V>; SHARED_SLOTS] {
    let mut shared_q = [Cv::real(V::splat(0.0)); SHARED_SLOTS];
    for &(j, slot) in &repeats.first[..repeats.count] {
        shared_q[usize::from(slot)] = sqrt_upper(medium(usize::from(j)).1.sub_real(beta_sq));
    }
    shared_q
}

/// A medium's q: its material's shared value where it has one, else
/// sqrt_upper(n² − β²). A function, not a closure, so that it is always
/// inlined into the AVX2 copy.
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

/// The kernel's loop over groups of four output points. Point `i` of `out`
/// is wavelength `i / cos_theta0.len()` at angle `i % cos_theta0.len()`;
/// a last partial group repeats its final point in the unused lanes.
#[inline(always)]
fn batch_body<V: Lanes>(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    out: &mut [Response],
) {
    let media = thicknesses_nm.len() + 2;
    let n_angles = cos_theta0.len();
    let total = out.len();
    let mut start = 0;
    while start < total {
        let mut idx: [&[C64]; LANES] = [&[]; LANES];
        let mut wl = [0.0; LANES];
        let mut cos = [0.0; LANES];
        for l in 0..LANES {
            let i = (start + l).min(total - 1);
            let (w, a) = (i / n_angles, i % n_angles);
            idx[l] = &indices[w * media..(w + 1) * media];
            wl[l] = wavelengths_nm[w];
            cos[l] = cos_theta0[a];
        }
        let gather = |j: usize| {
            let n = Cv {
                re: V::from_array(idx.map(|n| n[j].re)),
                im: V::from_array(idx.map(|n| n[j].im)),
            };
            (n, n.mul(n))
        };
        let k0 = V::splat(std::f64::consts::TAU).div(V::from_array(wl));
        let res = solve_lanes::<V>(gather, &Repeats::NONE, k0, idx, thicknesses_nm, wl, cos);
        Store(&mut *out).take(start / LANES, &res);
        start += LANES;
    }
}

/// A stack's indices at a list of wavelengths, laid out for the lanes:
/// per group of four consecutive wavelengths and per medium, n and n² of the
/// four lanes side by side, and 2π/λ of each lane. Built once per
/// [`StackGrid`](super::StackGrid), it turns each lane's loads into one
/// vector load and takes n², 2π/λ off the per-point work.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Spectrum {
    media: usize,
    wavelengths: usize,
    /// [group][medium][n.re, n.im, n².re, n².im][lane].
    lanes: Vec<[[f64; LANES]; 4]>,
    /// [group][lane].
    k0: Vec<[f64; LANES]>,
    wavelengths_nm: Vec<[f64; LANES]>,
    /// Every medium has the same index at every wavelength: the spectrum
    /// can take the non-dispersive kernel ([`constant`]).
    non_dispersive: bool,
    /// Media that share their index at every wavelength with another.
    repeats: Repeats,
}

/// Distinct materials whose q the kernel keeps for their repeats.
const SHARED_SLOTS: usize = 8;

/// Which media (below the ambient) have the same index as another medium at
/// every wavelength, so that one square root gives the q of all of them.
/// Up to [`SHARED_SLOTS`] such materials, among the first 256 media; the
/// others compute their own q.
#[derive(Clone, Debug, PartialEq)]
struct Repeats {
    /// Per medium: 0 for none, else 1 + its material's slot.
    slot_of: Vec<u8>,
    /// (medium, slot) of each slot's first medium, which computes its q.
    first: [(u8, u8); SHARED_SLOTS],
    count: usize,
}

impl Default for Repeats {
    fn default() -> Self {
        Repeats::NONE
    }
}

impl Repeats {
    const NONE: Repeats = Repeats {
        slot_of: Vec::new(),
        first: [(0, 0); SHARED_SLOTS],
        count: 0,
    };

    /// `indices` wavelength-major, `media` per wavelength.
    fn new(indices: &[C64], media: usize) -> Repeats {
        let mut r = Repeats::NONE;
        let rows = || indices.chunks_exact(media.max(1));
        // The first wavelength's indices rule most pairs out before any
        // other row is read.
        let first = indices.get(..media).unwrap_or(&[]);
        let same =
            |a: usize, b: usize| first.get(a) == first.get(b) && rows().all(|row| row[a] == row[b]);
        let media = media.min(256);
        r.slot_of = vec![0; media];
        for j in 1..media {
            if r.slot_of[j] != 0 || r.count == SHARED_SLOTS {
                continue;
            }
            let twins: Vec<usize> = (j + 1..media)
                .filter(|&k| r.slot_of[k] == 0 && same(j, k))
                .collect();
            if twins.is_empty() {
                continue;
            }
            let slot = r.count as u8;
            r.first[r.count] = (j as u8, slot);
            r.count += 1;
            for k in std::iter::once(j).chain(twins) {
                r.slot_of[k] = slot + 1;
            }
        }
        r
    }

    #[inline(always)]
    fn slot(&self, j: usize) -> Option<usize> {
        match self.slot_of.get(j) {
            Some(&s) if s != 0 => Some(usize::from(s - 1)),
            _ => None,
        }
    }
}

impl Spectrum {
    /// `indices` wavelength-major, `media` per wavelength (as
    /// [`StackGrid`](super::StackGrid) stores them). A last partial group
    /// repeats its final wavelength.
    pub fn new(indices: &[C64], media: usize, wavelengths_nm: &[f64]) -> Spectrum {
        assert_eq!(indices.len(), media * wavelengths_nm.len());
        let groups = wavelengths_nm.len().div_ceil(LANES);
        let mut lanes = Vec::with_capacity(groups * media);
        let mut k0 = Vec::with_capacity(groups);
        let mut wl = Vec::with_capacity(groups);
        for g in 0..groups {
            let w = |l: usize| (g * LANES + l).min(wavelengths_nm.len() - 1);
            for j in 0..media {
                let mut m = [[0.0; LANES]; 4];
                for l in 0..LANES {
                    let n = indices[w(l) * media + j];
                    let nsq = n * n;
                    m[0][l] = n.re;
                    m[1][l] = n.im;
                    m[2][l] = nsq.re;
                    m[3][l] = nsq.im;
                }
                lanes.push(m);
            }
            let group_wl: [f64; LANES] = std::array::from_fn(|l| wavelengths_nm[w(l)]);
            k0.push(group_wl.map(|x| std::f64::consts::TAU / x));
            wl.push(group_wl);
        }
        let first = &indices[..media.min(indices.len())];
        let non_dispersive = indices.chunks_exact(media.max(1)).all(|row| row == first);
        Spectrum {
            non_dispersive,
            repeats: Repeats::new(indices, media),
            media,
            wavelengths: wavelengths_nm.len(),
            lanes,
            k0,
            wavelengths_nm: wl,
        }
    }
}

/// Every wavelength of a [`Spectrum`] at one angle, four per vector.
#[inline(always)]
fn spectrum_body<V: Lanes>(
    spectrum: &Spectrum,
    indices: &[C64],
    thicknesses_nm: &[f64],
    cos_theta0: f64,
    sink: &mut impl Sink<V>,
) {
    let media = spectrum.media;
    let total = spectrum.wavelengths;
    if spectrum.non_dispersive {
        if let Some(f) = constant::Interfaces::new(&indices[..media], thicknesses_nm, cos_theta0) {
            for (g, k0) in spectrum.k0.iter().enumerate() {
                sink.take(g, &constant::solve_lanes::<V>(&f, V::from_array(*k0)));
            }
            return;
        }
    }
    for (g, (k0, wl)) in spectrum.k0.iter().zip(&spectrum.wavelengths_nm).enumerate() {
        let group = &spectrum.lanes[g * media..(g + 1) * media];
        let medium = |j: usize| {
            let m = &group[j];
            (
                Cv {
                    re: V::from_array(m[0]),
                    im: V::from_array(m[1]),
                },
                Cv {
                    re: V::from_array(m[2]),
                    im: V::from_array(m[3]),
                },
            )
        };
        let start = g * LANES;
        let idx: [&[C64]; LANES] = std::array::from_fn(|l| {
            let w = (start + l).min(total - 1);
            &indices[w * media..(w + 1) * media]
        });
        let res = solve_lanes::<V>(
            medium,
            &spectrum.repeats,
            V::from_array(*k0),
            idx,
            thicknesses_nm,
            *wl,
            [cos_theta0; LANES],
        );
        sink.take(g, &res);
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn spectrum_avx2(
    spectrum: &Spectrum,
    indices: &[C64],
    thicknesses_nm: &[f64],
    cos_theta0: f64,
    out: &mut [Response],
) {
    let sink = &mut Store(out);
    spectrum_body::<avx2::Avx2>(spectrum, indices, thicknesses_nm, cos_theta0, sink)
}

fn spectrum_portable(
    spectrum: &Spectrum,
    indices: &[C64],
    thicknesses_nm: &[f64],
    cos_theta0: f64,
    out: &mut [Response],
) {
    let sink = &mut Store(out);
    spectrum_body::<Portable>(spectrum, indices, thicknesses_nm, cos_theta0, sink)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn weighted_avx2(
    spectrum: &Spectrum,
    indices: &[C64],
    thicknesses_nm: &[f64],
    cos_theta0: f64,
    weights: &SpectralWeights,
) -> WeightedPower {
    let mut sink = Integrate::<avx2::Avx2>::new(weights);
    spectrum_body(spectrum, indices, thicknesses_nm, cos_theta0, &mut sink);
    sink.finish()
}

fn weighted_portable(
    spectrum: &Spectrum,
    indices: &[C64],
    thicknesses_nm: &[f64],
    cos_theta0: f64,
    weights: &SpectralWeights,
) -> WeightedPower {
    let mut sink = Integrate::<Portable>::new(weights);
    spectrum_body(spectrum, indices, thicknesses_nm, cos_theta0, &mut sink);
    sink.finish()
}

/// The lengths [`solve_spectrum_on`] and [`weighted_spectrum_on`] need.
fn check_spectrum_lengths(spectrum: &Spectrum, indices: &[C64], thicknesses_nm: &[f64]) {
    assert_eq!(spectrum.media, thicknesses_nm.len() + 2, "media");
    assert_eq!(
        indices.len(),
        spectrum.media * spectrum.wavelengths,
        "indices"
    );
}

/// R and T at every wavelength of `spectrum` at one angle, into `out` (one
/// per wavelength). `indices` are the same indices, wavelength-major (for
/// the lanes the scalar solver takes over); `thicknesses_nm` the N layers'.
///
/// # Panics
/// If the lengths disagree.
pub fn solve_spectrum_on(
    path: Path,
    spectrum: &Spectrum,
    indices: &[C64],
    thicknesses_nm: &[f64],
    cos_theta0: f64,
    out: &mut [Response],
) {
    check_spectrum_lengths(spectrum, indices, thicknesses_nm);
    assert_eq!(out.len(), spectrum.wavelengths, "out: one per wavelength");
    if out.is_empty() {
        return;
    }
    #[cfg(target_arch = "x86_64")]
    if path == Path::Best && avx2_available() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { spectrum_avx2(spectrum, indices, thicknesses_nm, cos_theta0, out) };
    }
    let _ = path;
    spectrum_portable(spectrum, indices, thicknesses_nm, cos_theta0, out)
}

/// The spectrum of [`solve_spectrum_on`] folded into `weights`' three
/// weighted sums of R and of T as it is solved, without being stored; the
/// sums have the bits of [`SpectralIntegrator`](crate::color::SpectralIntegrator)'s
/// dot product over the stored spectrum.
///
/// # Panics
/// If the lengths disagree (`weights` needs one weight per wavelength).
pub fn weighted_spectrum_on(
    path: Path,
    spectrum: &Spectrum,
    indices: &[C64],
    thicknesses_nm: &[f64],
    cos_theta0: f64,
    weights: &SpectralWeights,
) -> WeightedPower {
    check_spectrum_lengths(spectrum, indices, thicknesses_nm);
    assert_eq!(
        weights.len(),
        spectrum.wavelengths,
        "weights: one per wavelength"
    );
    if weights.is_empty() {
        return WeightedPower::default();
    }
    #[cfg(target_arch = "x86_64")]
    if path == Path::Best && avx2_available() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { weighted_avx2(spectrum, indices, thicknesses_nm, cos_theta0, weights) };
    }
    let _ = path;
    weighted_portable(spectrum, indices, thicknesses_nm, cos_theta0, weights)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn batch_avx2(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    out: &mut [Response],
) {
    batch_body::<avx2::Avx2>(indices, thicknesses_nm, wavelengths_nm, cos_theta0, out)
}

fn batch_portable(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    out: &mut [Response],
) {
    batch_body::<Portable>(indices, thicknesses_nm, wavelengths_nm, cos_theta0, out)
}

/// Which copy of the kernel runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// AVX2 when the CPU has it (checked at run time), portable otherwise.
    Best,
    /// The portable copy, whatever the CPU (for tests and comparisons).
    Portable,
}

/// True when [`Path::Best`] runs the AVX2 copy on this CPU.
pub fn avx2_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// [`solve_batch`](super::solver::solve_batch) on a chosen copy of the
/// kernel; the lengths must already agree (the caller checks them).
pub fn solve_batch_on(
    path: Path,
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    out: &mut [Response],
) {
    if cos_theta0.is_empty() || out.is_empty() {
        return;
    }
    #[cfg(target_arch = "x86_64")]
    if path == Path::Best && avx2_available() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { batch_avx2(indices, thicknesses_nm, wavelengths_nm, cos_theta0, out) };
    }
    let _ = path;
    batch_portable(indices, thicknesses_nm, wavelengths_nm, cos_theta0, out)
}
