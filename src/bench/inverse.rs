//! Inverse design's speed (issue 38), in the report: the cost of the exact
//! thickness derivatives against the forward solve (a 20-layer stack, 401
//! wavelengths × 3 angles), a 3-layer fit to one 401-wavelength spectrum,
//! and the batched fit's spectra per second. The same workloads as
//! `benches/gradient.rs` and `benches/fit.rs`, timed here as the fastest of
//! a few runs so that `irid bench` reports them beside its other figures.

use std::time::Instant;

use crate::error::Result;
use crate::fit::{fit_spectrum, Measurement, SpectrumFitter, Vary};
use crate::optics::gradient::solve_stack_grid_with_gradient;
use crate::optics::{Layer, Material, Response, Stack, StackGrid};

/// The ceiling on the gradient's cost, in forward solves.
pub const GRADIENT_RATIO_TARGET: f64 = 3.0;

/// The ceiling on one 3-layer fit, in seconds.
pub const FIT_TARGET_S: f64 = 0.05;

/// Spectra in the batched fit.
pub const BATCH: usize = 64;

/// What the inverse-design workloads took.
#[derive(Clone, Debug, PartialEq)]
pub struct InverseFigures {
    /// Runs each time is the fastest of.
    pub repeat: usize,
    /// R and T of the 20-layer stack over the 401 × 3 grid, seconds.
    pub forward_s: f64,
    /// The same with the derivatives by all 20 thicknesses, seconds.
    pub gradient_s: f64,
    /// One 3-layer fit to one 401-wavelength spectrum, seconds.
    pub fit_s: f64,
    /// [`BATCH`] such spectra fitted at once, seconds.
    pub batch_s: f64,
    /// The batch's thicknesses, fitted, all within 1 nm of the truth.
    pub batch_recovered: bool,
}

impl InverseFigures {
    /// The gradient's cost in forward solves.
    pub fn gradient_ratio(&self) -> f64 {
        self.gradient_s / self.forward_s
    }

    /// The batched fit's throughput.
    pub fn spectra_per_second(&self) -> f64 {
        BATCH as f64 / self.batch_s
    }
}

/// Air, `layers` films alternating lossless (1.5) and absorbing
/// (2.3 + 0.05i), 100, 107, 114, ... nm, on a gold-like substrate: the
/// stack of `benches/gradient.rs`.
pub fn gradient_stack(layers: usize) -> Stack {
    Stack {
        ambient: Material::constant(1.0, 0.0),
        layers: (0..layers)
            .map(|i| {
                let m = if i % 2 == 0 {
                    Material::constant(1.5, 0.0)
                } else {
                    Material::constant(2.3, 0.05)
                };
                Layer::new(m, 100.0 + 7.0 * i as f64)
            })
            .collect(),
        substrate: Material::constant(0.27, 2.9),
    }
}

/// Three lossless films (2.3, 1.45, 2.1) of the given thicknesses on glass:
/// the stack of `benches/fit.rs`.
pub fn fit_stack(thicknesses_nm: &[f64]) -> Stack {
    Stack {
        ambient: Material::constant(1.0, 0.0),
        layers: thicknesses_nm
            .iter()
            .zip([2.3, 1.45, 2.1])
            .map(|(&d, n)| Layer::new(Material::constant(n, 0.0), d))
            .collect(),
        substrate: Material::constant(1.52, 0.0),
    }
}

/// R at normal incidence of [`fit_stack`]`(truth)`, 380–780 nm every 1 nm,
/// with a deterministic ripple of 1e-3 standing for noise (σ = 1e-3).
pub fn fit_measurement(truth: &[f64], seed: f64) -> Result<Measurement> {
    let wavelengths: Vec<f64> = (0..401).map(|i| 380.0 + i as f64).collect();
    let grid = StackGrid::new(&fit_stack(truth), &wavelengths)?;
    let mut out = vec![Response::default(); wavelengths.len()];
    grid.solve_spectrum(truth, 1.0, &mut out);
    Ok(Measurement {
        angle_deg: vec![0.0; wavelengths.len()],
        reflectance: Some(
            out.iter()
                .enumerate()
                .map(|(i, r)| r.r() + 1e-3 * (i as f64 * 1.3 + seed).sin())
                .collect(),
        ),
        sigma: Some(vec![1e-3; wavelengths.len()]),
        wavelength_nm: wavelengths,
        transmittance: None,
    })
}

/// The fastest of `repeat` runs of `run`, in seconds.
fn fastest(repeat: usize, mut run: impl FnMut() -> Result<()>) -> Result<f64> {
    let mut best = f64::INFINITY;
    for _ in 0..repeat.max(1) {
        let started = Instant::now();
        run()?;
        best = best.min(started.elapsed().as_secs_f64());
    }
    Ok(best)
}

/// Times the three workloads, each the fastest of `repeat` runs, on the
/// current rayon pool (the batched fit spreads its spectra over it).
pub fn run(repeat: usize) -> Result<InverseFigures> {
    let wavelengths: Vec<f64> = (0..401).map(|i| 400.0 + i as f64).collect();
    let cos: Vec<f64> = [0.0f64, 30.0, 60.0]
        .iter()
        .map(|a| a.to_radians().cos())
        .collect();
    let stack = gradient_stack(20);
    let grid = StackGrid::new(&stack, &wavelengths)?;
    let d = stack.thicknesses_nm();
    let mut out = vec![Response::default(); wavelengths.len() * cos.len()];
    let forward_s = fastest(repeat, || {
        grid.solve(std::hint::black_box(&cos), &mut out);
        Ok(())
    })?;
    let gradient_s = fastest(repeat, || {
        std::hint::black_box(solve_stack_grid_with_gradient(&grid, &d, &cos)?);
        Ok(())
    })?;

    let truth = [95.0, 160.0, 70.0];
    let start = fit_stack(&[110.0, 140.0, 80.0]);
    let bounds: Vec<(f64, f64)> = truth.iter().map(|d| (0.5 * d, 1.5 * d)).collect();
    let vary = Vary::new(&start, &[1, 2, 3], Some(&bounds), "vary", "bounds")?;
    let measured = fit_measurement(&truth, 0.0)?;
    let fit_s = fastest(repeat, || {
        fit_spectrum(&start, &vary, &measured).map(|_| ())
    })?;

    let truths: Vec<Vec<f64>> = (0..BATCH)
        .map(|i| truth.iter().map(|d| d * (1.0 + 0.002 * i as f64)).collect())
        .collect();
    let batch = truths
        .iter()
        .enumerate()
        .map(|(i, t)| fit_measurement(t, i as f64))
        .collect::<Result<Vec<_>>>()?;
    let fitter = SpectrumFitter::new(&start, &vary, &batch[0])?;
    let mut fits = Vec::new();
    let batch_s = fastest(repeat, || {
        fits = fitter.fit_many(&batch)?;
        Ok(())
    })?;
    let batch_recovered = fits.len() == BATCH
        && fits.iter().zip(&truths).all(|(f, t)| {
            f.thickness_nm
                .iter()
                .zip(t)
                .all(|(got, want)| (got - want).abs() <= 1.0)
        });
    Ok(InverseFigures {
        repeat,
        forward_s,
        gradient_s,
        fit_s,
        batch_s,
        batch_recovered,
    })
}

/// The report's "Inverse design" section.
pub fn markdown(f: &InverseFigures) -> String {
    let ms = |s: f64| format!("{:.3} ms", s * 1e3);
    let mut s = String::from("\n## Inverse design\n\n");
    s.push_str(&format!(
        "Each time is the fastest of {} runs in this process (docs/inverse.md).\n\n",
        f.repeat
    ));
    s.push_str("| workload | time | figure | issue 38's target |\n|---|---:|---:|---|\n");
    s.push_str(&format!(
        "| 20 layers, 401 wavelengths × 3 angles: R and T | {} | | |\n",
        ms(f.forward_s)
    ));
    s.push_str(&format!(
        "| the same with ∂R, ∂T (s, p) by all 20 thicknesses | {} | {:.2}× the forward | ≤ {GRADIENT_RATIO_TARGET}× |\n",
        ms(f.gradient_s),
        f.gradient_ratio()
    ));
    s.push_str(&format!(
        "| 3-layer fit to one 401-wavelength spectrum (bounds ±50 %) | {} | | < {} ms |\n",
        ms(f.fit_s),
        FIT_TARGET_S * 1e3
    ));
    s.push_str(&format!(
        "| batched fit, {BATCH} such spectra | {} | {:.0} spectra/s | reported |\n",
        ms(f.batch_s),
        f.spectra_per_second()
    ));
    if !f.batch_recovered {
        s.push_str("\nThe batched fit missed a thickness by more than 1 nm: the figures above are not of a working fit.\n");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One run of each workload: every time is positive and finite, the
    /// batch recovers its thicknesses, and the section has its four rows
    /// with the figures it derives.
    #[test]
    fn inverse_design_rows() {
        let f = run(1).unwrap();
        for t in [f.forward_s, f.gradient_s, f.fit_s, f.batch_s] {
            assert!(t > 0.0 && t.is_finite(), "{f:?}");
        }
        assert!(f.batch_recovered, "{f:?}");
        let md = markdown(&f);
        assert_eq!(
            md.lines().filter(|l| l.starts_with("| ")).count(),
            5,
            "{md}"
        );
        assert!(
            md.contains(&format!("{:.2}× the forward", f.gradient_ratio())),
            "{md}"
        );
        assert!(
            md.contains(&format!("{:.0} spectra/s", f.spectra_per_second())),
            "{md}"
        );
        assert!(!md.contains("missed"), "{md}");
    }
}
