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

mod split;

use std::f64::consts::TAU;

use num_complex::Complex64 as C64;

use super::solver::{grazing, recurse_media, sin_sq, solve, sqrt_upper, Amplitudes, Response};
use crate::error::Error;
pub(crate) use split::{split, Env, Parts};

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
    /// What is wrong at this point (`wavelength_nm`, `cos_theta0`), for a
    /// message that names the layer in its caller's terms.
    pub fn reason(&self, wavelength_nm: f64, cos_theta0: f64) -> String {
        let angle = cos_theta0.clamp(-1.0, 1.0).acos().to_degrees();
        let gain = if self.round_trip.is_finite() {
            format!(
                "a wave in it comes back with {} times its power after each round trip",
                short_figure(self.round_trip)
            )
        } else {
            "it amplifies beyond any finite power".to_string()
        };
        format!(
            "this incoherent layer lases at {wavelength_nm} nm, {angle:.4}°: {gain} \
             (gain in it or in the layers around it), so its multiple reflections \
             have no finite sum"
        )
    }

    /// The one-line error for this point, naming the layer as a stack file
    /// does (`layers[K]`).
    pub fn error(&self, wavelength_nm: f64, cos_theta0: f64) -> Error {
        Error::invalid(
            format!("layers[{}]", self.layer),
            self.reason(wavelength_nm, cos_theta0),
        )
    }
}

/// A gain as a short figure: `1.000123` near the threshold of 1, where the
/// digits matter, `4.35e217` for a gain far above it, whose fixed-point
/// form runs to hundreds of digits.
fn short_figure(x: f64) -> String {
    if x.abs() < 1e3 {
        format!("{x:.6}")
    } else {
        format!("{x:.2e}")
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

/// A run of a stack's media read top down or bottom up, for the recursions
/// that climb sub-stacks in either direction without copying them. Media
/// are numbered from the view's top, 0 to [`View::len`] − 1.
#[derive(Clone, Copy)]
pub(super) struct View<'a> {
    indices: &'a [C64],
    /// The finite media's thicknesses: medium j's at j − 1 (original order).
    thicknesses_nm: &'a [f64],
    /// The position of the view's medium 0 in the whole stack.
    first: usize,
    reversed: bool,
}

impl<'a> View<'a> {
    /// A whole stack top down: `indices` N + 2, `thicknesses_nm` N.
    pub(super) fn stack(indices: &'a [C64], thicknesses_nm: &'a [f64]) -> View<'a> {
        View {
            indices,
            thicknesses_nm,
            first: 0,
            reversed: false,
        }
    }

    /// The stack's media `from..=to` (positions in the whole stack), read
    /// top down, or bottom up (the view's medium 0 is then `to`).
    pub(super) fn run(self, from: usize, to: usize, reversed: bool) -> View<'a> {
        debug_assert!(!self.reversed && self.first == 0 && from < to);
        View {
            indices: &self.indices[from..=to],
            thicknesses_nm: &self.thicknesses_nm[from..to - 1],
            first: from,
            reversed,
        }
    }

    #[inline(always)]
    pub(super) fn len(&self) -> usize {
        self.indices.len()
    }

    /// The view's medium `j` is the stack's medium at this position.
    #[inline(always)]
    pub(super) fn position(&self, j: usize) -> usize {
        self.first + if self.reversed { self.len() - 1 - j } else { j }
    }

    #[inline(always)]
    pub(super) fn index(&self, j: usize) -> C64 {
        self.indices[if self.reversed { self.len() - 1 - j } else { j }]
    }

    /// The thickness of the view's medium `j`, a finite layer (0 < j < len − 1).
    #[inline(always)]
    pub(super) fn thickness(&self, j: usize) -> f64 {
        self.thicknesses_nm[if self.reversed {
            self.len() - 2 - j
        } else {
            j - 1
        }]
    }

    /// The amplitudes of the view's media `top..=bottom` (view numbering) as
    /// one coherent group: `top_medium` (n, n², q) of its top medium, and the
    /// q of its bottom one.
    #[inline(always)]
    pub(super) fn group(
        &self,
        top: usize,
        bottom: usize,
        light: &Light,
        top_medium: [C64; 3],
        q_bottom: C64,
    ) -> Amplitudes {
        recurse_media(
            bottom - top + 1,
            |j| self.index(top + j),
            |j| self.thickness(top + j + 1),
            light.wavelength_nm,
            light.beta_sq,
            top_medium,
            q_bottom,
        )
    }
}

/// The incident light: what every medium's q is computed from.
#[derive(Clone, Copy, Debug)]
pub(super) struct Light {
    pub(super) wavelength_nm: f64,
    /// 2π/λ.
    pub(super) k0: f64,
    /// The ambient's (real) index.
    pub(super) n0: f64,
    /// q0 = n0 cos θ0.
    pub(super) q0: f64,
    /// β² = n0² sin² θ0.
    pub(super) beta_sq: f64,
}

impl Light {
    /// Light of `wavelength_nm` from an ambient of index `n0` at cos θ0
    /// (in (0, 1]).
    pub(super) fn new(wavelength_nm: f64, n0: f64, cos_theta0: f64) -> Light {
        Light {
            wavelength_nm,
            k0: TAU / wavelength_nm,
            n0,
            q0: n0 * cos_theta0,
            beta_sq: n0 * n0 * sin_sq(cos_theta0),
        }
    }

    /// n² − β² of a medium ([`normal_index_sq`]).
    #[inline]
    pub(super) fn normal_index_sq(&self, n: C64) -> C64 {
        normal_index_sq(n, self.n0, self.q0)
    }
}

/// What the incoherent recursion leaves at the top of a view.
#[derive(Clone, Copy, Debug)]
pub(super) struct Climbed {
    /// Per polarization (s, p): ρ, the power reflectance seen from the
    /// view's top medium, and τ, the product of the |t|² and P down to its
    /// bottom medium.
    pub(super) sums: [(f64, f64); 2],
    /// An opaque layer (see the module's text) cut the view: nothing below
    /// it counts, and no power reaches the bottom (τ means nothing).
    pub(super) opaque: bool,
    /// The incoherent layer with the largest P crossed (its position, P),
    /// to name when the sums overflow.
    pub(super) strongest: (usize, f64),
}

/// The incoherent recursion (see the module's text) up a view: its bottom
/// medium a half-space of normal index `q_bottom`, its top medium given as
/// (n, n², q), and the view's media at `incoherent` (view numbering,
/// ascending, each strictly between top and bottom) incoherent layers.
pub(super) fn climb(
    view: View<'_>,
    incoherent: impl DoubleEndedIterator<Item = usize>,
    light: &Light,
    top_medium: [C64; 3],
    q_bottom: C64,
) -> Result<Climbed, Diverged> {
    let last = view.len() - 1;
    // The incoherent medium at the bottom of the group being added: its
    // view number and (n, q).
    let (mut below, mut n_below, mut q_below) = (last, view.index(last), q_bottom);
    let mut state: Option<[(f64, f64); 2]> = None;
    // Below an opaque incoherent layer nothing matters: the recursion
    // starts again from it as from a half-space, and T = 0.
    let mut opaque = false;
    let mut strongest = (0, 0.0);
    for m in incoherent.rev().chain(std::iter::once(0)) {
        let (n, q) = if m == 0 {
            (top_medium[0], top_medium[2])
        } else {
            let n = view.index(m);
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
        let down = view.group(m, below, light, top, q_below);
        state = Some(match state {
            None => [
                (down.rs.norm_sqr(), down.ts.norm_sqr()),
                (down.rp.norm_sqr(), down.tp.norm_sqr()),
            ],
            Some([s, p]) => {
                let reversed = View {
                    reversed: !view.reversed,
                    ..view
                };
                let (rm, rb) = (last - below, last - m);
                let up = reversed.group(rm, rb, light, [n_below, n_below * n_below, q_below], q);
                let pass = one_pass(light.k0, q_below, view.thickness(below));
                let layer = view.position(below);
                if pass > strongest.1 || pass.is_nan() {
                    strongest = (layer, pass);
                }
                let Amplitudes { rs, rp, ts, tp } = down;
                [
                    through_layer(s, (rs, ts), (up.rs, up.ts), pass, layer)?,
                    through_layer(p, (rp, tp), (up.rp, up.tp), pass, layer)?,
                ]
            }
        });
        (below, n_below, q_below) = (m, n, q);
    }
    Ok(Climbed {
        sums: state.expect("the view's top closes the recursion"),
        opaque,
        strongest,
    })
}

/// The Poynting factors that turn τ into T for s and p: Re(q_sub)/q0 and
/// Re(n_sub conj(cos θ_sub))/q0, as [`solve`] computes them.
#[inline]
pub(super) fn flux_factors(n_sub: C64, q_sub: C64, q0: f64) -> [f64; 2] {
    let p_flux = (q_sub.conj() * n_sub * n_sub).re / n_sub.norm_sqr();
    [q_sub.re / q0, p_flux / q0]
}

/// R and T of a stack whose layers are coherent or incoherent as
/// `coherence` says: [`solve`]'s arguments and conventions (indices of the
/// ambient, the N layers and the substrate; N thicknesses), and its answer
/// when every layer is coherent. Nothing is allocated.
///
/// # Errors
/// [`Diverged`] where an incoherent layer lases (see the module's text).
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
    let light = Light::new(wavelength_nm, indices[0].re, cos_theta0.min(1.0));
    let n_sub = indices[indices.len() - 1];
    let q_sub = sqrt_upper(light.normal_index_sq(n_sub));
    let n0 = C64::new(light.n0, 0.0);
    let climbed = climb(
        View::stack(indices, thicknesses_nm),
        coherence.incoherent.iter().copied(),
        &light,
        [n0, n0 * n0, C64::new(light.q0, 0.0)],
        q_sub,
    )?;
    let [(rs, ts), (rp, tp)] = climbed.sums;
    let [flux_s, flux_p] = if climbed.opaque {
        [0.0, 0.0]
    } else {
        flux_factors(n_sub, q_sub, light.q0)
    };
    let response = Response {
        rs,
        rp,
        ts: ts * flux_s,
        tp: tp * flux_p,
    };
    if response.is_finite() {
        Ok(response)
    } else {
        // Finite round trips whose gain still overflows the sum.
        Err(Diverged {
            layer: climbed.strongest.0,
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
