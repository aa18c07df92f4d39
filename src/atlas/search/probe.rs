//! Step 2, the probe: each piece evaluated once on a coarse chart and its
//! doubled grid, giving the spacing the target needs along u and v.

use super::*;

/// Per probe row: how dense each band over it must be (see [`cut_bands`]).
pub(super) struct RowNeeds {
    /// cos θ of each probe node row.
    pub(super) c: Vec<f64>,
    /// Per p₀ choice and node row: max over the row of 1 / (needed p
    /// spacing · dU/dp), U = ln(1 + p/p₀) (or p): a band over the row needs
    /// (U(hi) − U(lo)) times this many intervals.
    pub(super) u: Vec<Vec<f64>>,
    /// Per offset choice and row interval: max of 1 / (needed cos θ spacing
    /// · dW/dc), likewise.
    pub(super) v: Vec<Vec<f64>>,
}

/// The largest normalized midpoint errors at one spacing and at twice it.
pub(super) type Pair = (f64, f64);

/// A chart's midpoint errors along u and v, and its exact node values
/// ([`Film::channels`] per node, row-major).
pub(super) type Checked = ((Pair, Pair), Vec<f64>);

pub(super) fn merge(a: Pair, b: Pair) -> Pair {
    (a.0.max(b.0), a.1.max(b.1))
}

/// The error's exponent from the largest errors at one spacing and at twice
/// it, within [1, 2] (2 for a smooth function at fine enough spacing).
pub(super) fn exponent((e1, e2): Pair) -> f64 {
    if e1 > 0.0 && e2 > e1 {
        (e2 / e1).log2().clamp(1.0, 2.0)
    } else {
        2.0
    }
}

/// Nodes an axis of `n` nodes needs so that its normalized midpoint error
/// `e` (measured with `e` at twice the spacing too) falls to 1.
pub(super) fn needed_nodes(n: usize, (e1, e2): Pair) -> usize {
    if e1.is_nan() || e1 <= 0.0 || n < 2 {
        return n.max(2);
    }
    nodes_for((n - 1) as f64 * e1.powf(1.0 / exponent((e1, e2))))
}

/// Nodes for an axis that needs `x` intervals (5 % to spare).
pub(super) fn nodes_for(x: f64) -> usize {
    if !x.is_finite() || x > 1e9 {
        return 1 << 30;
    }
    ((x * 1.05).ceil() as usize + 1).max(2)
}

/// Normalized midpoint errors of one axis at node k of a line of fine
/// values `at(k)`: between its neighbours, and between the ones two away.
pub(super) fn midpoint_pair<'a>(
    at: &dyn Fn(usize) -> &'a [f64],
    k: usize,
    n: usize,
    shares: Pair,
) -> Pair {
    let err = |a: usize, b: usize| normalized_error(at(a), at(b), at(k), shares);
    let e1 = err(k - 1, k + 1);
    let e2 = if k >= 2 && k + 2 < n {
        err(k - 2, k + 2)
    } else {
        0.0
    };
    (e1, e2)
}

/// Evaluates the probe of one piece and what it asks of its bands.
pub(super) fn probe(skeleton: &Skeleton, piece: &Piece, shares: Pair) -> Result<RowNeeds> {
    let optical = skeleton.optical();
    let (probe_p, probe_c) = (
        band_p(skeleton, PROBE_P0_NM, piece.lo, piece.hi),
        piece.axis(piece.lo, piece.hi, PROBE_OFFSET),
    );
    let chart = Chart {
        side: skeleton.req.side,
        optical,
        coords: Coords::Band {
            p: probe_p,
            c: probe_c,
        },
        rect: Rect {
            x: 0,
            y: 0,
            width: PROBE_U,
            height: PROBE_V,
        },
    };
    let (nu, nv) = (2 * PROBE_U - 1, 2 * PROBE_V - 1);
    let fine = skeleton.req.film.chart_flat(&chart, nu, nv)?;
    let ch = skeleton.req.film.channels();
    let node = |k: usize| &fine[k * ch..(k + 1) * ch];
    let mut sized = chart;
    sized.rect.width = nu;
    sized.rect.height = nv;
    let (dx, dy) = (1.0 / (PROBE_U - 1) as f64, 1.0 / (PROBE_V - 1) as f64);
    let rows: Vec<(Vec<f64>, Vec<f64>)> = (0..nv)
        .into_par_iter()
        .map(|jj| {
            let c = sized.node(0, jj).1;
            let mut u = vec![0.0; P0_CHOICES.len()];
            let mut v = vec![0.0; OFFSET_CHOICES.len()];
            let odd_row = jj % 2 == 1;
            let mut errors = Vec::new();
            let mut pair = (0.0, 0.0);
            for i in (0..nu).filter(|i| (i % 2 == 1) != odd_row) {
                let d = sized.node(i, jj).0;
                let weight = skeleton.weight(d, c);
                if weight == 0.0 || (!odd_row && (i == 0 || i + 1 == nu)) {
                    continue;
                }
                let e = if odd_row {
                    midpoint_pair(&|k| node(k * nu + i), jj, nv, shares)
                } else {
                    midpoint_pair(&|k| node(jj * nu + k), i, nu, shares)
                };
                let e = (weight * e.0, weight * e.1);
                pair = merge(pair, e);
                errors.push((d * optical.s(c), e.0));
            }
            let alpha = exponent(pair);
            for (p, e) in errors.into_iter().filter(|e| e.1 > 0.0) {
                if odd_row {
                    let h = dy * e.powf(-1.0 / alpha) / probe_c.density(c);
                    for (k, &o) in OFFSET_CHOICES.iter().enumerate() {
                        let slope = piece.axis(piece.lo, piece.hi, o).slope(c);
                        v[k] = f64::max(v[k], 1.0 / (h * slope));
                    }
                } else {
                    let h = dx * e.powf(-1.0 / alpha) / probe_p.density(p);
                    for (k, &p0) in P0_CHOICES.iter().enumerate() {
                        let slope = if p0 > 0.0 { 1.0 / (p0 + p) } else { 1.0 };
                        u[k] = f64::max(u[k], 1.0 / (h * slope));
                    }
                }
            }
            (u, v)
        })
        .collect();
    let needs = RowNeeds {
        c: (0..PROBE_V).map(|j| chart.node(0, j).1).collect(),
        u: (0..P0_CHOICES.len())
            .map(|k| (0..PROBE_V).map(|j| rows[2 * j].0[k]).collect())
            .collect(),
        v: (0..OFFSET_CHOICES.len())
            .map(|k| (0..PROBE_V - 1).map(|j| rows[2 * j + 1].1[k]).collect())
            .collect(),
    };
    Ok(needs)
}
