//! Bounded Levenberg–Marquardt: minimizes Σ rᵢ(x)² for residuals r of a
//! few parameters x inside a box, given r and its Jacobian.
//!
//! Each step solves (JᵀJ + λ D) δ = −Jᵀr with D the diagonal of JᵀJ
//! (Marquardt's scaling, so that thicknesses of different sensitivity step
//! alike), over the parameters not held at a bound by the gradient, and
//! projects x + δ into the box. λ follows Nielsen's rule: shrunk by the
//! ratio of actual to predicted decrease when a step is taken, doubled
//! (then quadrupled, ...) when refused.

use super::linalg::{cholesky, cholesky_solve, spd_inverse};
use crate::error::Result;

/// A least-squares model: writes the m residuals at `x` into `residuals`
/// and, when asked, the Jacobian into `jacobian`, parameter-major
/// (`jacobian[p * m + i]` = ∂rᵢ/∂x_p).
pub trait Residuals {
    /// Evaluates the residuals (and the Jacobian when `jacobian` is `Some`).
    fn evaluate(
        &mut self,
        x: &[f64],
        residuals: &mut [f64],
        jacobian: Option<&mut [f64]>,
    ) -> Result<()>;
}

impl<F> Residuals for F
where
    F: FnMut(&[f64], &mut [f64], Option<&mut [f64]>) -> Result<()>,
{
    fn evaluate(
        &mut self,
        x: &[f64],
        residuals: &mut [f64],
        jacobian: Option<&mut [f64]>,
    ) -> Result<()> {
        self(x, residuals, jacobian)
    }
}

/// When to stop.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Most Jacobian evaluations.
    pub max_iterations: usize,
    /// Converged when no parameter moves by more than this fraction of
    /// its size (plus this, absolute, for a parameter near 0).
    pub step_tolerance: f64,
    /// Converged when an accepted step lowers Σr² by less than this
    /// fraction of it.
    pub relative_tolerance: f64,
    /// Done once Σr² falls to this (0: never).
    pub chi2_floor: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            max_iterations: 100,
            step_tolerance: 1e-10,
            relative_tolerance: 1e-15,
            chi2_floor: 0.0,
        }
    }
}

/// Where the minimization ended.
#[derive(Clone, Debug)]
pub struct Minimum {
    /// The parameters.
    pub x: Vec<f64>,
    /// Σ rᵢ² there.
    pub chi2: f64,
    /// The residuals there.
    pub residuals: Vec<f64>,
    /// (JᵀJ)⁻¹ there, row-major, `None` when JᵀJ is singular (a parameter
    /// the residuals do not depend on).
    pub covariance: Option<Vec<f64>>,
    /// Jacobian evaluations made.
    pub iterations: usize,
}

/// Minimizes Σ r(x)² from `start` inside `bounds` (one closed interval per
/// parameter; `start` is clamped into it) for a model of `m` residuals.
pub fn minimize(
    model: &mut impl Residuals,
    m: usize,
    start: &[f64],
    bounds: &[(f64, f64)],
    options: &Options,
) -> Result<Minimum> {
    let n = start.len();
    let clamp = |x: &mut [f64]| {
        for (v, &(lo, hi)) in x.iter_mut().zip(bounds) {
            *v = v.clamp(lo, hi);
        }
    };
    let mut x = start.to_vec();
    clamp(&mut x);
    let (mut r, mut jac) = (vec![0.0; m], vec![0.0; n * m]);
    model.evaluate(&x, &mut r, Some(&mut jac))?;
    let mut chi2 = sum_sq(&r);
    let (mut jtj, mut g) = normal_equations(&jac, &r, n, m);
    let mut lambda = 1e-3 * (0..n).map(|p| jtj[p * n + p]).fold(0.0, f64::max);
    let mut nu = 2.0;
    let mut iterations = 1;
    let (mut r_new, mut x_new) = (vec![0.0; m], vec![0.0; n]);
    while iterations < options.max_iterations && chi2 > options.chi2_floor {
        let Some(step) = damped_step(&jtj, &g, &x, bounds, lambda, n) else {
            break;
        };
        for p in 0..n {
            x_new[p] = x[p] + step[p];
        }
        clamp(&mut x_new);
        let taken: Vec<f64> = (0..n).map(|p| x_new[p] - x[p]).collect();
        let tol = options.step_tolerance;
        if taken
            .iter()
            .zip(&x)
            .all(|(d, x)| d.abs() <= tol * (x.abs() + tol))
        {
            break;
        }
        model.evaluate(&x_new, &mut r_new, None)?;
        let chi2_new = sum_sq(&r_new);
        let predicted = -(2.0 * dot(&taken, &g) + quadratic(&jtj, &taken, n));
        if chi2_new < chi2 && predicted > 0.0 {
            let rho = (chi2 - chi2_new) / predicted;
            let decrease = (chi2 - chi2_new) / chi2;
            x.copy_from_slice(&x_new);
            r.copy_from_slice(&r_new);
            chi2 = chi2_new;
            model.evaluate(&x, &mut r, Some(&mut jac))?;
            (jtj, g) = normal_equations(&jac, &r, n, m);
            iterations += 1;
            lambda *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
            nu = 2.0;
            if decrease < options.relative_tolerance {
                break;
            }
        } else {
            lambda *= nu;
            nu *= 2.0;
            if !lambda.is_finite() || nu > 1e30 {
                break;
            }
        }
    }
    Ok(Minimum {
        covariance: spd_inverse(&jtj, n),
        x,
        chi2,
        residuals: r,
        iterations,
    })
}

/// The damped Gauss–Newton step over the parameters free to move: one held
/// at a bound by a gradient pointing out of the box stays.
fn damped_step(
    jtj: &[f64],
    g: &[f64],
    x: &[f64],
    bounds: &[(f64, f64)],
    lambda: f64,
    n: usize,
) -> Option<Vec<f64>> {
    let free: Vec<usize> = (0..n)
        .filter(|&p| {
            let (lo, hi) = bounds[p];
            !((x[p] <= lo && g[p] > 0.0) || (x[p] >= hi && g[p] < 0.0))
        })
        .collect();
    let k = free.len();
    if k == 0 {
        return None;
    }
    let mut a = vec![0.0; k * k];
    let mut b = vec![0.0; k];
    for (i, &p) in free.iter().enumerate() {
        for (j, &q) in free.iter().enumerate() {
            a[i * k + j] = jtj[p * n + q];
        }
        // Marquardt's scaling, floored so that a parameter with no
        // influence at this point still gets a finite step.
        let diagonal = jtj[p * n + p].max(1e-12 * (1.0 + lambda));
        a[i * k + i] += lambda * diagonal;
        b[i] = -g[p];
    }
    let l = cholesky(&a, k)?;
    cholesky_solve(&l, k, &mut b);
    let mut step = vec![0.0; n];
    for (i, &p) in free.iter().enumerate() {
        step[p] = b[i];
    }
    step.iter().all(|s| s.is_finite()).then_some(step)
}

/// JᵀJ (row-major n × n) and Jᵀr from a parameter-major Jacobian.
fn normal_equations(jac: &[f64], r: &[f64], n: usize, m: usize) -> (Vec<f64>, Vec<f64>) {
    let mut jtj = vec![0.0; n * n];
    let mut g = vec![0.0; n];
    for p in 0..n {
        let column_p = &jac[p * m..(p + 1) * m];
        g[p] = dot(column_p, r);
        for q in 0..=p {
            let v = dot(column_p, &jac[q * m..(q + 1) * m]);
            jtj[p * n + q] = v;
            jtj[q * n + p] = v;
        }
    }
    (jtj, g)
}

fn quadratic(a: &[f64], x: &[f64], n: usize) -> f64 {
    (0..n)
        .map(|i| x[i] * (0..n).map(|j| a[i * n + j] * x[j]).sum::<f64>())
        .sum()
}

pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

pub(super) fn sum_sq(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    const FREE: (f64, f64) = (f64::NEG_INFINITY, f64::INFINITY);

    /// Rosenbrock's valley as residuals (10(y − x²), 1 − x): the minimum 0
    /// at (1, 1) along a curved, badly scaled valley.
    #[test]
    fn rosenbrock_reaches_its_minimum() {
        let mut model = |x: &[f64], r: &mut [f64], j: Option<&mut [f64]>| {
            r[0] = 10.0 * (x[1] - x[0] * x[0]);
            r[1] = 1.0 - x[0];
            if let Some(j) = j {
                j.copy_from_slice(&[-20.0 * x[0], -1.0, 10.0, 0.0]);
            }
            Ok(())
        };
        let min = minimize(&mut model, 2, &[-1.2, 1.0], &[FREE; 2], &Options::default()).unwrap();
        assert!(
            (min.x[0] - 1.0).abs() < 1e-8 && (min.x[1] - 1.0).abs() < 1e-8,
            "{min:?}"
        );
        assert!(min.chi2 < 1e-16, "{min:?}");
    }

    /// y = a e^{−b t} sampled without noise: recovered exactly; with the
    /// covariance of the linearized model at the optimum.
    #[test]
    fn exponential_decay_and_its_covariance() {
        let t: Vec<f64> = (0..20).map(|i| i as f64 * 0.25).collect();
        let (a, b) = (2.5, 0.7);
        let y: Vec<f64> = t.iter().map(|t| a * (-b * t).exp()).collect();
        let mut model = |x: &[f64], r: &mut [f64], j: Option<&mut [f64]>| {
            for i in 0..t.len() {
                r[i] = x[0] * (-x[1] * t[i]).exp() - y[i];
            }
            if let Some(j) = j {
                for i in 0..t.len() {
                    let e = (-x[1] * t[i]).exp();
                    j[i] = e;
                    j[t.len() + i] = -x[0] * t[i] * e;
                }
            }
            Ok(())
        };
        let min = minimize(
            &mut model,
            t.len(),
            &[1.0, 2.0],
            &[FREE; 2],
            &Options::default(),
        )
        .unwrap();
        assert!(
            (min.x[0] - a).abs() < 1e-8 && (min.x[1] - b).abs() < 1e-8,
            "{min:?}"
        );
        // (JᵀJ)⁻¹ from the Jacobian written out at the truth.
        let (mut s00, mut s01, mut s11) = (0.0, 0.0, 0.0);
        for &t in &t {
            let e = (-b * t).exp();
            let (j0, j1) = (e, -a * t * e);
            s00 += j0 * j0;
            s01 += j0 * j1;
            s11 += j1 * j1;
        }
        let det = s00 * s11 - s01 * s01;
        let cov = min.covariance.unwrap();
        for (got, want) in cov
            .iter()
            .zip([s11 / det, -s01 / det, -s01 / det, s00 / det])
        {
            assert!((got - want).abs() < 1e-8 * want.abs(), "{got} {want}");
        }
    }

    /// A minimum outside the box ends on the bound, the other parameter at
    /// its own optimum given that bound.
    #[test]
    fn a_bound_holds() {
        // r = (x − 3, y − x/2): unbounded minimum (3, 1.5); with x ≤ 2 the
        // minimum is (2, 1).
        let mut model = |x: &[f64], r: &mut [f64], j: Option<&mut [f64]>| {
            r[0] = x[0] - 3.0;
            r[1] = x[1] - 0.5 * x[0];
            if let Some(j) = j {
                j.copy_from_slice(&[1.0, -0.5, 0.0, 1.0]);
            }
            Ok(())
        };
        let bounds = [(0.0, 2.0), (-5.0, 5.0)];
        let min = minimize(&mut model, 2, &[0.5, 0.0], &bounds, &Options::default()).unwrap();
        assert_eq!(min.x[0], 2.0);
        assert!((min.x[1] - 1.0).abs() < 1e-8, "{min:?}");
    }

    /// A parameter the residuals ignore has no covariance.
    #[test]
    fn an_unconstrained_parameter_has_no_covariance() {
        let mut model = |x: &[f64], r: &mut [f64], j: Option<&mut [f64]>| {
            r[0] = x[0] - 1.0;
            if let Some(j) = j {
                j.copy_from_slice(&[1.0, 0.0]);
            }
            Ok(())
        };
        let min = minimize(&mut model, 1, &[0.0, 0.0], &[FREE; 2], &Options::default()).unwrap();
        assert!((min.x[0] - 1.0).abs() < 1e-8, "{min:?}");
        assert!(min.covariance.is_none());
    }
}
