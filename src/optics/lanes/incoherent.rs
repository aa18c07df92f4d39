//! Stacks with incoherent layers in the kernels' loops: each vector of
//! points is solved by [`solve_mixed`] point by point and handed to the same
//! sinks as the coherent kernels, so a spectrum folded into a colour has the
//! bits of integrating the stored one.

use num_complex::Complex64 as C64;

use super::arith::{Lanes, MAX_LANES};
use super::sink::{Power, Sink, Store};
use super::spectrum::Spectrum;
use crate::optics::incoherent::{solve_mixed, Coherence};
use crate::optics::solver::Response;

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
        let mut res = [Response::default(); MAX_LANES];
        for (l, r) in res.iter_mut().enumerate().take(V::WIDTH) {
            let w = (start + l).min(total - 1);
            *r = solve_mixed(
                &indices[w * media..(w + 1) * media],
                thicknesses_nm,
                coherence,
                spectrum.wavelengths_nm()[w],
                cos_theta0,
            );
        }
        sink.take(start, &Power::from_responses(&res));
    }
}

/// Every (wavelength, angle) pair, wavelength-major, into `out`.
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
    let n_angles = cos_theta0.len();
    let total = out.len();
    for start in (0..total).step_by(V::WIDTH) {
        let mut res = [Response::default(); MAX_LANES];
        for (l, r) in res.iter_mut().enumerate().take(V::WIDTH) {
            let i = (start + l).min(total - 1);
            let (w, a) = (i / n_angles, i % n_angles);
            *r = solve_mixed(
                &indices[w * media..(w + 1) * media],
                thicknesses_nm,
                coherence,
                wavelengths_nm[w],
                cos_theta0[a],
            );
        }
        Store(&mut *out).take(start, &Power::<V>::from_responses(&res));
    }
}
