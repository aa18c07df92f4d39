//! Splitting a stack around one layer, so that the response as a function of
//! that layer's thickness costs one complex rotation and one division per
//! polarization.
//!
//! With the sub-stack A above the varying layer (ambient down to the layer's
//! medium, seen as semi-infinite) and B below it (the layer's medium down to
//! the substrate), the multiple reflections inside the layer sum to Airy's
//!
//! ```text
//! r = r_A + t_A t'_A r_B φ² / (1 − r'_A r_B φ²)      t = t_A t_B φ / (1 − r'_A r_B φ²)
//! ```
//!
//! with φ = e^{i k0 q d}. r', t' are A seen from below. Everything except φ is
//! fixed for one wavelength and angle, so a thickness sweep reuses it. The
//! sub-stacks come from the solver's own recursion
//! (`recurse_beta`, as [`super::solve_amplitudes_beta`] runs it), whose
//! t_ij t_ji product is sign-consistent,
//! so the composition agrees with [`super::solve`] to rounding.

use num_complex::Complex64 as C64;

use super::incoherent::{split, Coherence, Env, Parts};
use super::solver::{normal_index_at, recurse_beta, Amplitudes, Response};
use crate::simd::simd_dispatch;

/// |q|² / |n|² below which the layer counts as at its critical angle. The
/// split loses about ε|n|/|q| to rounding, so below |q|/|n| = 1e-4 it could
/// miss 1e-12 (tested on both sides of the threshold).
const DEGENERATE_Q: f64 = 1e-8;

/// Reusable buffers for [`VaryingLayer::new`], so that a bake allocates once
/// per worker rather than once per wavelength and angle.
#[derive(Default)]
pub struct Scratch {
    indices: Vec<C64>,
    thicknesses_nm: Vec<f64>,
}

/// Everything about one (wavelength, angle) that does not depend on the
/// varying layer's thickness. Index 0 of each pair is s, index 1 is p.
#[derive(Clone, Copy, Debug)]
pub struct VaryingLayer {
    /// The coefficients of R and T in φ², made once per split.
    factors: Factors,
    /// 2π/λ.
    k0: f64,
    /// q of the varying layer: φ = exp(i k0 q d).
    q: C64,
    /// cos θ0 = 0: no power enters, R = 1 and T = 0 whatever the stack.
    grazing: bool,
    /// The layer's q is (nearly) 0: it sits at its own critical angle, where
    /// the waves in it have no direction to split the stack by. Also set
    /// where a stack with incoherent layers does not split (see
    /// [`VaryingLayer::new_mixed`]).
    degenerate: bool,
    /// In a stack with incoherent layers, the layer's coherent group and the
    /// incoherent sums around it; `None` in a coherent stack.
    around: Option<Surroundings>,
}

impl VaryingLayer {
    /// Splits the stack `indices` (ambient, N layers, substrate; the ambient
    /// lossless) around layer `layer` (1-based from the ambient side). The
    /// thickness of that layer in `thicknesses_nm` is ignored.
    pub fn new(
        indices: &[C64],
        thicknesses_nm: &[f64],
        layer: usize,
        wavelength_nm: f64,
        cos_theta0: f64,
        scratch: &mut Scratch,
    ) -> VaryingLayer {
        debug_assert!(layer >= 1 && layer + 1 < indices.len());
        let n0 = indices[0].re;
        let beta_sq = n0 * n0 * (1.0 - cos_theta0 * cos_theta0);
        let k0 = std::f64::consts::TAU / wavelength_nm;
        let n_layer = indices[layer];
        let q_layer = normal_index_at(n_layer, n0, cos_theta0);

        let n_sub = indices[indices.len() - 1];
        let q_sub = normal_index_at(n_sub, n0, cos_theta0);
        // Each medium the three sub-stacks share gets its q once, passed to
        // the recursion.
        let n_ambient = C64::new(n0, 0.0);
        let ambient = [
            n_ambient,
            n_ambient * n_ambient,
            C64::new(n0 * cos_theta0, 0.0),
        ];
        let varying = [n_layer, n_layer * n_layer, q_layer];

        // A from above: ambient, layers 1..layer-1, the varying medium.
        let mut top: Vec<C64> = std::mem::take(&mut scratch.indices);
        top.clear();
        top.push(n_ambient);
        top.extend_from_slice(&indices[1..=layer]);
        let above = &thicknesses_nm[..layer - 1];
        let a = recurse_beta(&top, above, wavelength_nm, beta_sq, ambient, q_layer);
        // A from below: the same media reversed.
        top.reverse();
        let mut t_rev = std::mem::take(&mut scratch.thicknesses_nm);
        t_rev.clear();
        t_rev.extend(above.iter().rev());
        let a_up = recurse_beta(&top, &t_rev, wavelength_nm, beta_sq, varying, ambient[2]);
        // B: the varying medium down to the substrate.
        let b = recurse_beta(
            &indices[layer..],
            &thicknesses_nm[layer..],
            wavelength_nm,
            beta_sq,
            varying,
            q_sub,
        );
        scratch.indices = top;
        scratch.thicknesses_nm = t_rev;

        let q0 = n0 * cos_theta0;
        let cos_sub = q_sub / n_sub;
        // The Poynting factors turning |t|² into power.
        let t_power = [q_sub.re / q0, (n_sub * cos_sub.conj()).re / q0];
        VaryingLayer {
            factors: Factors::new(&a, &a_up, &b, t_power),
            k0,
            q: q_layer,
            grazing: cos_theta0 <= 0.0,
            degenerate: q_layer.norm_sqr() < DEGENERATE_Q * n_layer.norm_sqr(),
            around: None,
        }
    }

    /// [`Self::new`] for a stack whose layers are coherent or incoherent as
    /// `coherence` says; `layer` must be coherent. The split is then of the
    /// layer's coherent group (between the nearest incoherent media above
    /// and below it), and the incoherent sums around the group are made once
    /// here: a node costs two more real divisions per polarization. Where
    /// the layer cannot matter (an opaque incoherent layer above it) or the
    /// sums around it diverge, the split is degenerate: evaluate node by node
    /// with [`super::solve_mixed`].
    pub fn new_mixed(
        indices: &[C64],
        thicknesses_nm: &[f64],
        coherence: &Coherence,
        layer: usize,
        wavelength_nm: f64,
        cos_theta0: f64,
        scratch: &mut Scratch,
    ) -> VaryingLayer {
        if coherence.is_coherent() {
            return Self::new(
                indices,
                thicknesses_nm,
                layer,
                wavelength_nm,
                cos_theta0,
                scratch,
            );
        }
        let k0 = std::f64::consts::TAU / wavelength_nm;
        let parts = (cos_theta0 > 0.0)
            .then(|| {
                split(
                    indices,
                    thicknesses_nm,
                    coherence,
                    layer,
                    wavelength_nm,
                    cos_theta0,
                )
            })
            .flatten();
        let Some(Parts {
            above,
            above_up,
            below,
            below_up,
            q_layer,
            env,
        }) = parts
        else {
            return VaryingLayer {
                factors: Factors::default(),
                k0,
                q: C64::new(0.0, 0.0),
                grazing: cos_theta0 <= 0.0,
                degenerate: cos_theta0 > 0.0,
                around: None,
            };
        };
        let pol = |a: &Amplitudes| [(a.rs, a.ts), (a.rp, a.tp)];
        let (b, b_up, a_up, a) = (pol(&below), pol(&below_up), pol(&above_up), pol(&above));
        VaryingLayer {
            factors: Factors::new(&above, &above_up, &below, [0.0; 2]),
            k0,
            q: q_layer,
            grazing: false,
            degenerate: q_layer.norm_sqr() < DEGENERATE_Q * indices[layer].norm_sqr(),
            around: Some(Surroundings {
                rb: [0, 1].map(|k| b_up[k].0),
                xb_net: [0, 1].map(|k| (b[k].1 * b_up[k].1 - b[k].0 * b_up[k].0) * a_up[k].0),
                z_down: [0, 1].map(|k| (a[k].1 * b[k].1).norm_sqr()),
                z_up: [0, 1].map(|k| (a_up[k].1 * b_up[k].1).norm_sqr()),
                env,
            }),
        }
    }

    /// The same split at another wavelength, where only the varying layer's
    /// phase changes: exactly [`Self::new`] there when the varying layer is
    /// the stack's only layer and no medium disperses. The sub-stacks are
    /// then single interfaces, whose coefficients do not depend on the
    /// wavelength, so one split per angle serves the whole spectrum.
    pub fn at_wavelength(&self, wavelength_nm: f64) -> VaryingLayer {
        VaryingLayer {
            k0: std::f64::consts::TAU / wavelength_nm,
            ..*self
        }
    }

    /// i k0 q: φ = exp(ikq · d).
    #[inline]
    fn ikq(&self) -> C64 {
        C64::new(0.0, self.k0) * self.q
    }

    /// The varying layer's sharpest fringe at thickness `thickness_nm`: the
    /// larger over s and p of |r'_A r_B φ²|, the round trip's amplitude in
    /// the layer (its fringes have a width in round-trip phase of about
    /// 2 (1 − |r'_A r_B φ²|), narrowing without bound where it nears 1: a
    /// free-standing film at grazing incidence), and how much the
    /// unpolarized R changes between that polarization's resonance and the
    /// phase opposite, at the layer's absorption over that thickness (0
    /// where the layer's phase cannot show in R: total internal reflection
    /// in a lossless stack).
    pub fn fringe(&self, thickness_nm: f64) -> (f64, f64) {
        let k = self.sharper();
        let y = -self.factors.neg_y[k];
        let decay = self.phase(thickness_nm).norm();
        // Resonance where y φ² is real and positive: φ² = e^{−i arg y}.
        let at = |psi: f64| self.response(C64::from_polar(decay, 0.5 * psi)).r();
        let resonance = -y.arg();
        let visibility = (at(resonance) - at(resonance + std::f64::consts::PI)).abs();
        (y.norm() * decay * decay, visibility)
    }

    /// The polarization (0: s, 1: p) whose round trip is the larger.
    fn sharper(&self) -> usize {
        usize::from(self.factors.neg_y[1].norm() > self.factors.neg_y[0].norm())
    }

    /// The first value of [`Self::fringe`] alone (the round trip's
    /// amplitude at thickness `thickness_nm`), without the visibility's two
    /// responses.
    pub fn round_trip(&self, thickness_nm: f64) -> f64 {
        let decay = self.phase(thickness_nm).norm();
        self.factors.neg_y[self.sharper()].norm() * decay * decay
    }

    /// The width in wavelength (nm) of a fringe of round-trip amplitude `y`
    /// (from [`Self::fringe`]) at thickness `thickness_nm`: its width in
    /// round-trip phase, 2 |1 − y| / √y, over the phase's rate
    /// |dδ/dλ| = 4π Re(q) d / λ² = k₀² Re(q) d / π (the layer's dispersion
    /// left out). Infinite for a layer at or beyond its own critical angle.
    pub fn fringe_width_nm(&self, y: f64, thickness_nm: f64) -> f64 {
        let rate = self.k0 * self.k0 * self.q.re * thickness_nm / std::f64::consts::PI;
        if rate <= 0.0 {
            return f64::INFINITY;
        }
        2.0 * (1.0 - y).abs() / y.sqrt() / rate
    }

    /// How fast the varying layer's waves fade, in nepers per nm of
    /// thickness one way (k₀ Im q): 0 for a lossless layer below its own
    /// critical angle, negative for a gain layer.
    pub fn attenuation_per_nm(&self) -> f64 {
        self.k0 * self.q.im
    }

    /// True when the split is unusable (the layer's q ≈ 0, see the field):
    /// evaluate such a (wavelength, angle) with [`super::solve`] instead.
    pub fn is_degenerate(&self) -> bool {
        self.degenerate
    }

    /// φ = e^{i k0 q d} for a thickness of the varying layer.
    #[inline]
    pub fn phase(&self, thickness_nm: f64) -> C64 {
        (self.ikq() * thickness_nm).exp()
    }

    /// The angle whose one-way factor is [`Self::phase`]: φ with
    /// e^{iφ} = e^{i k0 q d}, for the lanes' exponential
    /// ([`crate::optics::lanes::one_way_many`]).
    #[inline]
    pub fn phase_angle(&self, thickness_nm: f64) -> C64 {
        let ikq = self.ikq();
        C64::new(ikq.im * thickness_nm, -ikq.re * thickness_nm)
    }

    /// Power R and T for both polarizations at the layer's phase factor φ.
    ///
    /// Written without complex division: with D = 1 − r'_A r_B φ²,
    /// R = |r_A + (t_A t'_A − r_A r'_A) r_B φ²|² / |D|² (the numerator
    /// r_A D + t_A t'_A r_B φ² with its constant parts gathered) and
    /// T = |t_A t_B|² |φ|² / |D|² (times the Poynting factor), one real
    /// division per polarization. The batched loops run the same fused
    /// operations, so a table does not depend on which of the two evaluated
    /// it. Always inlined, so that a caller compiled for FMA (such as a
    /// `simd_dispatch!` copy) fuses them in instructions, not library calls.
    #[inline(always)]
    pub fn response(&self, phase: C64) -> Response {
        if self.grazing {
            return Response {
                rs: 1.0,
                rp: 1.0,
                ts: 0.0,
                tp: 0.0,
            };
        }
        let [rs, rp, ts, tp] = match &self.around {
            None => self.factors.polarized(phase.re, phase.im),
            Some(around) => around.polarized(&self.factors, phase.re, phase.im),
        };
        Response { rs, rp, ts, tp }
    }
    /// Unpolarized R and T at many phase factors at once, bit for bit what
    /// [`Self::response`] gives node by node. The phases come as separate
    /// real and imaginary arrays and the loop has no branch, so it compiles
    /// to packed arithmetic: a bake spends most of its time here.
    pub fn responses(&self, phase_re: &[f64], phase_im: &[f64], r: &mut [f64], t: &mut [f64]) {
        batch_responses(self, phase_re, phase_im, r, t);
    }

    /// Adds `weights` × R and × T (unpolarized, as [`Self::responses`] gives
    /// them; each product and sum fused, one rounding) to channel-major accumulators `acc` (`[channel][node]`, the
    /// three R channels first, one node per phase factor). One pass instead
    /// of [`Self::responses`] and a second loop over its output: R and T stay
    /// in registers, and the accumulation's loads and adds fill the slots
    /// the divisions leave idle.
    pub fn accumulate_responses(
        &self,
        phase_re: &[f64],
        phase_im: &[f64],
        weights: [f64; 3],
        acc: &mut [f64],
    ) {
        batch_accumulate(self, phase_re, phase_im, weights, acc);
    }
}

/// The thickness-independent factors of [`VaryingLayer::response`], as the
/// batched loops use them, per polarization.
#[derive(Clone, Copy, Debug, Default)]
struct Factors {
    ra: [C64; 2],
    /// t_A t'_A r_B − r_A r'_A r_B: the numerator's φ² coefficient.
    x_net: [C64; 2],
    /// −r'_A r_B: the denominator is 1 + (−y)φ².
    neg_y: [C64; 2],
    /// |t_A t_B|² times the Poynting factor.
    zt: [f64; 2],
}

/// |c + x φ²|² and |1 + neg_y φ²|², φ² = `p_re` + i `p_im`: the squared
/// moduli of a reflection's numerator and of the shared denominator.
#[inline(always)]
fn moduli(p_re: f64, p_im: f64, c: C64, x: C64, neg_y: C64) -> (f64, f64) {
    let den_re = neg_y.re.mul_add(p_re, (-neg_y.im).mul_add(p_im, 1.0));
    let den_im = neg_y.re.mul_add(p_im, neg_y.im * p_re);
    let num_re = x.re.mul_add(p_re, (-x.im).mul_add(p_im, c.re));
    let num_im = x.re.mul_add(p_im, x.im.mul_add(p_re, c.im));
    (
        num_re.mul_add(num_re, num_im * num_im),
        den_re.mul_add(den_re, den_im * den_im),
    )
}

impl Factors {
    /// The factors of a split into A (`a` from above, `a_up` from below) and
    /// B (`b`), with the Poynting factors `t_power` of the substrate.
    fn new(a: &Amplitudes, a_up: &Amplitudes, b: &Amplitudes, t_power: [f64; 2]) -> Factors {
        let r_above = [a.rs, a.rp];
        // t_A t'_A r_B and r'_A r_B.
        let x = [a.ts * a_up.ts * b.rs, a.tp * a_up.tp * b.rp];
        let y = [a_up.rs * b.rs, a_up.rp * b.rp];
        // t_A t_B.
        let z = [a.ts * b.ts, a.tp * b.tp];
        Factors {
            ra: r_above,
            x_net: [0, 1].map(|k| x[k] - r_above[k] * y[k]),
            neg_y: y.map(|y| -y),
            zt: [z[0].norm_sqr() * t_power[0], z[1].norm_sqr() * t_power[1]],
        }
    }

    /// Rs, Rp, Ts, Tp at the phase factor `a + ib`. Products and sums are
    /// fused (`mul_add`, one rounding each), which takes the loop from about
    /// a hundred operations a node to half that; every copy of the batched
    /// loops and the scalar [`VaryingLayer::response`] run these same
    /// operations, so they agree bit for bit.
    #[inline(always)]
    fn polarized(&self, a: f64, b: f64) -> [f64; 4] {
        // φ² and |φ|²; 2ab is exact doubling of one rounded product.
        let (p_re, p_im) = (a.mul_add(a, -(b * b)), 2.0 * (a * b));
        let phase_sq = a.mul_add(a, b * b);
        let (ns, ds) = moduli(p_re, p_im, self.ra[0], self.x_net[0], self.neg_y[0]);
        let (np, dp) = moduli(p_re, p_im, self.ra[1], self.x_net[1], self.neg_y[1]);
        let (inv_s, inv_p) = (1.0 / ds, 1.0 / dp);
        [
            ns * inv_s,
            np * inv_p,
            self.zt[0] * phase_sq * inv_s,
            self.zt[1] * phase_sq * inv_p,
        ]
    }

    /// The sums Rs + Rp and Ts + Tp (twice the unpolarized R and T).
    #[inline(always)]
    fn sums(&self, a: f64, b: f64) -> (f64, f64) {
        let [rs, rp, ts, tp] = self.polarized(a, b);
        (rs + rp, ts + tp)
    }
}

/// What surrounds the varying layer's coherent group in a stack with
/// incoherent layers ([`crate::optics::incoherent`]), per polarization: the
/// group's reflection from below and its transmissions, which share the
/// denominator D = 1 − r'_A r_B φ² of its reflection from above, and the
/// incoherent sums above and below the group.
#[derive(Clone, Copy, Debug)]
struct Surroundings {
    /// r'_B: the constant of the group's reflection from below, r'_g =
    /// (r'_B + x' φ²) / D.
    rb: [C64; 2],
    /// x' = (t_B t'_B − r_B r'_B) r'_A.
    xb_net: [C64; 2],
    /// |t_A t_B|² and |t'_A t'_B|²: |t_g|² = |t_A t_B|² |φ|² / |D|².
    z_down: [f64; 2],
    z_up: [f64; 2],
    env: Env,
}

impl Surroundings {
    /// Rs, Rp, Ts, Tp at the phase factor `a + ib`: the group's four power
    /// coefficients, closed below and above by the incoherent sums. A sum
    /// that diverges (a lasing incoherent layer) gives +∞, as
    /// [`super::solve_mixed`] does.
    #[inline(always)]
    fn polarized(&self, f: &Factors, a: f64, b: f64) -> [f64; 4] {
        let (p_re, p_im) = (a.mul_add(a, -(b * b)), 2.0 * (a * b));
        let phase_sq = a.mul_add(a, b * b);
        let env = &self.env;
        let mut out = [0.0; 4];
        for k in 0..2 {
            let (n_r, dd) = moduli(p_re, p_im, f.ra[k], f.x_net[k], f.neg_y[k]);
            let (n_rb, _) = moduli(p_re, p_im, self.rb[k], self.xb_net[k], f.neg_y[k]);
            let inv = 1.0 / dd;
            let (r_g, rb_g) = (n_r * inv, n_rb * inv);
            let (t_g, tb_g) = (
                self.z_down[k] * phase_sq * inv,
                self.z_up[k] * phase_sq * inv,
            );
            let d_below = 1.0 - rb_g * env.rho_below[k];
            let rho = r_g + t_g * tb_g * env.rho_below[k] / d_below;
            let tau = t_g * env.tau_below[k] / d_below;
            let d_above = 1.0 - env.rb[k] * rho;
            let lases = !(d_below > 0.0 && d_above > 0.0);
            out[k] = if lases {
                f64::INFINITY
            } else {
                env.r[k] + env.tt[k] * rho / d_above
            };
            out[2 + k] = if lases {
                f64::INFINITY
            } else {
                env.t[k] * tau / d_above
            };
        }
        out
    }
}

simd_dispatch! {
    /// [`VaryingLayer::responses`].
    fn batch_responses(
        v: &VaryingLayer,
        phase_re: &[f64],
        phase_im: &[f64],
        r: &mut [f64],
        t: &mut [f64],
    ) {
        let n = phase_re.len();
        let (phase_im, r, t) = (&phase_im[..n], &mut r[..n], &mut t[..n]);
        if v.grazing {
            r.fill(1.0);
            t.fill(0.0);
            return;
        }
        let f = v.factors;
        if let Some(around) = v.around {
            for j in 0..n {
                let [rs, rp, ts, tp] = around.polarized(&f, phase_re[j], phase_im[j]);
                (r[j], t[j]) = (0.5 * (rs + rp), 0.5 * (ts + tp));
            }
            return;
        }
        for j in 0..n {
            let (r_sum, t_sum) = f.sums(phase_re[j], phase_im[j]);
            (r[j], t[j]) = (0.5 * r_sum, 0.5 * t_sum);
        }
    }
}

simd_dispatch! {
    /// [`VaryingLayer::accumulate_responses`].
    fn batch_accumulate(
        v: &VaryingLayer,
        phase_re: &[f64],
        phase_im: &[f64],
        weights: [f64; 3],
        acc: &mut [f64],
    ) {
        let n = phase_re.len();
        let phase_im = &phase_im[..n];
        let (acc_r, acc_t) = acc[..6 * n].split_at_mut(3 * n);
        let (r0, acc_r) = acc_r.split_at_mut(n);
        let (r1, r2) = acc_r.split_at_mut(n);
        let (t0, acc_t) = acc_t.split_at_mut(n);
        let (t1, t2) = acc_t.split_at_mut(n);
        // w (½ (Rs + Rp)) and (½ w)(Rs + Rp) are the same exact product, so
        // each fused step gives what weighting the unpolarized R would.
        let [w0, w1, w2] = weights.map(|w| 0.5 * w);
        let f = v.factors;
        macro_rules! add {
            ($j:expr, $r:expr, $t:expr) => {{
                let (j, r, t) = ($j, $r, $t);
                r0[j] = w0.mul_add(r, r0[j]);
                r1[j] = w1.mul_add(r, r1[j]);
                r2[j] = w2.mul_add(r, r2[j]);
                t0[j] = w0.mul_add(t, t0[j]);
                t1[j] = w1.mul_add(t, t1[j]);
                t2[j] = w2.mul_add(t, t2[j]);
            }};
        }
        if let (false, Some(around)) = (v.grazing, v.around) {
            for j in 0..n {
                let [rs, rp, ts, tp] = around.polarized(&f, phase_re[j], phase_im[j]);
                add!(j, rs + rp, ts + tp);
            }
            return;
        }
        for j in 0..n {
            // At grazing incidence no power enters: R = 1, T = 0. The test
            // does not change along the loop, which the compiler hoists.
            let (r, t) = if v.grazing {
                (2.0, 0.0)
            } else {
                f.sums(phase_re[j], phase_im[j])
            };
            add!(j, r, t);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::solve;

    #[test]
    fn a_single_constant_layer_splits_the_same_at_every_wavelength() {
        // One layer, no dispersion: the split at one wavelength, moved to
        // another, must be the split made there, bit for bit (the bake
        // splits such a stack once per angle). Lossless, absorbing, gain,
        // metal, and a dense ambient whose layer reaches its critical angle.
        let stacks = [
            [C64::new(1.0, 0.0), C64::new(1.33, 0.0), C64::new(1.0, 0.0)],
            [C64::new(1.0, 0.0), C64::new(2.0, 0.4), C64::new(1.52, 0.0)],
            [C64::new(1.0, 0.0), C64::new(1.6, -0.02), C64::new(0.2, 3.4)],
            [C64::new(1.5, 0.0), C64::new(1.33, 0.0), C64::new(1.0, 0.0)],
        ];
        let mut scratch = Scratch::default();
        for indices in &stacks {
            for &c in &[1.0, 0.8, 0.6635, 0.5, 0.2, 0.0] {
                let first = VaryingLayer::new(indices, &[0.0], 1, 360.0, c, &mut scratch);
                for wl in [361.0, 455.5, 550.0, 830.0] {
                    let moved = first.at_wavelength(wl);
                    let made = VaryingLayer::new(indices, &[0.0], 1, wl, c, &mut scratch);
                    assert_eq!(moved.is_degenerate(), made.is_degenerate());
                    for d in [0.0, 1.0, 250.0, 1234.5] {
                        let (a, b) = (moved.response(moved.phase(d)), made.response(made.phase(d)));
                        let bits = |r: Response| [r.rs, r.rp, r.ts, r.tp].map(f64::to_bits);
                        assert_eq!(bits(a), bits(b), "{indices:?} at cos {c}, {wl} nm, {d} nm");
                    }
                }
            }
        }
    }

    fn check(indices: &[C64], thick: &[f64], layer: usize) {
        check_at(indices, thick, layer, &[1.0, 0.8, 0.5, 0.2, 0.03, 0.0]);
    }

    fn check_at(indices: &[C64], thick: &[f64], layer: usize, cosines: &[f64]) {
        let mut scratch = Scratch::default();
        for &wl in &[380.0, 550.0, 779.0] {
            for &c in cosines {
                let v = VaryingLayer::new(indices, thick, layer, wl, c, &mut scratch);
                if v.is_degenerate() {
                    continue;
                }
                for &d in &[0.0, 13.0, 250.0, 999.0] {
                    let mut t = thick.to_vec();
                    t[layer - 1] = d;
                    let want = solve(indices, &t, wl, c);
                    let got = v.response(v.phase(d));
                    for (g, w) in [
                        (got.rs, want.rs),
                        (got.rp, want.rp),
                        (got.ts, want.ts),
                        (got.tp, want.tp),
                    ] {
                        assert!(
                            (g - w).abs() <= 1e-12 * (1.0 + w.abs()),
                            "{indices:?} layer {layer} λ {wl} cos {c} d {d}: {g} vs {w}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn zero_thickness_near_grazing_is_the_bare_interface() {
        // At thickness 0 the film is absent: what is left is the interface
        // of the ambient and the substrate, in closed form. Near grazing
        // incidence the film's interfaces reflect almost fully (r'_A r_B →
        // 1), and below cos θ ≈ 1e-8 (n0 cos θ)² is lost against n0²: the
        // split must still give the bare interface there, not 0/0.
        let c = |n: f64, k: f64| C64::new(n, k);
        let fresnel_r = |n0: f64, n1: f64, mu: f64| {
            let q0 = n0 * mu;
            let q1 = (n1 * n1 - n0 * n0 + q0 * q0).sqrt();
            let rs = (q0 - q1) / (q0 + q1);
            let rp = (n1 * n1 * q0 - n0 * n0 * q1) / (n1 * n1 * q0 + n0 * n0 * q1);
            (rs * rs, rp * rp)
        };
        let mut scratch = Scratch::default();
        for (n1, film) in [(1.0, c(1.33, 0.0)), (1.52, c(1.5, 0.0)), (1.0, c(1.5, 0.1))] {
            let idx = [c(1.0, 0.0), film, c(n1, 0.0)];
            // 1 − r'_A r_B ≈ 4 μ / q1 carries the rounding of r'_A r_B
            // (1e-16) relative to μ: the response holds to about 1e-16 / μ.
            for mu in [1e-6, 1e-8, 1e-9, 1e-10, 1e-11] {
                let tolerance = 1e-9 + 1e-14 / mu;
                for wl in [380.0, 550.0, 780.0] {
                    let v = VaryingLayer::new(&idx, &[0.0], 1, wl, mu, &mut scratch);
                    let got = v.response(v.phase(0.0));
                    let (rs, rp) = fresnel_r(1.0, n1, mu);
                    for (g, w) in [(got.rs, rs), (got.rp, rp)] {
                        assert!((g - w).abs() <= tolerance, "{idx:?} cos {mu}: R {g} vs {w}");
                    }
                    // Lossless media: what is not reflected is transmitted.
                    for (r, t) in [(got.rs, got.ts), (got.rp, got.tp)] {
                        let sum = r + t;
                        assert!(
                            (sum - 1.0).abs() <= tolerance,
                            "{idx:?} cos {mu}: R + T {sum}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn agrees_with_solver_on_hard_stacks() {
        let c = |n: f64, k: f64| C64::new(n, k);
        // Soap film; absorbing film; gain film on gold; dense ambient (TIR).
        check(&[c(1.0, 0.0), c(1.33, 0.0), c(1.0, 0.0)], &[0.0], 1);
        check(&[c(1.0, 0.0), c(1.5, 0.15), c(1.33, 0.0)], &[0.0], 1);
        check(&[c(1.0, 0.0), c(1.5, -0.05), c(0.18, 3.4)], &[0.0], 1);
        check(&[c(1.5, 0.0), c(1.38, 0.0), c(1.0, 0.0)], &[0.0], 1);
        // Frustrated TIR: an air gap seen from glass, at and near the gap's
        // critical angle (where the gap's q is 0).
        let cc = (1.0f64 - (1.0 / 1.5f64).powi(2)).sqrt();
        let gap = [c(1.5, 0.0), c(1.0, 0.0), c(1.0, 0.0)];
        check_at(&gap, &[0.0], 1, &[cc, cc + 1e-9, cc + 2e-6, cc - 2e-6]);
        let mut scratch = Scratch::default();
        for near in [cc, cc + 1e-9, cc - 1e-9] {
            assert!(VaryingLayer::new(&gap, &[0.0], 1, 500.0, near, &mut scratch).is_degenerate());
        }
        // Varying a middle layer of a three-layer stack on metal.
        let idx = [
            c(1.0, 0.0),
            c(2.4, 0.0),
            c(1.38, 0.01),
            c(1.6, 0.0),
            c(0.05, 4.0),
        ];
        for layer in 1..=3 {
            check(&idx, &[90.0, 120.0, 60.0], layer);
        }
    }
}
