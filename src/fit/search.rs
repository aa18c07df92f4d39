//! The global search over interference orders: a coarse scan of the varied
//! thicknesses inside their bounds, local refinement (bounded
//! Levenberg–Marquardt with the model's Jacobian) from the best distinct
//! scan points, then hops along each thickness axis from the best minimum
//! until no scan along an axis finds a lower basin.
//!
//! A thickness landscape repeats roughly every half wave of optical path:
//! the scan steps a quarter of that period at the shortest wavelength (the
//! model's [`Model::scan_steps`]), so that every basin holds a scan point.
//! When the full grid would exceed the budget (many varied layers), the
//! scan takes a Halton sequence of the budget's size instead, and the axis
//! hops make up for its sparser cover.

use rayon::prelude::*;

use super::lm::{minimize, Minimum, Options};
use crate::error::Result;

/// What predicts: a stack's spectrum or colours as a function of the varied
/// thicknesses, independent of any measurement.
pub(crate) trait Model: Sync {
    /// Values predicted per evaluation.
    fn predictions(&self) -> usize;
    /// The predictions at `x` into `out`.
    fn predict(&self, x: &[f64], out: &mut [f64]) -> Result<()>;
    /// The predictions and their Jacobian, parameter-major
    /// (`jacobian[p * predictions + i]`).
    fn predict_with_jacobian(&self, x: &[f64], out: &mut [f64], jacobian: &mut [f64])
        -> Result<()>;
    /// The scan step of each parameter: a quarter of its shortest period.
    fn scan_steps(&self) -> Vec<f64>;
}

/// What is minimized: residuals of the predictions against one measurement.
pub(crate) trait Loss: Sync {
    /// How many residuals.
    fn residual_count(&self) -> usize;
    /// The residuals of predictions `p`.
    fn residuals(&self, p: &[f64], r: &mut [f64]);
    /// The residuals and their Jacobian from the predictions' (both
    /// parameter-major).
    fn chain(&self, p: &[f64], dp: &[f64], r: &mut [f64], jacobian: &mut [f64]);
    /// Σr² below which a refinement is done (0: run to convergence).
    fn chi2_floor(&self) -> f64 {
        0.0
    }
}

/// The scan: points inside the bounds and the model's predictions there,
/// computed once and reused for every measurement of a batch.
pub(crate) struct Library {
    points: Vec<Vec<f64>>,
    predictions: Vec<f64>,
    width: usize,
    steps: Vec<f64>,
}

impl Library {
    /// Scans `model` over `bounds` (at most `budget` points, plus `start`).
    pub fn new(
        model: &impl Model,
        bounds: &[(f64, f64)],
        start: &[f64],
        budget: usize,
    ) -> Result<Library> {
        let steps = model.scan_steps();
        let mut points = scan_points(bounds, &steps, budget);
        points.push(start.to_vec());
        let width = model.predictions();
        let rows: Vec<Vec<f64>> = points
            .par_iter()
            .map(|x| {
                let mut p = vec![0.0; width];
                model.predict(x, &mut p).map(|_| p)
            })
            .collect::<Result<_>>()?;
        Ok(Library {
            points,
            predictions: rows.concat(),
            width,
            steps,
        })
    }

    /// The number of scanned points.
    pub fn len(&self) -> usize {
        self.points.len()
    }
}

/// The minima a search found, best first.
#[derive(Clone, Debug)]
pub(crate) struct Found {
    /// Distinct local minima, ascending χ².
    pub minima: Vec<Minimum>,
}

/// How many scan points the local refinement starts from.
fn candidate_count(parameters: usize) -> usize {
    4 + 2 * parameters
}

/// Finds the lowest minimum of `loss` over the model inside `bounds`,
/// starting from the library's best distinct points.
pub(crate) fn search(
    model: &impl Model,
    loss: &impl Loss,
    library: &Library,
    bounds: &[(f64, f64)],
) -> Result<Found> {
    let mut r = vec![0.0; loss.residual_count()];
    let mut scored: Vec<(f64, usize)> = (0..library.len())
        .map(|i| {
            let p = &library.predictions[i * library.width..(i + 1) * library.width];
            loss.residuals(p, &mut r);
            (super::lm::sum_sq(&r), i)
        })
        .collect();
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut starts: Vec<&[f64]> = Vec::new();
    for &(_, i) in &scored {
        let x = &library.points[i];
        if starts.iter().all(|s| !same_cell(s, x, &library.steps)) {
            starts.push(x);
            if starts.len() == candidate_count(bounds.len()) {
                break;
            }
        }
    }
    let mut minima: Vec<Minimum> = starts
        .par_iter()
        .map(|x| refine(model, loss, x, bounds))
        .collect::<Result<_>>()?;
    minima.sort_by(|a, b| a.chi2.total_cmp(&b.chi2));
    hop_along_axes(model, loss, bounds, &library.steps, &mut minima)?;
    Ok(Found {
        minima: distinct(minima, &library.steps),
    })
}

/// Local refinement from `x`.
pub(crate) fn refine(
    model: &impl Model,
    loss: &impl Loss,
    x: &[f64],
    bounds: &[(f64, f64)],
) -> Result<Minimum> {
    let (n, m) = (x.len(), loss.residual_count());
    let width = model.predictions();
    let (mut p, mut dp) = (vec![0.0; width], vec![0.0; width * n]);
    let mut residuals = |x: &[f64], r: &mut [f64], jacobian: Option<&mut [f64]>| -> Result<()> {
        match jacobian {
            Some(jacobian) => {
                model.predict_with_jacobian(x, &mut p, &mut dp)?;
                loss.chain(&p, &dp, r, jacobian);
            }
            None => {
                model.predict(x, &mut p)?;
                loss.residuals(&p, r);
            }
        }
        Ok(())
    };
    let options = Options {
        chi2_floor: loss.chi2_floor(),
        ..Options::default()
    };
    minimize(&mut residuals, m, x, bounds, &options)
}

/// From the best minimum, scans each parameter alone across its bounds (the
/// others held) at half the scan step; a point below the best starts a
/// refinement, and a lower minimum found so becomes the best. Repeats until
/// a round finds nothing lower.
fn hop_along_axes(
    model: &impl Model,
    loss: &impl Loss,
    bounds: &[(f64, f64)],
    steps: &[f64],
    minima: &mut Vec<Minimum>,
) -> Result<()> {
    const ROUNDS: usize = 8;
    let width = model.predictions();
    for _ in 0..ROUNDS {
        let best = minima[0].clone();
        let lines: Vec<Vec<f64>> = (0..bounds.len())
            .flat_map(|axis| {
                let (lo, hi) = bounds[axis];
                let count = ((hi - lo) / (0.5 * steps[axis])).ceil() as usize + 1;
                let best = &best;
                (0..count).map(move |i| {
                    let mut x = best.x.clone();
                    x[axis] = lo + (hi - lo) * i as f64 / (count - 1).max(1) as f64;
                    x
                })
            })
            .collect();
        let scores: Vec<f64> = lines
            .par_iter()
            .map(|x| {
                let (mut p, mut r) = (vec![0.0; width], vec![0.0; loss.residual_count()]);
                model.predict(x, &mut p)?;
                loss.residuals(&p, &mut r);
                Ok(super::lm::sum_sq(&r))
            })
            .collect::<Result<_>>()?;
        let mut below: Vec<(f64, &Vec<f64>)> = scores
            .iter()
            .zip(&lines)
            .filter(|(s, x)| **s < best.chi2 * (1.0 - 1e-9) && !same_cell(x, &best.x, steps))
            .map(|(s, x)| (*s, x))
            .collect();
        below.sort_by(|a, b| a.0.total_cmp(&b.0));
        below.truncate(candidate_count(bounds.len()));
        let found: Vec<Minimum> = below
            .par_iter()
            .map(|(_, x)| refine(model, loss, x, bounds))
            .collect::<Result<_>>()?;
        let improved = found.iter().any(|m| m.chi2 < best.chi2 * (1.0 - 1e-9));
        minima.extend(found);
        minima.sort_by(|a, b| a.chi2.total_cmp(&b.chi2));
        if !improved {
            break;
        }
    }
    Ok(())
}

/// True when `a` and `b` lie within one scan step of each other in every
/// parameter: the same basin as far as the scan can tell.
fn same_cell(a: &[f64], b: &[f64], steps: &[f64]) -> bool {
    a.iter()
        .zip(b)
        .zip(steps)
        .all(|((a, b), s)| (a - b).abs() <= *s)
}

/// Minima (ascending χ²) with repeats of one minimum dropped: two are the
/// same when every parameter agrees within a hundredth of a scan step.
fn distinct(minima: Vec<Minimum>, steps: &[f64]) -> Vec<Minimum> {
    let mut kept: Vec<Minimum> = Vec::new();
    for m in minima {
        let repeat = kept.iter().any(|k| {
            k.x.iter()
                .zip(&m.x)
                .zip(steps)
                .all(|((a, b), s)| (a - b).abs() <= 0.01 * s)
        });
        if !repeat {
            kept.push(m);
        }
    }
    kept
}

/// The scan: the full grid at `steps` when it has at most `budget` points,
/// else `budget` points of a Halton sequence over the box.
fn scan_points(bounds: &[(f64, f64)], steps: &[f64], budget: usize) -> Vec<Vec<f64>> {
    let counts: Vec<usize> = bounds
        .iter()
        .zip(steps)
        .map(|(&(lo, hi), &s)| {
            if hi > lo {
                ((hi - lo) / s).ceil().max(1.0) as usize + 1
            } else {
                1
            }
        })
        .collect();
    let at = |axis: usize, t: f64| bounds[axis].0 + (bounds[axis].1 - bounds[axis].0) * t;
    let total = counts
        .iter()
        .try_fold(1usize, |acc, &c| acc.checked_mul(c))
        .unwrap_or(usize::MAX);
    if total <= budget {
        return (0..total)
            .map(|mut i| {
                (0..bounds.len())
                    .map(|axis| {
                        let c = counts[axis];
                        let k = i % c;
                        i /= c;
                        at(
                            axis,
                            if c > 1 {
                                k as f64 / (c - 1) as f64
                            } else {
                                0.5
                            },
                        )
                    })
                    .collect()
            })
            .collect();
    }
    (1..=budget)
        .map(|i| {
            (0..bounds.len())
                .map(|axis| at(axis, radical_inverse(i, PRIMES[axis % PRIMES.len()])))
                .collect()
        })
        .collect()
}

const PRIMES: [usize; 16] = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53];

/// The van der Corput radical inverse of `i` in `base`: the Halton
/// sequence's coordinate.
fn radical_inverse(mut i: usize, base: usize) -> f64 {
    let (mut value, mut scale) = (0.0, 1.0 / base as f64);
    while i > 0 {
        value += (i % base) as f64 * scale;
        i /= base;
        scale /= base as f64;
    }
    value
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-parameter model with many minima: p = (cos x, sin x) against
    /// a target angle, so every basin repeats with period 2π and the search
    /// must find the one basin the bounds allow that reaches zero.
    struct Circle;
    impl Model for Circle {
        fn predictions(&self) -> usize {
            2
        }
        fn predict(&self, x: &[f64], out: &mut [f64]) -> Result<()> {
            out[0] = (x[0]).cos() + 0.3 * (x[0] * 0.1).cos();
            out[1] = (x[0]).sin();
            Ok(())
        }
        fn predict_with_jacobian(&self, x: &[f64], out: &mut [f64], j: &mut [f64]) -> Result<()> {
            self.predict(x, out)?;
            j[0] = -(x[0]).sin() - 0.03 * (x[0] * 0.1).sin();
            j[1] = (x[0]).cos();
            Ok(())
        }
        fn scan_steps(&self) -> Vec<f64> {
            vec![std::f64::consts::PI / 4.0]
        }
    }

    struct Target(Vec<f64>);
    impl Loss for Target {
        fn residual_count(&self) -> usize {
            self.0.len()
        }
        fn residuals(&self, p: &[f64], r: &mut [f64]) {
            for i in 0..r.len() {
                r[i] = p[i] - self.0[i];
            }
        }
        fn chain(&self, p: &[f64], dp: &[f64], r: &mut [f64], j: &mut [f64]) {
            self.residuals(p, r);
            j.copy_from_slice(dp);
        }
    }

    #[test]
    fn the_global_minimum_among_many() {
        let truth = 23.0;
        let mut p = [0.0; 2];
        Circle.predict(&[truth], &mut p).unwrap();
        let bounds = [(1.0, 40.0)];
        let library = Library::new(&Circle, &bounds, &[2.0], 4096).unwrap();
        let found = search(&Circle, &Target(p.to_vec()), &library, &bounds).unwrap();
        assert!((found.minima[0].x[0] - truth).abs() < 1e-6, "{found:?}");
        assert!(found.minima[0].chi2 < 1e-20);
        // Its neighbours a period away are minima too, but higher.
        assert!(found.minima.len() > 1 && found.minima[1].chi2 > 1e-4);
    }

    #[test]
    fn halton_covers_the_box() {
        let bounds = [(0.0, 1.0), (10.0, 20.0), (-1.0, 1.0)];
        let points = scan_points(&bounds, &[1e-3; 3], 1000);
        assert_eq!(points.len(), 1000);
        for axis in 0..3 {
            let (lo, hi) = bounds[axis];
            let mean = points.iter().map(|p| p[axis]).sum::<f64>() / 1000.0;
            assert!(
                (mean - 0.5 * (lo + hi)).abs() < 0.01 * (hi - lo),
                "{axis}: {mean}"
            );
            assert!(points.iter().all(|p| (lo..=hi).contains(&p[axis])));
        }
        // A small grid is scanned whole, corners included.
        let grid = scan_points(&[(0.0, 2.0), (5.0, 5.0)], &[1.0, 1.0], 1000);
        assert_eq!(grid.len(), 3);
        assert_eq!(grid[2], vec![2.0, 5.0]);
    }
}
