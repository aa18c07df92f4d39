//! The solver of [`super::solver`] on several (wavelength, angle) pairs of
//! one stack at once: every complex quantity of the recursion is held as its
//! real parts and its imaginary parts, one per lane, so that one instruction
//! advances four lanes (AVX2) or eight (AVX-512).
//!
//! The arithmetic is the scalar recursion's (the same products and sums in
//! the same order, the same branch of every square root). It departs from
//! [`solve`](super::solver::solve) only where speed asks: e^x, sin and cos come from a range
//! reduction and a polynomial instead of the C library, a complex
//! reciprocal takes one division and two products instead of two divisions,
//! and a complex product fuses each part's sum into its first product.
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
//! reduction's exact range (`PHASE_LIMIT`, 10⁵ rad) is computed with the C
//! library.
//!
//! Gain layers and evanescent gaps need nothing of their own: the branch
//! Im q ≥ 0 keeps every factor bounded, exactly as in the scalar solver.
//!
//! The kernel is generic over its lane type, and three copies are compiled:
//! AVX-512 (eight lanes per register), AVX2 (four) and portable (an array of
//! four). [`Path::Best`] picks the widest the CPU has, at run time. All
//! perform the same IEEE operations in the same order on each lane, so they
//! agree bit for bit: Rust never fuses a multiply and an add on its own, and
//! where the polynomials fuse them on purpose (one rounding, and a shorter
//! chain of dependent operations) every copy does, the portable one through
//! `f64::mul_add`. The AVX2 copy therefore also needs FMA, which every CPU
//! with AVX2 in practice has.
//! On a CPU that runs the kernel's chain of dependent operations at the
//! same latency in either width (as AMD's Zen 4 runs 512-bit operations
//! in two halves), eight lanes still help: each instruction carries twice
//! the points, so the out-of-order window holds twice as many independent
//! wavelengths.

mod arith;
mod constant;
mod general;
mod gradient;
mod incoherent;
mod mixed_gradient;
mod sink;
mod spectrum;
#[cfg(target_arch = "x86_64")]
mod x86;

pub use arith::MAX_LANES;
use arith::{Lanes, Portable};
use general::{batch_body, points_body, spectrum_body};
pub use gradient::GradientSink;
use sink::{Integrate, Store};
pub use sink::{SpectralWeights, WeightedPower};
pub use spectrum::Spectrum;

use num_complex::Complex64 as C64;

use super::incoherent::Coherence;
use super::solver::Response;

/// Which copy of the kernel runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// The widest the CPU has (checked at run time): AVX-512, AVX2 or
    /// portable.
    Best,
    /// The AVX2 copy when the CPU has AVX2, portable otherwise (for tests
    /// and comparisons).
    Avx2,
    /// The portable copy, whatever the CPU (for tests and comparisons).
    Portable,
}

/// A kernel copy the CPU can run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum KernelCopy {
    #[cfg(target_arch = "x86_64")]
    Avx512,
    #[cfg(target_arch = "x86_64")]
    Avx2,
    Portable,
}

impl Path {
    fn copy(self) -> KernelCopy {
        #[cfg(target_arch = "x86_64")]
        {
            if self == Path::Best && avx512_available() {
                return KernelCopy::Avx512;
            }
            if self != Path::Portable && avx2_available() {
                return KernelCopy::Avx2;
            }
        }
        KernelCopy::Portable
    }
}

/// True when the CPU has AVX2 and FMA, so that [`Path::Avx2`] runs the
/// AVX2 copy.
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

/// True when the CPU has AVX-512F, so that [`Path::Best`] runs the AVX-512
/// copy.
pub fn avx512_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx512f")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// The name of the copy [`Path::Best`] runs on this CPU: "AVX-512", "AVX2"
/// or "portable".
pub fn best_copy() -> &'static str {
    match Path::Best.copy() {
        #[cfg(target_arch = "x86_64")]
        KernelCopy::Avx512 => "AVX-512",
        #[cfg(target_arch = "x86_64")]
        KernelCopy::Avx2 => "AVX2",
        KernelCopy::Portable => "portable",
    }
}

/// Defines `$name(path, args…)`, which runs `$body` (generic over the lane
/// type `$V`) in the copy `path` picks: compiled for AVX-512F, for AVX2, or
/// portable.
macro_rules! kernel_copies {
    (
        fn $name:ident<$V:ident>($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty $body:block
    ) => {
        fn $name(path: Path, $($arg: $ty),*) -> $ret {
            #[inline(always)]
            fn body<$V: Lanes>($($arg: $ty),*) -> $ret $body

            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx512f")]
            fn avx512($($arg: $ty),*) -> $ret {
                body::<x86::Avx512>($($arg),*)
            }

            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2,fma")]
            fn avx2($($arg: $ty),*) -> $ret {
                body::<x86::Avx2>($($arg),*)
            }

            match path.copy() {
                // SAFETY: `Path::copy` picks this copy only when the CPU
                // has AVX-512F.
                #[cfg(target_arch = "x86_64")]
                KernelCopy::Avx512 => unsafe { avx512($($arg),*) },
                // SAFETY: likewise, only when the CPU has AVX2.
                #[cfg(target_arch = "x86_64")]
                KernelCopy::Avx2 => unsafe { avx2($($arg),*) },
                KernelCopy::Portable => body::<Portable>($($arg),*),
            }
        }
    };
}

kernel_copies! {
    fn spectrum_copies<V>(
        spectrum: &Spectrum,
        indices: &[C64],
        thicknesses_nm: &[f64],
        coherence: &Coherence,
        cos_theta0: f64,
        out: &mut [Response],
    ) -> () {
        let sink = &mut Store(out);
        if coherence.is_coherent() {
            spectrum_body::<V>(spectrum, indices, thicknesses_nm, cos_theta0, sink)
        } else {
            incoherent::spectrum_body::<V>(spectrum, indices, thicknesses_nm, coherence, cos_theta0, sink)
        }
    }
}

kernel_copies! {
    fn weighted_copies<V>(
        spectrum: &Spectrum,
        indices: &[C64],
        thicknesses_nm: &[f64],
        coherence: &Coherence,
        cos_theta0: f64,
        weights: &SpectralWeights,
    ) -> WeightedPower {
        let mut sink = Integrate::new(weights);
        if coherence.is_coherent() {
            spectrum_body::<V>(spectrum, indices, thicknesses_nm, cos_theta0, &mut sink);
        } else {
            incoherent::spectrum_body::<V>(spectrum, indices, thicknesses_nm, coherence, cos_theta0, &mut sink);
        }
        sink.finish()
    }
}

kernel_copies! {
    fn batch_copies<V>(
        indices: &[C64],
        thicknesses_nm: &[f64],
        coherence: &Coherence,
        wavelengths_nm: &[f64],
        cos_theta0: &[f64],
        out: &mut [Response],
    ) -> () {
        if coherence.is_coherent() {
            batch_body::<V>(indices, thicknesses_nm, wavelengths_nm, cos_theta0, out)
        } else {
            incoherent::batch_body::<V>(indices, thicknesses_nm, coherence, wavelengths_nm, cos_theta0, out)
        }
    }
}

kernel_copies! {
    fn points_copies<V>(
        layers: usize,
        indices: &[C64],
        thicknesses_nm: &[f64],
        wavelengths_nm: &[f64],
        cos_theta0: &[f64],
        out: &mut [Response],
    ) -> () {
        points_body::<V>(layers, indices, thicknesses_nm, wavelengths_nm, cos_theta0, out)
    }
}

kernel_copies! {
    fn gradient_copies<V>(
        indices: &[C64],
        thicknesses_nm: &[f64],
        wavelengths_nm: &[f64],
        cos_theta0: &[f64],
        sink: &mut GradientSink<'_>,
    ) -> () {
        gradient::gradient_body::<V>(indices, thicknesses_nm, wavelengths_nm, cos_theta0, sink)
    }
}

/// R, T and their derivatives by every layer's thickness at every
/// (wavelength, angle) point of a coherent stack, `indices`
/// wavelength-major (N + 2 per wavelength), into `sink` (the layout is
/// [`GradientSink`]'s). Points at grazing incidence or with a layer near
/// its critical angle are not solved but listed in `sink.fallback`, for
/// the scalar gradient (`optics::gradient`) to fill.
///
/// # Panics
/// If the lengths disagree.
pub fn gradient_grid_on(
    path: Path,
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    sink: &mut GradientSink<'_>,
) {
    let points = wavelengths_nm.len() * cos_theta0.len();
    assert_eq!(
        indices.len(),
        (thicknesses_nm.len() + 2) * wavelengths_nm.len(),
        "indices"
    );
    assert_eq!(sink.response.len(), points, "response");
    assert_eq!(sink.amplitudes.len(), points, "amplitudes");
    for d in &sink.d {
        assert_eq!(d.len(), points * thicknesses_nm.len(), "derivatives");
    }
    if points == 0 {
        return;
    }
    gradient_copies(
        path,
        indices,
        thicknesses_nm,
        wavelengths_nm,
        cos_theta0,
        sink,
    )
}

kernel_copies! {
    fn mixed_gradient_copies<V>(
        indices: &[C64],
        thicknesses_nm: &[f64],
        coherence: &Coherence,
        wavelengths_nm: &[f64],
        cos_theta0: &[f64],
        sink: &mut GradientSink<'_>,
    ) -> () {
        mixed_gradient::mixed_gradient_body::<V>(
            indices, thicknesses_nm, coherence, wavelengths_nm, cos_theta0, sink,
        )
    }
}

/// [`gradient_grid_on`] for a stack with incoherent layers (`coherence`):
/// the same layout, `sink.amplitudes` left alone (a mixed stack has none).
/// Points at grazing incidence, with a near-critical layer inside a
/// coherent group, an opaque incoherent layer, or where an incoherent layer
/// lases are listed in `sink.fallback` for the scalar gradient.
///
/// # Panics
/// If the lengths disagree.
pub fn mixed_gradient_grid_on(
    path: Path,
    indices: &[C64],
    thicknesses_nm: &[f64],
    coherence: &Coherence,
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    sink: &mut GradientSink<'_>,
) {
    let points = wavelengths_nm.len() * cos_theta0.len();
    assert_eq!(
        indices.len(),
        (thicknesses_nm.len() + 2) * wavelengths_nm.len(),
        "indices"
    );
    assert_eq!(sink.response.len(), points, "response");
    for d in &sink.d {
        assert_eq!(d.len(), points * thicknesses_nm.len(), "derivatives");
    }
    if points == 0 {
        return;
    }
    mixed_gradient_copies(
        path,
        indices,
        thicknesses_nm,
        coherence,
        wavelengths_nm,
        cos_theta0,
        sink,
    )
}

kernel_copies! {
    fn one_way_copies<V>(phases: &[C64; MAX_LANES]) -> [C64; MAX_LANES] {
        let mut out = [C64::new(0.0, 0.0); MAX_LANES];
        for start in (0..MAX_LANES).step_by(V::WIDTH) {
            let (mut re, mut im) = ([0.0; MAX_LANES], [0.0; MAX_LANES]);
            for (l, z) in phases[start..].iter().enumerate() {
                (re[l], im[l]) = (z.re, z.im);
            }
            let z = arith::one_way(arith::Cv {
                re: V::from_array(re),
                im: V::from_array(im),
            });
            let (re, im) = (z.re.to_array(), z.im.to_array());
            for (l, o) in out[start..start + V::WIDTH].iter_mut().enumerate() {
                *o = C64::new(re[l], im[l]);
            }
        }
        out
    }
}

/// e^{iφ} for eight phases φ at once, as the lanes compute a layer's
/// one-way factor: e^{−Im φ} (cos Re φ + i sin Re φ), within an ulp or a
/// few of the C library's (`tests/batched.rs`). For callers that need a
/// handful of scattered exponentials, such as the baker's exact phase at
/// the start of each stretch of thickness nodes.
pub fn one_way_many(path: Path, phases: &[C64; MAX_LANES]) -> [C64; MAX_LANES] {
    one_way_copies(path, phases)
}

/// The lengths [`solve_spectrum_on`] and [`weighted_spectrum_on`] need.
fn check_spectrum_lengths(spectrum: &Spectrum, indices: &[C64], thicknesses_nm: &[f64]) {
    assert_eq!(spectrum.media(), thicknesses_nm.len() + 2, "media");
    assert_eq!(
        indices.len(),
        spectrum.media() * spectrum.wavelengths(),
        "indices"
    );
}

/// R and T at every wavelength of `spectrum` at one angle, into `out` (one
/// per wavelength). `indices` are the same indices, wavelength-major (for
/// the lanes the scalar solver takes over); `thicknesses_nm` the N layers';
/// `coherence` which of them are incoherent (a lasing point of an
/// incoherent gain layer comes out as +∞, as
/// [`solve_mixed`](super::incoherent::solve_mixed) gives it).
///
/// # Panics
/// If the lengths disagree.
pub fn solve_spectrum_on(
    path: Path,
    spectrum: &Spectrum,
    indices: &[C64],
    thicknesses_nm: &[f64],
    coherence: &Coherence,
    cos_theta0: f64,
    out: &mut [Response],
) {
    check_spectrum_lengths(spectrum, indices, thicknesses_nm);
    assert_eq!(out.len(), spectrum.wavelengths(), "out: one per wavelength");
    if out.is_empty() {
        return;
    }
    spectrum_copies(
        path,
        spectrum,
        indices,
        thicknesses_nm,
        coherence,
        cos_theta0,
        out,
    )
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
    coherence: &Coherence,
    cos_theta0: f64,
    weights: &SpectralWeights,
) -> WeightedPower {
    check_spectrum_lengths(spectrum, indices, thicknesses_nm);
    assert_eq!(
        weights.len(),
        spectrum.wavelengths(),
        "weights: one per wavelength"
    );
    if weights.is_empty() {
        return WeightedPower::default();
    }
    weighted_copies(
        path,
        spectrum,
        indices,
        thicknesses_nm,
        coherence,
        cos_theta0,
        weights,
    )
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
    solve_batch_mixed_on(
        path,
        indices,
        thicknesses_nm,
        &Coherence::coherent(),
        wavelengths_nm,
        cos_theta0,
        out,
    )
}

/// [`solve_batch_on`] for a stack with incoherent layers (`coherence`);
/// a lasing point of an incoherent gain layer comes out as +∞, as
/// [`solve_mixed`](super::incoherent::solve_mixed) gives it.
pub fn solve_batch_mixed_on(
    path: Path,
    indices: &[C64],
    thicknesses_nm: &[f64],
    coherence: &Coherence,
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    out: &mut [Response],
) {
    if cos_theta0.is_empty() || out.is_empty() {
        return;
    }
    batch_copies(
        path,
        indices,
        thicknesses_nm,
        coherence,
        wavelengths_nm,
        cos_theta0,
        out,
    )
}

/// R and T at arbitrary points of one stack of `layers` layers, on a chosen
/// copy of the kernel: point i has its own indices (`indices[i(N+2)..
/// (i+1)(N+2)]`: ambient, layers, substrate), thicknesses
/// (`thicknesses_nm[iN..(i+1)N]`), wavelength and cos θ0, and its result
/// goes to `out[i]`. The preconditions are [`solve`](super::solver::solve)'s
/// for every point; nothing is allocated.
///
/// # Panics
/// If the lengths disagree.
pub fn solve_points_on(
    path: Path,
    layers: usize,
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    out: &mut [Response],
) {
    let points = out.len();
    assert_eq!(
        indices.len(),
        (layers + 2) * points,
        "indices: N + 2 per point"
    );
    assert_eq!(
        thicknesses_nm.len(),
        layers * points,
        "thicknesses: N per point"
    );
    assert_eq!(wavelengths_nm.len(), points, "wavelengths: one per point");
    assert_eq!(cos_theta0.len(), points, "cos θ0: one per point");
    if points == 0 {
        return;
    }
    points_copies(
        path,
        layers,
        indices,
        thicknesses_nm,
        wavelengths_nm,
        cos_theta0,
        out,
    )
}
