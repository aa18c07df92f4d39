//! The derivative of the coherent recursion ([`recurse_media`]) with respect
//! to every layer's thickness, by reverse mode: the forward sweep runs the
//! recursion step for step (Γ form, and the field form of near-critical
//! layers) and records each step's local derivatives; one backward sweep
//! multiplies them from the top down.
//!
//! Per polarization the state between steps is w = (Γ, ·) in Γ form or
//! w = (u, v) in field form, and ℓ = log t (t is a product, so its steps
//! add to ℓ). Every step is holomorphic in w and in the layer's phase, so
//! each has a complex 2×2 Jacobian J (new w by old w), a gradient k of its
//! additive ℓ term, and, for a layer, the derivatives ∂w/∂d and ∂ℓ/∂d at
//! fixed old w. Walking back from the top with the adjoints
//! g = ∂Γ_top/∂w and h = ∂ℓ_top/∂w gives ∂Γ_top/∂d = g·∂w/∂d and
//! ∂ℓ_top/∂d = h·∂w/∂d + ∂ℓ/∂d at each layer. Thickness enters only
//! through the layer's own step, so this is every derivative.
//!
//! [`recurse_media`]: super::super::solver::recurse_media

use num_complex::Complex64 as C64;

use super::super::solver::{near_critical, one_way, sqrt_upper, Amplitudes};

const ZERO: C64 = C64::new(0.0, 0.0);
const ONE: C64 = C64::new(1.0, 0.0);
const I: C64 = C64::new(0.0, 1.0);

/// The derivative of a stack's (or view's) amplitudes with respect to one
/// layer's thickness in nm: of r, and of log t (so that
/// ∂|t|²/∂d = 2|t|² Re ∂log t/∂d stays finite where t underflows).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AmplitudeGradient {
    /// ∂r_s/∂d.
    pub rs: C64,
    /// ∂r_p/∂d.
    pub rp: C64,
    /// ∂(log t_s)/∂d.
    pub log_ts: C64,
    /// ∂(log t_p)/∂d.
    pub log_tp: C64,
}

/// One step's local derivatives for one polarization (see the module's text).
#[derive(Clone, Copy, Debug, Default)]
struct Local {
    /// ∂w_new/∂w_old, row-major.
    jac: [C64; 4],
    /// ∂(ℓ_new − ℓ_old)/∂w_old.
    log_t: [C64; 2],
    /// ∂w_new/∂d and ∂ℓ_new/∂d (layer steps only).
    dw: [C64; 2],
    dl: C64,
}

/// One recorded step of the recursion: a layer crossed (`layer` is its
/// number among the view's finite media, 0-based) or an interface.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Step {
    layer: Option<usize>,
    s: Local,
    p: Local,
}

/// The per-polarization state of the forward sweep.
#[derive(Clone, Copy)]
struct Wave {
    /// Γ form: (Γ, 0); field form: (u, v).
    w: [C64; 2],
    t: C64,
}

impl Wave {
    fn start() -> Wave {
        Wave {
            w: [ZERO, ZERO],
            t: ONE,
        }
    }

    /// Crosses a layer in Γ form: Γ e^{2iδ}, t e^{iδ}.
    fn cross_gamma(&mut self, one_way: C64, k0q: C64) -> Local {
        let round_trip = one_way * one_way;
        self.w[0] *= round_trip;
        self.t *= one_way;
        Local {
            jac: [round_trip, ZERO, ZERO, ZERO],
            dw: [2.0 * I * k0q * self.w[0], ZERO],
            dl: I * k0q,
            ..Local::default()
        }
    }

    /// An interface in Γ form: Γ' = (x − y)/(x + y), t' = t c/(x + y) with
    /// x = a(1 + Γ), y = b(1 − Γ).
    fn interface(&mut self, a: C64, b: C64, c: C64) -> Local {
        let g = self.w[0];
        let inv = (a * (ONE + g) + b * (ONE - g)).inv();
        let x = a * (ONE + g);
        let y = b * (ONE - g);
        self.w[0] = (x - y) * inv;
        self.t *= c * inv;
        Local {
            jac: [4.0 * a * b * inv * inv, ZERO, ZERO, ZERO],
            log_t: [-(a - b) * inv, ZERO],
            ..Local::default()
        }
    }

    /// Γ form to field form at admittance η: u = 1 + Γ, v = η(1 − Γ).
    fn enter_fields(&mut self, eta: C64) -> Local {
        let g = self.w[0];
        self.w = [ONE + g, eta * (ONE - g)];
        Local {
            jac: [ONE, ZERO, -eta, ZERO],
            ..Local::default()
        }
    }

    /// Field form back to Γ form into a medium of admittance η:
    /// Γ = (ηu − v)/(ηu + v), t gains 2η/(ηu + v).
    fn leave_fields(&mut self, eta: C64) -> Local {
        let [u, v] = self.w;
        let inv = (eta * u + v).inv();
        self.w = [(eta * u - v) * inv, ZERO];
        self.t *= 2.0 * eta * inv;
        let inv2 = inv * inv;
        Local {
            jac: [2.0 * eta * v * inv2, -2.0 * eta * u * inv2, ZERO, ZERO],
            log_t: [-eta * inv, -inv],
            ..Local::default()
        }
    }
}

/// One near-critical layer's matrix in field form (see
/// `solver::NearCritical::cross_layer`), possibly scaled by e^{iδ} where
/// Im δ is large, with the pieces its derivative needs.
struct FieldLayer {
    cos_d: C64,
    sin_d: C64,
    /// k0 d sinc δ = sin δ / q, finite at q = 0.
    sin_over_q: C64,
    /// q sin δ = k0 d q² sinc δ, finite at q = 0.
    q_sin: C64,
    /// e^{iδ} when the matrix is scaled by it, else 1.
    scale: C64,
    scaled: bool,
}

impl FieldLayer {
    fn new(k0_d: f64, q: C64) -> FieldLayer {
        let delta = k0_d * q;
        let (cos_d, sin_d, sinc_d, scale, scaled) = if delta.im > 30.0 {
            let e = (I * delta).exp();
            let e2 = e * e;
            let sin_d = I * (ONE - e2) * 0.5;
            (0.5 * (ONE + e2), sin_d, sin_d / delta, e, true)
        } else {
            let sinc_d = if delta.norm_sqr() < 1e-6 {
                let d2 = delta * delta;
                ONE - d2 / 6.0 + d2 * d2 / 120.0
            } else {
                delta.sin() / delta
            };
            (delta.cos(), delta.sin(), sinc_d, ONE, false)
        };
        FieldLayer {
            cos_d,
            sin_d,
            sin_over_q: k0_d * sinc_d,
            q_sin: k0_d * q * q * sinc_d,
            scale,
            scaled,
        }
    }

    /// Applies the layer to one polarization of admittance η = q / m
    /// (m = 1 for s, n² for p): u' = cos δ u − i (m sin δ/q) v,
    /// v' = −i (q/m) sin δ u + cos δ v, and records the derivative
    /// (δ = k0 q d: ∂δ/∂d = k0 q, and e^{iδ} adds i k0 q to ℓ when scaled).
    fn cross(&self, wave: &mut Wave, k0: f64, q: C64, m: C64) -> Local {
        let [u, v] = wave.w;
        let m01 = -I * m * self.sin_over_q;
        let m10 = -I * (q / m) * self.sin_d;
        let jac = [self.cos_d, m01, m10, self.cos_d];
        wave.w = [jac[0] * u + jac[1] * v, jac[2] * u + jac[3] * v];
        wave.t *= self.scale;
        // ∂M/∂d of the unscaled matrix, times the scale; plus i k0 q M when scaled.
        let d00 = -k0 * self.q_sin;
        let d01 = -I * k0 * m * self.cos_d;
        let d10 = -I * k0 * (q * q / m) * self.cos_d;
        let mut dw = [d00 * u + d01 * v, d10 * u + d00 * v];
        let mut dl = ZERO;
        if self.scaled {
            let k0q = k0 * q;
            dw[0] += I * k0q * wave.w[0];
            dw[1] += I * k0q * wave.w[1];
            dl = I * k0q;
        }
        Local {
            jac,
            log_t: [ZERO, ZERO],
            dw,
            dl,
        }
    }
}

/// [`recurse_media`](super::super::solver::recurse_media) with the
/// derivative of its amplitudes with respect to the thickness of each of
/// its `media − 2` finite media, written into `out` (medium j + 1's at
/// `out[j]`). `tape` is scratch, reused across calls.
#[allow(clippy::too_many_arguments)]
pub(crate) fn recurse_media_gradient(
    media: usize,
    index: impl Fn(usize) -> C64,
    thickness: impl Fn(usize) -> f64,
    wavelength_nm: f64,
    beta_sq: f64,
    top: [C64; 3],
    q_sub: C64,
    tape: &mut Vec<Step>,
    out: &mut [AmplitudeGradient],
) -> Amplitudes {
    debug_assert_eq!(out.len(), media - 2);
    let k0 = std::f64::consts::TAU / wavelength_nm;
    tape.clear();
    let last = media - 1;
    let mut n_below = index(last);
    let mut nsq_below = n_below * n_below;
    let mut q_below = q_sub;
    let (mut s, mut p) = (Wave::start(), Wave::start());
    let mut in_fields = false;

    for j in (0..last).rev() {
        let (n_above, nsq_above, q_above) = if j == 0 {
            (top[0], top[1], top[2])
        } else {
            let n = index(j);
            let nsq = n * n;
            (n, nsq, sqrt_upper(nsq - beta_sq))
        };
        if j + 1 < last {
            let k0_d = k0 * thickness(j);
            let step = if in_fields {
                let layer = FieldLayer::new(k0_d, q_below);
                Step {
                    layer: Some(j),
                    s: layer.cross(&mut s, k0, q_below, ONE),
                    p: layer.cross(&mut p, k0, q_below, nsq_below),
                }
            } else {
                let one_way = one_way(k0_d * q_below);
                let k0q = k0 * q_below;
                Step {
                    layer: Some(j),
                    s: s.cross_gamma(one_way, k0q),
                    p: p.cross_gamma(one_way, k0q),
                }
            };
            tape.push(step);
        }
        let above_near_critical = j > 0 && near_critical(q_above, nsq_above);
        let ratio = n_above / n_below;
        let step = match (in_fields, above_near_critical) {
            (false, false) => Step {
                layer: None,
                s: s.interface(q_above, q_below, 2.0 * q_above),
                p: p.interface(
                    nsq_below * q_above,
                    nsq_above * q_below,
                    2.0 * n_above * n_below * q_above,
                ),
            },
            (false, true) => {
                p.t *= ratio;
                in_fields = true;
                Step {
                    layer: None,
                    s: s.enter_fields(q_below),
                    p: p.enter_fields(q_below / nsq_below),
                }
            }
            (true, true) => {
                p.t *= ratio;
                Step {
                    layer: None,
                    s: identity(),
                    p: identity(),
                }
            }
            (true, false) => {
                p.t *= ratio;
                in_fields = false;
                Step {
                    layer: None,
                    s: s.leave_fields(q_above),
                    p: p.leave_fields(q_above / nsq_above),
                }
            }
        };
        tape.push(step);
        n_below = n_above;
        nsq_below = nsq_above;
        q_below = q_above;
    }
    backward(tape, out);
    Amplitudes {
        rs: s.w[0],
        rp: p.w[0],
        ts: s.t,
        tp: p.t,
    }
}

fn identity() -> Local {
    Local {
        jac: [ONE, ZERO, ZERO, ONE],
        ..Local::default()
    }
}

/// The adjoints of one polarization: g = ∂Γ_top/∂w, h = ∂ℓ_top/∂w.
#[derive(Clone, Copy)]
struct Adjoint {
    g: [C64; 2],
    h: [C64; 2],
}

impl Adjoint {
    /// ∂Γ_top/∂d and ∂ℓ_top/∂d of a layer step.
    #[inline]
    fn layer(&self, local: &Local) -> (C64, C64) {
        let [dw0, dw1] = local.dw;
        (
            self.g[0] * dw0 + self.g[1] * dw1,
            self.h[0] * dw0 + self.h[1] * dw1 + local.dl,
        )
    }

    /// Moves the adjoints below a step.
    #[inline]
    fn pull(&mut self, local: &Local) {
        let [j00, j01, j10, j11] = local.jac;
        let [g0, g1] = self.g;
        let [h0, h1] = self.h;
        self.g = [g0 * j00 + g1 * j10, g0 * j01 + g1 * j11];
        self.h = [
            h0 * j00 + h1 * j10 + local.log_t[0],
            h0 * j01 + h1 * j11 + local.log_t[1],
        ];
    }
}

fn backward(tape: &[Step], out: &mut [AmplitudeGradient]) {
    let top = Adjoint {
        g: [ONE, ZERO],
        h: [ZERO, ZERO],
    };
    let (mut s, mut p) = (top, top);
    for step in tape.iter().rev() {
        if let Some(layer) = step.layer {
            let (rs, log_ts) = s.layer(&step.s);
            let (rp, log_tp) = p.layer(&step.p);
            out[layer] = AmplitudeGradient {
                rs,
                rp,
                log_ts,
                log_tp,
            };
        }
        s.pull(&step.s);
        p.pull(&step.p);
    }
}
