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
    /// ∂w_new/∂N and ∂ℓ_new/∂N at fixed old w, by the complex index N of
    /// the step's media: `[0]` the medium below the interface (a layer
    /// step's own medium), `[1]` the medium above it (interfaces only).
    dw_index: [[C64; 2]; 2],
    dl_index: [C64; 2],
}

/// One recorded step of the recursion: a layer crossed (`layer` is its
/// number among the view's finite media, 0-based) or an interface;
/// `medium` is the medium below the interface, or the layer's own (view
/// numbering: the medium above an interface is `medium − 1`).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Step {
    layer: Option<usize>,
    medium: usize,
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

/// dq/dN = N/q of a medium crossed in Γ form (q ≠ 0 there but for a
/// grazing half-space, whose own derivative is never asked for).
#[inline]
fn dq_dn(n: C64, q: C64) -> C64 {
    if q == ZERO {
        ZERO
    } else {
        n / q
    }
}

/// A medium as the recursion sees it: N, N², q and dq/dN.
#[derive(Clone, Copy)]
struct Medium {
    n: C64,
    nsq: C64,
    q: C64,
    dq: C64,
}

impl Medium {
    fn new(n: C64, nsq: C64, q: C64) -> Medium {
        Medium {
            n,
            nsq,
            q,
            dq: dq_dn(n, q),
        }
    }

    /// The p admittance q/N² and its derivative by N.
    fn eta_p(&self) -> (C64, C64) {
        let eta = self.q / self.nsq;
        (eta, self.dq / self.nsq - 2.0 * eta / self.n)
    }
}

impl Wave {
    fn start() -> Wave {
        Wave {
            w: [ZERO, ZERO],
            t: ONE,
        }
    }

    /// Crosses a layer in Γ form: Γ e^{2iδ}, t e^{iδ}, δ = k0 q d.
    fn cross_gamma(&mut self, one_way: C64, k0q: C64, k0_d: f64, dq: C64) -> Local {
        let round_trip = one_way * one_way;
        self.w[0] *= round_trip;
        self.t *= one_way;
        let mut local = Local {
            jac: [round_trip, ZERO, ZERO, ZERO],
            dw: [2.0 * I * k0q * self.w[0], ZERO],
            dl: I * k0q,
            ..Local::default()
        };
        local.dw_index[0] = [2.0 * I * k0_d * dq * self.w[0], ZERO];
        local.dl_index[0] = I * k0_d * dq;
        local
    }

    /// An interface in Γ form: Γ' = (x − y)/(x + y), t' = t c/(x + y) with
    /// x = a(1 + Γ), y = b(1 − Γ); `da`, `db`, `dlog_c` the derivatives of
    /// a, b and log c by the index of the medium below (`[0]`) and above.
    fn interface(
        &mut self,
        (a, b, c): (C64, C64, C64),
        da: [C64; 2],
        db: [C64; 2],
        dlog_c: [C64; 2],
    ) -> Local {
        let g = self.w[0];
        let inv = (a * (ONE + g) + b * (ONE - g)).inv();
        let x = a * (ONE + g);
        let y = b * (ONE - g);
        self.w[0] = (x - y) * inv;
        self.t *= c * inv;
        let (gamma_a, gamma_b) = (
            2.0 * y * (ONE + g) * inv * inv,
            -2.0 * x * (ONE - g) * inv * inv,
        );
        let (log_a, log_b) = (-(ONE + g) * inv, -(ONE - g) * inv);
        let mut local = Local {
            jac: [4.0 * a * b * inv * inv, ZERO, ZERO, ZERO],
            log_t: [-(a - b) * inv, ZERO],
            ..Local::default()
        };
        for m in 0..2 {
            local.dw_index[m] = [gamma_a * da[m] + gamma_b * db[m], ZERO];
            local.dl_index[m] = log_a * da[m] + log_b * db[m] + dlog_c[m];
        }
        local
    }

    /// Γ form to field form at admittance η (`d_eta` its derivative by the
    /// index of the medium below): u = 1 + Γ, v = η(1 − Γ).
    fn enter_fields(&mut self, eta: C64, d_eta: C64) -> Local {
        let g = self.w[0];
        self.w = [ONE + g, eta * (ONE - g)];
        let mut local = Local {
            jac: [ONE, ZERO, -eta, ZERO],
            ..Local::default()
        };
        local.dw_index[0] = [ZERO, d_eta * (ONE - g)];
        local
    }

    /// Field form back to Γ form into a medium of admittance η (`d_eta` its
    /// derivative by that medium's index): Γ = (ηu − v)/(ηu + v), t gains
    /// 2η/(ηu + v).
    fn leave_fields(&mut self, eta: C64, d_eta: C64) -> Local {
        let [u, v] = self.w;
        let inv = (eta * u + v).inv();
        self.w = [(eta * u - v) * inv, ZERO];
        self.t *= 2.0 * eta * inv;
        let inv2 = inv * inv;
        let mut local = Local {
            jac: [2.0 * eta * v * inv2, -2.0 * eta * u * inv2, ZERO, ZERO],
            log_t: [-eta * inv, -inv],
            ..Local::default()
        };
        local.dw_index[1] = [2.0 * u * v * inv2 * d_eta, ZERO];
        local.dl_index[1] = (eta.inv() - u * inv) * d_eta;
        local
    }
}

/// Adds the p transmission's factor N_above/N_below, which the field-form
/// steps carry, to a p step's index derivatives.
fn with_index_ratio(mut local: Local, above: &Medium, below: &Medium) -> Local {
    local.dl_index[0] -= below.n.inv();
    local.dl_index[1] += above.n.inv();
    local
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
    /// The derivatives of cos δ, sin δ/q and q sin δ by z = q² (scaled
    /// like them), and of log of the scale (i dδ/dz when scaled, else 0).
    d_cos: C64,
    d_sin_over_q: C64,
    d_q_sin: C64,
    d_log_scale: C64,
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
        // sinc'(δ)/δ = (δ cos δ − sin δ)/δ³, even and finite at δ = 0: by
        // its series where the difference would cancel.
        let sinc_slope = if !scaled && delta.norm_sqr() < 1e-2 {
            let d2 = delta * delta;
            C64::new(-1.0 / 3.0, 0.0) + d2 * (1.0 / 30.0 - d2 * (1.0 / 840.0 - d2 / 45360.0))
        } else {
            (delta * cos_d - sin_d) / (delta * delta * delta)
        };
        let z = q * q;
        let sin_over_q = k0_d * sinc_d;
        // d(sin δ/q)/dz = (k0 d)³ sinc'(δ)/(2δ); dδ/dz = k0 d/(2q).
        let d_sin_over_q_unscaled = 0.5 * k0_d * k0_d * k0_d * sinc_slope;
        let d_cos_unscaled = -0.5 * k0_d * sin_over_q;
        let d_log_scale = if scaled { I * k0_d / (2.0 * q) } else { ZERO };
        let d_sin_over_q = d_sin_over_q_unscaled + d_log_scale * sin_over_q;
        let q_sin = k0_d * z * sinc_d;
        FieldLayer {
            cos_d,
            sin_d,
            sin_over_q,
            q_sin,
            scale,
            scaled,
            d_cos: d_cos_unscaled + d_log_scale * cos_d,
            d_sin_over_q,
            // q sin δ = z (sin δ/q).
            d_q_sin: sin_over_q + z * d_sin_over_q,
            d_log_scale,
        }
    }

    /// Applies the layer to one polarization of admittance η = q / m
    /// (m = 1 for s, n² for p): u' = cos δ u − i (m sin δ/q) v,
    /// v' = −i (q/m) sin δ u + cos δ v, and records the derivative
    /// (δ = k0 q d: ∂δ/∂d = k0 q, and e^{iδ} adds i k0 q to ℓ when scaled).
    /// `dm` is dm/dN (0 for s): N enters through z = q² = N² − β² and m.
    fn cross(&self, wave: &mut Wave, k0: f64, q: C64, (m, dm): (C64, C64), n: C64) -> Local {
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
        // ∂M/∂N = 2N ∂M/∂z + ∂M/∂m dm/dN, the scale's derivative inside.
        let dz = 2.0 * n;
        let n00 = dz * self.d_cos;
        let n01 = -I * (dz * m * self.d_sin_over_q + dm * self.sin_over_q);
        let n10 = -I * (dz * self.d_q_sin / m - dm * self.q_sin / (m * m));
        let mut local = Local {
            jac,
            log_t: [ZERO, ZERO],
            dw,
            dl,
            ..Local::default()
        };
        local.dw_index[0] = [n00 * u + n01 * v, n10 * u + n00 * v];
        local.dl_index[0] = dz * self.d_log_scale;
        local
    }
}

/// [`recurse_media`](super::super::solver::recurse_media) with the
/// derivative of its amplitudes with respect to the thickness of each of
/// its `media − 2` finite media, written into `out` (medium j + 1's at
/// `out[j]`), and with respect to the complex index N of each of its
/// media, half-spaces included (at fixed β), into `out_index` (medium j's
/// at `out_index[j]`). `tape` is scratch, reused across calls.
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
    (out, out_index): (&mut [AmplitudeGradient], &mut [AmplitudeGradient]),
) -> Amplitudes {
    debug_assert_eq!(out.len(), media - 2);
    debug_assert_eq!(out_index.len(), media);
    let k0 = std::f64::consts::TAU / wavelength_nm;
    tape.clear();
    let last = media - 1;
    let n_sub = index(last);
    let mut below = Medium::new(n_sub, n_sub * n_sub, q_sub);
    let (mut s, mut p) = (Wave::start(), Wave::start());
    let mut in_fields = false;

    for j in (0..last).rev() {
        let above = if j == 0 {
            Medium::new(top[0], top[1], top[2])
        } else {
            let n = index(j);
            let nsq = n * n;
            Medium::new(n, nsq, sqrt_upper(nsq - beta_sq))
        };
        if j + 1 < last {
            let k0_d = k0 * thickness(j);
            let (q, n) = (below.q, below.n);
            let (s_local, p_local) = if in_fields {
                let layer = FieldLayer::new(k0_d, q);
                (
                    layer.cross(&mut s, k0, q, (ONE, ZERO), n),
                    layer.cross(&mut p, k0, q, (below.nsq, 2.0 * n), n),
                )
            } else {
                let one_way = one_way(k0_d * q);
                let k0q = k0 * q;
                (
                    s.cross_gamma(one_way, k0q, k0_d, below.dq),
                    p.cross_gamma(one_way, k0q, k0_d, below.dq),
                )
            };
            tape.push(Step {
                layer: Some(j),
                medium: j + 1,
                s: s_local,
                p: p_local,
            });
        }
        let above_near_critical = j > 0 && near_critical(above.q, above.nsq);
        let (s_local, p_local) = match (in_fields, above_near_critical) {
            (false, false) => interface(&mut s, &mut p, &above, &below),
            (false, true) => {
                p.t *= above.n / below.n;
                in_fields = true;
                let p_local = p.enter_fields(below.q / below.nsq, below.eta_p().1);
                (
                    s.enter_fields(below.q, below.dq),
                    with_index_ratio(p_local, &above, &below),
                )
            }
            (true, true) => {
                p.t *= above.n / below.n;
                (identity(), with_index_ratio(identity(), &above, &below))
            }
            (true, false) => {
                p.t *= above.n / below.n;
                in_fields = false;
                let (eta_p, d_eta_p) = above.eta_p();
                let p_local = p.leave_fields(eta_p, d_eta_p);
                (
                    s.leave_fields(above.q, above.dq),
                    with_index_ratio(p_local, &above, &below),
                )
            }
        };
        tape.push(Step {
            layer: None,
            medium: j + 1,
            s: s_local,
            p: p_local,
        });
        below = above;
    }
    backward(tape, out, out_index);
    Amplitudes {
        rs: s.w[0],
        rp: p.w[0],
        ts: s.t,
        tp: p.t,
    }
}

/// A Γ-form interface for both polarizations: s has a = q_above,
/// b = q_below, c = 2 q_above; p has a = N²_below q_above,
/// b = N²_above q_below, c = 2 N_above N_below q_above.
fn interface(s: &mut Wave, p: &mut Wave, above: &Medium, below: &Medium) -> (Local, Local) {
    let s_local = s.interface(
        (above.q, below.q, 2.0 * above.q),
        [ZERO, above.dq],
        [below.dq, ZERO],
        [ZERO, dq_dn(above.dq, above.q)],
    );
    let p_local = p.interface(
        (
            below.nsq * above.q,
            above.nsq * below.q,
            2.0 * above.n * below.n * above.q,
        ),
        [2.0 * below.n * above.q, below.nsq * above.dq],
        [above.nsq * below.dq, 2.0 * above.n * below.q],
        [below.n.inv(), above.n.inv() + dq_dn(above.dq, above.q)],
    );
    (s_local, p_local)
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

    /// ∂Γ_top/∂N and ∂ℓ_top/∂N of a step through the index of its
    /// medium below (`slot` 0) or above (1).
    #[inline]
    fn index(&self, local: &Local, slot: usize) -> (C64, C64) {
        let [dw0, dw1] = local.dw_index[slot];
        (
            self.g[0] * dw0 + self.g[1] * dw1,
            self.h[0] * dw0 + self.h[1] * dw1 + local.dl_index[slot],
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

fn backward(tape: &[Step], out: &mut [AmplitudeGradient], out_index: &mut [AmplitudeGradient]) {
    out_index.fill(AmplitudeGradient::default());
    let top = Adjoint {
        g: [ONE, ZERO],
        h: [ZERO, ZERO],
    };
    let (mut s, mut p) = (top, top);
    for step in tape.iter().rev() {
        for (slot, medium) in [(0, step.medium), (1, step.medium - 1)] {
            let (rs, log_ts) = s.index(&step.s, slot);
            let (rp, log_tp) = p.index(&step.p, slot);
            let d = &mut out_index[medium];
            d.rs += rs;
            d.rp += rp;
            d.log_ts += log_ts;
            d.log_tp += log_tp;
        }
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
