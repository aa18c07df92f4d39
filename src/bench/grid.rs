//! Grid evaluation: R and T of one stack over thickness × angle × wavelength,
//! the workload the Python peers are timed on. The output layout is
//! `[thickness][angle][wavelength]`, row-major.

use std::time::Instant;

use num_complex::Complex64 as C64;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::optics::{solve, Stack};

#[derive(Clone, Debug)]
pub struct Grid {
    pub wavelengths_nm: Vec<f64>,
    pub angles_deg: Vec<f64>,
    /// Values for the varying layer; `None` keeps the stack's own thickness.
    pub thicknesses_nm: Option<Vec<f64>>,
}

impl Grid {
    pub fn thickness_count(&self) -> usize {
        self.thicknesses_nm.as_ref().map_or(1, Vec::len)
    }

    pub fn points(&self) -> usize {
        self.thickness_count() * self.angles_deg.len() * self.wavelengths_nm.len()
    }
}

#[derive(Clone, Debug)]
pub struct GridOutput {
    pub r: Vec<f64>,
    pub t: Vec<f64>,
    /// Complex indices of ambient, layers and substrate at each wavelength,
    /// `[wavelength][medium]`: what a peer must be given to solve the same problem.
    pub indices: Vec<C64>,
    pub media: usize,
    /// Wall time of the fastest repetition.
    pub seconds: f64,
}

/// Evaluates the grid `repeat` times on `threads` threads and keeps the
/// fastest wall time. Indices are looked up once per wavelength, outside the
/// timed region only in the sense that a renderer would cache them too; the
/// lookup is included in the time all the same.
pub fn evaluate(
    stack: &Stack,
    varying_layer: usize,
    grid: &Grid,
    threads: usize,
    repeat: usize,
) -> Result<GridOutput> {
    stack.validate()?;
    if varying_layer >= stack.layers.len() && grid.thicknesses_nm.is_some() {
        return Err(Error::invalid(
            "varying layer",
            format!(
                "{} but the stack has {} layers",
                varying_layer + 1,
                stack.layers.len()
            ),
        ));
    }
    if let Some(a) = grid.angles_deg.iter().find(|a| !(0.0..90.0).contains(*a)) {
        return Err(Error::invalid(
            "angle",
            format!("{a} is outside [0, 90) degrees"),
        ));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .build()
        .map_err(|e| Error::invalid("threads", e.to_string()))?;
    let media = stack.layers.len() + 2;
    let n_w = grid.wavelengths_nm.len();
    let rows = grid.thickness_count() * grid.angles_deg.len();
    let mut r = vec![0.0; rows * n_w];
    let mut t = vec![0.0; rows * n_w];
    let mut indices = Vec::new();
    let mut best = f64::INFINITY;
    for _ in 0..repeat.max(1) {
        let start = Instant::now();
        indices = indices_table(stack, &grid.wavelengths_nm)?;
        let base_thickness = stack.thicknesses_nm();
        let cosines: Vec<f64> = grid
            .angles_deg
            .iter()
            .map(|a| a.to_radians().cos())
            .collect();
        pool.install(|| {
            r.par_chunks_mut(n_w)
                .zip(t.par_chunks_mut(n_w))
                .enumerate()
                .for_each_init(
                    || base_thickness.clone(),
                    |thick, (row, (r_row, t_row))| {
                        let (ti, ai) = (row / cosines.len(), row % cosines.len());
                        if let Some(ts) = &grid.thicknesses_nm {
                            thick[varying_layer] = ts[ti];
                        }
                        let cos = cosines[ai];
                        for (w, (&wavelength_nm, (r, t))) in grid
                            .wavelengths_nm
                            .iter()
                            .zip(r_row.iter_mut().zip(t_row.iter_mut()))
                            .enumerate()
                        {
                            let resp = solve(
                                &indices[w * media..(w + 1) * media],
                                thick,
                                wavelength_nm,
                                cos,
                            );
                            *r = resp.r();
                            *t = resp.t();
                        }
                    },
                );
        });
        best = best.min(start.elapsed().as_secs_f64());
    }
    Ok(GridOutput {
        r,
        t,
        indices,
        media,
        seconds: best,
    })
}

fn indices_table(stack: &Stack, wavelengths_nm: &[f64]) -> Result<Vec<C64>> {
    let mut all = Vec::with_capacity(wavelengths_nm.len() * (stack.layers.len() + 2));
    let mut one = Vec::new();
    for &w in wavelengths_nm {
        stack.indices_at(w, &mut one)?;
        all.extend_from_slice(&one);
    }
    Ok(all)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::stacks::find;

    #[test]
    fn grid_matches_pointwise_solve_in_any_thread_count() {
        let b = find("two-layer").unwrap().unwrap();
        let grid = Grid {
            wavelengths_nm: vec![400.0, 550.0, 700.0],
            angles_deg: vec![0.0, 45.0],
            thicknesses_nm: Some(vec![0.0, 120.0, 480.0]),
        };
        let one = evaluate(&b.stack, 0, &grid, 1, 1).unwrap();
        let two = evaluate(&b.stack, 0, &grid, 2, 1).unwrap();
        assert_eq!(one.r, two.r);
        let mut s = b.stack.clone();
        s.layers[0].thickness_nm = 480.0;
        let direct = s.response(700.0, 45f64.to_radians().cos()).unwrap();
        let last = one.r.len() - 1;
        assert_eq!(one.r[last], direct.r());
        assert_eq!(one.t[last], direct.t());
        assert!(evaluate(&b.stack, 5, &grid, 1, 1).is_err());
    }
}
