//! The dense tensor grid each slice is computed on (thickness × the μ
//! grid's cos θ nodes) and the cubic interpolation that fills a chart's
//! nodes from it.

use super::*;
use crate::cancel::Cancel;

/// The film's smooth colour on the dense thickness grid × the μ nodes, and
/// the cubic interpolation in thickness.
pub(super) struct Dense {
    /// Thickness nodes, uniform in w = ln(1 + (d − d_lo) / d₀).
    pub(super) lo_nm: f64,
    pub(super) step: f64,
    pub(super) count: usize,
    /// R, G, B at (μ node m, thickness t): `values[(m * count + t) * 3 + ch]`
    /// (one row of `3 * count` values per μ node, what the weighing sums).
    pub(super) values: Vec<f64>,
}

impl Dense {
    pub(super) fn position(&self, d: f64) -> f64 {
        if self.count < 2 {
            return 0.0;
        }
        ((d - self.lo_nm).max(0.0) / THICKNESS_SCALE_NM).ln_1p() / self.step
    }

    /// The four dense nodes around `d` and their Catmull–Rom weights
    /// (indices clamped at the ends).
    pub(super) fn stencil(&self, d: f64) -> ([usize; 4], [f64; 4]) {
        let last = self.count.saturating_sub(1);
        let pos = self.position(d).clamp(0.0, last as f64);
        let k = (pos.floor() as usize).min(last.saturating_sub(1));
        let t = pos - k as f64;
        let (t2, t3) = (t * t, t * t * t);
        let w = [
            -0.5 * t3 + t2 - 0.5 * t,
            1.5 * t3 - 2.5 * t2 + 1.0,
            -1.5 * t3 + 2.0 * t2 + 0.5 * t,
            0.5 * t3 - 0.5 * t2,
        ];
        let idx = |o: i64| (k as i64 + o).clamp(0, last as i64) as usize;
        ([idx(-1), idx(0), idx(1), idx(2)], w)
    }

    /// `out` (R, G, B at every dense thickness) = F_eff for `kernel`: the
    /// kernel's weighted sum of the μ rows, a row of the matrix product
    /// kernels × values, summed a cache-sized block of the row at a time.
    pub(super) fn weigh(&self, kernel: &Kernel, out: &mut [f64]) {
        const BLOCK: usize = 1024;
        let (first, weights) = kernel.weights();
        let len = 3 * self.count;
        out.fill(0.0);
        for start in (0..len).step_by(BLOCK) {
            let end = (start + BLOCK).min(len);
            for (j, &w) in weights.iter().enumerate() {
                let row = (first + j) * len;
                add_scaled(
                    w,
                    &self.values[row + start..row + end],
                    &mut out[start..end],
                );
            }
        }
    }
}

simd_dispatch! {
    /// `y += w x`, element by element (unfused: every copy rounds alike).
    pub(super) fn add_scaled(w: f64, x: &[f64], y: &mut [f64]) {
        for (y, x) in y.iter_mut().zip(x) {
            *y += w * *x;
        }
    }
}

/// F_eff at one roughness on the dense tensor grid:
/// `[(c * n_t + t) * 3 + ch]` for cos θ node c of the tables' grid, dense
/// thickness t and channel ch.
pub(super) type Table = Vec<f64>;

/// Where a point (thickness, cos θ) lies in the tables: the four dense
/// thicknesses and four cos θ nodes around it and their weights, found once
/// and applied to every slice's table.
#[derive(Clone, Copy)]
pub(super) struct Stencil {
    pub(super) thickness: [usize; 4],
    pub(super) thickness_weights: [f64; 4],
    pub(super) first_cos: usize,
    pub(super) cos_weights: [f64; 4],
}

/// What computes F_eff: the dense grid, the μ grid (its nodes are the μ of
/// the film's colour and the tables' cos θ), and the quadrature's rules.
pub(super) struct Filler<'a> {
    pub(super) dense: &'a Dense,
    pub(super) grid: &'a MuGrid,
    pub(super) rules: &'a Rules,
}

impl Filler<'_> {
    /// F_eff at every roughness of `roughness` on the dense tensor grid:
    /// one kernel per (roughness, cos θ node), each weighing the μ rows.
    pub(super) fn tables(&self, roughness: &[f64]) -> Vec<Table> {
        let len = 3 * self.dense.count;
        let cos = self.grid.nodes();
        roughness
            .iter()
            .map(|&r| {
                let mut table = vec![0.0; cos.len() * len];
                table
                    .par_chunks_mut(len)
                    .zip(cos.par_iter())
                    .for_each(|(out, &c)| {
                        let kernel = Kernel::with_rules(self.grid, c, r, self.rules);
                        self.dense.weigh(&kernel, out);
                    });
                table
            })
            .collect()
    }

    /// The stencil of (`d` nm, cos θ `c`): cubic in both.
    pub(super) fn stencil(&self, d: f64, c: f64) -> Stencil {
        let (thickness, thickness_weights) = self.dense.stencil(d);
        let (first_cos, cos_weights) = self.grid.interpolation(c);
        Stencil {
            thickness,
            thickness_weights,
            first_cos,
            cos_weights,
        }
    }

    /// F_eff from `table` at the point of `at`.
    pub(super) fn at(&self, table: &Table, at: &Stencil) -> [f64; 3] {
        let n_t = self.dense.count;
        let mut v = [0.0; 3];
        for (j, wc) in at.cos_weights.iter().enumerate() {
            let row = &table[(at.first_cos + j) * n_t * 3..];
            for (&i, wd) in at.thickness.iter().zip(at.thickness_weights) {
                let w = wc * wd;
                let texel = &row[i * 3..i * 3 + 3];
                for (o, x) in v.iter_mut().zip(texel) {
                    *o += w * x;
                }
            }
        }
        v
    }

    /// F_eff from `table` at each point of `at`.
    pub(super) fn values(&self, table: &Table, at: &[Stencil]) -> Vec<[f64; 3]> {
        at.iter().map(|s| self.at(table, s)).collect()
    }

    /// The stencils of every node of `chart` (its rectangle's size),
    /// row-major.
    pub(super) fn chart_stencils(&self, chart: &Chart) -> Vec<Stencil> {
        chart_nodes(chart)
            .into_iter()
            .map(|(d, c)| self.stencil(d, c))
            .collect()
    }
}

/// The dense thickness grid over every node's thickness and the film's
/// smooth colour on it × the quadrature's μ nodes.
pub(super) fn dense_grid(
    stack: &Stack,
    layer: usize,
    integrator: &SpectralIntegrator,
    nodes: &[(f64, f64)],
    grid: &MuGrid,
) -> Result<Dense> {
    let (lo, hi) = nodes
        .iter()
        .map(|n| n.0)
        .fold((f64::INFINITY, 0.0f64), |(a, b), d| (a.min(d), b.max(d)));
    let index = stack
        .layers
        .get(layer.wrapping_sub(1))
        .and_then(|l| l.material.index_at(550.0).ok())
        .map_or(1.0, |n| n.re.max(1.0));
    let period = SHORTEST_WAVELENGTH_NM / (2.0 * index);
    let span = hi - lo;
    let step = (FINEST_SPACING_NM / THICKNESS_SCALE_NM)
        .min(period / INTERVALS_PER_FRINGE / (span + THICKNESS_SCALE_NM));
    let (count, step) = if span > 1e-9 {
        let w = (span / THICKNESS_SCALE_NM).ln_1p();
        let n = (w / step).ceil() as usize;
        (n + 1, w / n as f64)
    } else {
        (1, 1.0)
    };
    let thickness: Vec<f64> = (0..count)
        .map(|k| lo + THICKNESS_SCALE_NM * (k as f64 * step).exp_m1())
        .collect();
    let mus = grid.nodes().len();
    crate::limits::check_allocation(
        &format!("F_eff over {count} thicknesses x {mus} μ nodes"),
        crate::limits::product(&[count as u64, mus as u64], 72),
    )?;
    // μ-major rows of thickness × RGB, as the weighing reads them.
    let values = rgb_at_nodes(
        stack,
        layer,
        integrator.clone(),
        &thickness,
        grid.nodes(),
        Cancel::never(),
    )?
    .into_iter()
    .flat_map(|v| [v[0], v[1], v[2]])
    .collect();
    Ok(Dense {
        lo_nm: lo,
        step,
        count,
        values,
    })
}
