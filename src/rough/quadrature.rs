//! Gauss–Legendre rules, and the resolution of the F_eff quadrature.

/// How finely F_eff is computed (see docs/rough.md for what each controls
/// and the convergence it reaches). [`Quadrature::default`] is what irid
/// uses everywhere; [`Quadrature::finer`] doubles every count, which is how
/// the tests measure the default's error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Quadrature {
    /// Intervals of the μ = v·h grid the film's smooth colour is computed
    /// on (and interpolated between, cubically).
    pub mu_intervals: usize,
    /// Gauss–Legendre points per panel of the integral over μ.
    pub outer: usize,
    /// Gauss–Legendre points of the integral over the azimuth of h about v.
    pub inner: usize,
}

impl Default for Quadrature {
    fn default() -> Self {
        Quadrature {
            mu_intervals: 128,
            outer: 4,
            inner: 16,
        }
    }
}

impl Quadrature {
    /// Every count doubled.
    pub fn finer(&self) -> Quadrature {
        Quadrature {
            mu_intervals: 2 * self.mu_intervals,
            outer: 2 * self.outer,
            inner: 2 * self.inner,
        }
    }
}

/// An n-point Gauss–Legendre rule on [0, 1]: nodes ascending, weights
/// summing to 1.
#[derive(Clone, Debug)]
pub(crate) struct Rule {
    pub(crate) nodes: Vec<f64>,
    pub(crate) weights: Vec<f64>,
}

impl Rule {
    /// The n-point rule (n ≥ 1), its nodes the roots of P_n found by
    /// Newton's method from the Chebyshev-like first guesses
    /// cos(π (i − 1/4) / (n + 1/2)), weights 2 / ((1 − x²) P_n'(x)²) on
    /// [−1, 1], then mapped to [0, 1].
    pub(crate) fn gauss_legendre(n: usize) -> Rule {
        let n = n.max(1);
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        for i in 0..n.div_ceil(2) {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut derivative = 1.0;
            for _ in 0..100 {
                let (p, dp) = legendre(n, x);
                derivative = dp;
                let step = p / dp;
                x -= step;
                if step.abs() < 1e-16 {
                    break;
                }
            }
            let (_, dp) = legendre(n, x);
            derivative = if dp.is_finite() { dp } else { derivative };
            let w = 2.0 / ((1.0 - x * x) * derivative * derivative);
            // x is the i-th largest root: symmetric pairs on [0, 1].
            nodes[n - 1 - i] = 0.5 * (1.0 + x);
            nodes[i] = 0.5 * (1.0 - x);
            weights[n - 1 - i] = 0.5 * w;
            weights[i] = 0.5 * w;
        }
        Rule { nodes, weights }
    }
}

/// P_n(x) and P_n'(x) by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    for k in 2..=n {
        let k = k as f64;
        let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    if n == 0 {
        return (1.0, 0.0);
    }
    let dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
    (p1, dp)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An n-point rule integrates polynomials of degree 2n − 1 exactly.
    #[test]
    fn rules_are_exact_to_degree_2n_minus_1() {
        for n in [1, 2, 3, 6, 7, 24, 48] {
            let rule = Rule::gauss_legendre(n);
            assert!(rule.nodes.windows(2).all(|w| w[0] < w[1]));
            for degree in 0..2 * n {
                let got: f64 = rule
                    .nodes
                    .iter()
                    .zip(&rule.weights)
                    .map(|(x, w)| w * x.powi(degree as i32))
                    .sum();
                let want = 1.0 / (degree as f64 + 1.0);
                assert!((got - want).abs() < 1e-14, "n {n} degree {degree}: {got}");
            }
        }
    }
}
