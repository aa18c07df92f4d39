//! Stacks that mix coherent films with incoherent (thick) layers: a coating
//! on a millimetre of glass, a coated window, films on both faces of a slide.
//!
//! A layer much thicker than the light's coherence length has no stable
//! phase: the waves bouncing inside it add in power, not in amplitude. The
//! formulation is Byrnes' `tmm.inc_tmm` (S. J. Byrnes, "Multilayer optical
//! calculations", arXiv:1603.02720, section 5, after C. C. Katsidis and
//! D. I. Siapkas, Appl. Opt. 41, 3978 (2002), and E. Centurioni, Appl. Opt.
//! 44, 7532 (2005)): the ambient, the substrate and every incoherent layer
//! are incoherent media; the coherent layers between two of them form a
//! group, solved exactly by the coherent recursion with those two media as
//! its half-spaces; and power is summed over the round trips inside each
//! incoherent layer, which keeps a fraction P = |e^{i k0 q d}|² =
//! e^{−2 k0 Im(q) d} of its power per pass (Byrnes' exp(−4π d Im(n cos θ)/λ)).
//!
//! Written bottom up, as the coherent solver is: with ρ the power reflectance
//! seen from inside an incoherent layer looking down (its lower group and all
//! below) and τ the product of the |t|² down to the substrate, crossing the
//! layer and the group above it (amplitudes r, t from above, r', t' from
//! below) gives
//!
//! ```text
//! ρ ← |r|² + |t t'|² P² ρ / (1 − |r'|² P² ρ)        τ ← |t|² P τ / (1 − |r'|² P² ρ)
//! ```
//!
//! and at the top R = ρ, T = τ times the Poynting factor of the substrate
//! over the incident flux, as in [`solve`]. This is `inc_tmm`'s product of
//! power matrices with every |t|² flux factor of an intermediate medium
//! cancelled (they appear as T_{i,j} T_{j,i}), so nothing is divided by the
//! power a wave carries in a layer. It is also the average of the coherent
//! answer over the layer's phase: the incoherent layer is what a coherent
//! one becomes when its thickness varies over more than a wavelength.
//!
//! Three decisions where `inc_tmm` is silent or wrong:
//! - **Evanescent layers.** A lossless layer beyond its critical angle (q
//!   purely imaginary, or 0) carries no propagating wave, and through a
//!   layer as thick as incoherent layers are the decaying wave brings
//!   nothing across: the layer reflects as a half-space would (totally,
//!   when everything above is lossless), and T = 0. This continues what a
//!   propagating layer gives as it nears its critical angle, where its
//!   interfaces' transmission goes to 0. A thin layer would let light
//!   tunnel, but that is a coherent effect: such a layer is coherent.
//!   (`inc_tmm` takes arcsin's principal branch there, so that its
//!   "incoherent" power grows through the layer and its R can be negative.)
//! - **Gain** (k < 0) in an incoherent layer: the wave is taken on the
//!   branch that carries power forward (Re q > 0, growing, P > 1). The sum
//!   over round trips converges only while |r'|² P² ρ < 1, which gain in
//!   the layer, or a coherent gain film beside it reflecting more than it
//!   receives, can break. Past that the layer lases and has no steady
//!   state: [`solve_incoherent`] returns [`Diverged`], and the callers
//!   refuse the stack there with one line (`inc_tmm` refuses gain in any
//!   medium next to an incoherent one, and returns negative powers for a
//!   coherent gain film that makes a layer lase).
//! - **Opaque layers.** P underflows to 0 and no power crosses, exactly
//!   (`inc_tmm` clamps P at 1e-30 to avoid dividing by it).
//!
//! A zero-thickness incoherent layer still adds its two interfaces' powers
//! (P = 1), as in `inc_tmm`: unlike a coherent layer it does not vanish.

use std::f64::consts::TAU;

use num_complex::Complex64 as C64;

use super::solver::{grazing, recurse_media, sin_sq, solve, sqrt_upper, Amplitudes, Response};
use crate::error::Error;

/// Which layers of a stack are incoherent: what the mixed solvers take
/// beside the indices and thicknesses. The default is every layer coherent.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash)]
pub struct Coherence {
    /// Layer numbers (1-based from the ambient side, which is also their
    /// position among the media) of the incoherent layers, ascending.
    incoherent: Vec<usize>,
}

impl Coherence {
    /// Every layer coherent: the mixed solvers are then the coherent ones.
    pub fn coherent() -> Coherence {
        Coherence::default()
    }

    /// One flag per layer, top down: `true` for coherent.
    pub fn from_flags<I: IntoIterator<Item = bool>>(coherent: I) -> Coherence {
        Coherence {
            incoherent: coherent
                .into_iter()
                .enumerate()
                .filter(|&(_, c)| !c)
                .map(|(i, _)| i + 1)
                .collect(),
        }
    }

    /// True when no layer is incoherent.
    pub fn is_coherent(&self) -> bool {
        self.incoherent.is_empty()
    }

    /// The incoherent layers' numbers, 1-based from the ambient side, ascending.
    pub fn incoherent_layers(&self) -> &[usize] {
        &self.incoherent
    }

    /// True when layer `layer` (1-based) is coherent.
    pub fn is_layer_coherent(&self, layer: usize) -> bool {
        self.incoherent.binary_search(&layer).is_err()
    }

    /// The same layers seen from the substrate side, for a stack of
    /// `layers` layers (as [`Stack::reversed`](super::Stack::reversed)).
    pub fn reversed(&self, layers: usize) -> Coherence {
        Coherence {
            incoherent: self
                .incoherent
                .iter()
                .rev()
                .map(|&l| layers + 1 - l)
                .collect(),
        }
    }
}

/// Where an incoherent layer with gain returns at least as much power per
/// round trip as it receives: the layer lases, and its multiple reflections
/// have no finite sum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Diverged {
    /// The incoherent layer, 1-based from the ambient side.
    pub layer: usize,
    /// |r'|² P² ρ: the fraction of its power a wave brings back after one
    /// round trip in the layer (≥ 1, or not a number when P overflows).
    pub round_trip: f64,
}

impl Diverged {
    /// The one-line error for this point (`wavelength_nm`, `cos_theta0`),
    /// naming the layer.
    pub fn error(&self, wavelength_nm: f64, cos_theta0: f64) -> Error {
        let angle = cos_theta0.clamp(-1.0, 1.0).acos().to_degrees();
        let gain = if self.round_trip.is_finite() {
            format!(
                "a wave in it comes back with {:.6} times its power after each round trip",
                self.round_trip
            )
        } else {
            "it amplifies beyond any finite power".to_string()
        };
        Error::invalid(
            format!("layers[{}]", self.layer),
            format!(
                "this incoherent layer lases at {wavelength_nm} nm, {angle:.4}°: {gain} \
                 (gain in it or in the layers around it), so its multiple reflections \
                 have no finite sum"
            ),
        )
    }
}

/// n² − β² of a medium of index `n` seen from an ambient of index `n0`
/// with q0 = n0 cos θ0, written (n² − n0²) + q0²: near grazing incidence
/// n² − β² cancels to a few ulps of n0², while this form is exact for a
/// medium of the ambient's index (a sheet of glass in air has air below it)
/// and loses nothing elsewhere.
#[inline]
pub(super) fn normal_index_sq(n: C64, n0: f64, q0: f64) -> C64 {
    (n * n - n0 * n0) + q0 * q0
}

/// q of an incoherent medium on the branch that carries power forward
/// (Re q > 0: growing when the medium has gain), from z = n² − β²
/// ([`normal_index_sq`]); `None` when the medium is lossless and its wave
/// evanescent or grazing (z ≤ 0): it carries no power, and the layer is
/// opaque (see the module's text).
#[inline]
pub(super) fn carrying_index(n: C64, z: C64) -> Option<C64> {
    if n.im == 0.0 && z.re <= 0.0 {
        return None;
    }
    let q = sqrt_upper(z);
    Some(if q.re < 0.0 { -q } else { q })
}

/// The fraction of its power a wave keeps over one pass through an
/// incoherent layer of normal index `q` (on [`carrying_index`]'s branch)
/// and thickness `d`: e^{−2 k0 Im(q) d}, above 1 with gain.
#[inline]
pub(super) fn one_pass(k0: f64, q: C64, thickness_nm: f64) -> f64 {
    // k0 d first: a zero thickness gives exactly 1 even when Im q is large.
    (-2.0 * (k0 * thickness_nm) * q.im).exp()
}

/// ρ and τ of one polarization (see the module's text) carried up through
/// an incoherent layer and the group above it: `down` the group's r, t from
/// above, `up` its r', t' from below, `pass` the layer's P.
#[inline]
pub(super) fn through_layer(
    (rho, tau): (f64, f64),
    (down_r, down_t): (C64, C64),
    (up_r, up_t): (C64, C64),
    pass: f64,
    layer: usize,
) -> Result<(f64, f64), Diverged> {
    let returned = pass * pass * rho;
    let round_trip = up_r.norm_sqr() * returned;
    // NaN (∞ · 0, from an overflowing P) diverges too.
    if round_trip >= 1.0 || round_trip.is_nan() || !returned.is_finite() {
        return Err(Diverged { layer, round_trip });
    }
    let inv = 1.0 / (1.0 - round_trip);
    Ok((
        down_r.norm_sqr() + (down_t * up_t).norm_sqr() * returned * inv,
        down_t.norm_sqr() * pass * tau * inv,
    ))
}

/// R and T of a stack whose layers are coherent or incoherent as
/// `coherence` says: [`solve`]'s arguments and conventions (indices of the
/// ambient, the N layers and the substrate; N thicknesses), and its answer
/// when every layer is coherent. Nothing is allocated.
///
/// # Errors
/// [`Diverged`] where an incoherent gain layer lases (see the module's text).
pub fn solve_incoherent(
    indices: &[C64],
    thicknesses_nm: &[f64],
    coherence: &Coherence,
    wavelength_nm: f64,
    cos_theta0: f64,
) -> Result<Response, Diverged> {
    debug_assert_eq!(indices.len(), thicknesses_nm.len() + 2);
    if coherence.is_coherent() {
        return Ok(solve(indices, thicknesses_nm, wavelength_nm, cos_theta0));
    }
    if cos_theta0 <= 0.0 {
        return Ok(grazing(indices));
    }
    let cos_theta0 = cos_theta0.min(1.0);
    let n0 = indices[0].re;
    let beta_sq = n0 * n0 * sin_sq(cos_theta0);
    let k0 = TAU / wavelength_nm;
    let last = indices.len() - 1;
    let n_sub = indices[last];
    let q0 = n0 * cos_theta0;
    let q_sub = sqrt_upper(normal_index_sq(n_sub, n0, q0));

    // The incoherent medium at the bottom of the group being added: its
    // position, index and q. The recursion climbs from the substrate.
    let (mut below, mut n_below, mut q_below) = (last, n_sub, q_sub);
    let mut state: Option<[(f64, f64); 2]> = None;
    // Below an opaque (evanescent) incoherent layer nothing matters: the
    // recursion starts again from it as from a substrate, and T = 0.
    let mut opaque = false;
    let mut strongest = (0, 0.0);
    for &m in coherence.incoherent.iter().rev().chain(std::iter::once(&0)) {
        let (n, q) = if m == 0 {
            (C64::new(n0, 0.0), C64::new(q0, 0.0))
        } else {
            let n = indices[m];
            let z = normal_index_sq(n, n0, q0);
            match carrying_index(n, z) {
                Some(q) => (n, q),
                None => {
                    (state, opaque) = (None, true);
                    (below, n_below, q_below) = (m, n, sqrt_upper(z));
                    continue;
                }
            }
        };
        let media = below - m + 1;
        let down = recurse_media(
            media,
            |j| indices[m + j],
            |j| thicknesses_nm[m + j],
            wavelength_nm,
            beta_sq,
            [n, n * n, q],
            q_below,
        );
        state = Some(match state {
            None => [
                (down.rs.norm_sqr(), down.ts.norm_sqr()),
                (down.rp.norm_sqr(), down.tp.norm_sqr()),
            ],
            Some([s, p]) => {
                let up = recurse_media(
                    media,
                    |j| indices[below - j],
                    |j| thicknesses_nm[below - j - 2],
                    wavelength_nm,
                    beta_sq,
                    [n_below, n_below * n_below, q_below],
                    q,
                );
                let pass = one_pass(k0, q_below, thicknesses_nm[below - 1]);
                if pass > strongest.1 || pass.is_nan() {
                    strongest = (below, pass);
                }
                let Amplitudes { rs, rp, ts, tp } = down;
                [
                    through_layer(s, (rs, ts), (up.rs, up.ts), pass, below)?,
                    through_layer(p, (rp, tp), (up.rp, up.tp), pass, below)?,
                ]
            }
        });
        (below, n_below, q_below) = (m, n, q);
    }
    let [(rs, ts), (rp, tp)] = state.expect("the ambient closes the recursion");
    let p_flux = (q_sub.conj() * n_sub * n_sub).re / n_sub.norm_sqr();
    let response = if opaque {
        Response {
            rs,
            rp,
            ts: 0.0,
            tp: 0.0,
        }
    } else {
        Response {
            rs,
            rp,
            ts: ts * q_sub.re / q0,
            tp: tp * p_flux / q0,
        }
    };
    if [rs, rp, response.ts, response.tp]
        .iter()
        .all(|x| x.is_finite())
    {
        Ok(response)
    } else {
        // Finite round trips whose gain still overflows the sum.
        Err(Diverged {
            layer: strongest.0,
            round_trip: f64::INFINITY,
        })
    }
}

/// [`solve_incoherent`] with a lasing point given as R = T = +∞ in every
/// polarization, for the batched loops, which keep going and let their
/// caller find such points ([`Response::is_finite`]).
#[inline]
pub fn solve_mixed(
    indices: &[C64],
    thicknesses_nm: &[f64],
    coherence: &Coherence,
    wavelength_nm: f64,
    cos_theta0: f64,
) -> Response {
    solve_incoherent(
        indices,
        thicknesses_nm,
        coherence,
        wavelength_nm,
        cos_theta0,
    )
    .unwrap_or(Response {
        rs: f64::INFINITY,
        rp: f64::INFINITY,
        ts: f64::INFINITY,
        tp: f64::INFINITY,
    })
}
