//! Step 4, confirm: each chart evaluated with its doubled grid and grown
//! where its midpoint errors are short, then the charts packed into the
//! atlas.

use super::*;

/// The largest normalized midpoint errors of `chart` at `w` × `h` nodes,
/// along u and along v (each at the nodes' spacing and at twice it), over
/// the points it serves that the target applies to; and the exact values
/// at its nodes, row-major.
pub(super) fn chart_check(
    skeleton: &Skeleton,
    chart: &Chart,
    w: usize,
    h: usize,
    shares: Pair,
) -> Result<Checked> {
    let (nu, nv) = (2 * w - 1, 2 * h - 1);
    let fine = skeleton.req.film.chart_flat(chart, nu, nv)?;
    let ch = skeleton.req.film.channels();
    let node = |k: usize| &fine[k * ch..(k + 1) * ch];
    let mut sized = *chart;
    sized.rect.width = nu;
    sized.rect.height = nv;
    let corner = matches!(chart.coords, Coords::Corner { .. });
    let (d0, d1) = skeleton.thickness_nm;
    let (c0, c1) = skeleton.req.cos;
    let weight = |d: f64, c: f64| {
        if !corner {
            skeleton.weight(d, c)
        } else if chart.in_corner(d, c) && d >= d0 && d <= d1 && c >= c0 && c <= c1 {
            1.0
        } else {
            0.0
        }
    };
    let per_row: Vec<(Pair, Pair)> = (0..nv)
        .into_par_iter()
        .map(|j| {
            let (mut eu, mut ev) = ((0.0, 0.0), (0.0, 0.0));
            for i in 0..nu {
                let (odd_i, odd_j) = (i % 2 == 1, j % 2 == 1);
                if odd_i == odd_j {
                    continue;
                }
                let (d, c) = sized.node(i, j);
                let w = weight(d, c);
                if w == 0.0 {
                    continue;
                }
                let scaled = |e: Pair| (w * e.0, w * e.1);
                if odd_i {
                    eu = merge(
                        eu,
                        scaled(midpoint_pair(&|k| node(j * nu + k), i, nu, shares)),
                    );
                } else {
                    ev = merge(
                        ev,
                        scaled(midpoint_pair(&|k| node(k * nu + i), j, nv, shares)),
                    );
                }
            }
            (eu, ev)
        })
        .collect();
    let errors = per_row.iter().fold(((0.0, 0.0), (0.0, 0.0)), |a, b| {
        (merge(a.0, b.0), merge(a.1, b.1))
    });
    let coarse = (0..h)
        .flat_map(|j| (0..w).map(move |i| 2 * j * nu + 2 * i))
        .flat_map(|k| node(k).iter().copied())
        .collect();
    Ok((errors, coarse))
}

/// Refuses a chart check whose memory would exceed the budget (see
/// [`crate::limits`]): `channels` exact values (f64) at each node of the
/// doubled grid, and the chart's own nodes kept from them.
pub(super) fn within_budget(goal: Goal, w: usize, h: usize, channels: usize) -> Result<()> {
    let (coarse, fine) = (w as u64 * h as u64, (2 * w as u64 - 1) * (2 * h as u64 - 1));
    let estimate = crate::limits::product(&[fine.saturating_add(coarse)], channels as u64 * 8);
    let target = match (goal.max_abs, goal.max_de) {
        (Some(e), Some(de)) => format!("max-error {e:e}, max-de {de}"),
        (Some(e), None) => format!("max-error {e:e}"),
        (None, Some(de)) => format!("max-de {de}"),
        (None, None) => "atlas".to_string(),
    };
    crate::limits::check_allocation(
        &format!("{target}: a grid of {coarse} nodes checked at {fine}"),
        estimate,
    )
}

/// Evaluates a chart with its doubled grid and grows it until its midpoint
/// errors meet the target; returns it with its values as stored
/// ([`Film::channels`] per node, row-major).
pub(super) fn confirm(
    skeleton: &Skeleton,
    chart: Chart,
    goal: Goal,
    max_side: usize,
    progress: &dyn Fn(&str),
) -> Result<(Chart, Vec<f32>)> {
    let mut chart = chart;
    // A chart that met the target and was then tried smaller.
    let mut met: Option<(Chart, Vec<f32>)> = None;
    for _ in 0..MAX_GROWTH {
        let (w, h) = (chart.rect.width, chart.rect.height);
        if w > max_side || h > max_side || w.saturating_mul(h) > MAX_CHART_TEXELS {
            return Err(unreachable_target(skeleton, &chart, goal));
        }
        let ch = skeleton.req.film.channels();
        within_budget(goal, w, h, ch)?;
        let ((eu, ev), values) = chart_check(skeleton, &chart, w, h, goal.shares()?)?;
        finite(&values, ch)?;
        progress(&format!(
            "  {} {w}×{h}: midpoint error {:.2} (u) {:.2} (v) of what is allowed",
            chart_name(&chart),
            eu.0,
            ev.0
        ));
        if eu.0 <= 1.0 && ev.0 <= 1.0 {
            let stored = values.iter().map(|&x| goal.store(x)).collect();
            // The probe predicts from coarse spacings, where the error has
            // not reached its h² law: an axis far inside the target is
            // tried once at the size its measured error asks for.
            let smaller = (
                if eu.0 < SHRINK_BELOW {
                    needed_nodes(w, eu)
                } else {
                    w
                },
                if ev.0 < SHRINK_BELOW {
                    needed_nodes(h, ev)
                } else {
                    h
                },
            );
            if met.is_some() || smaller.0.max(2) * smaller.1.max(2) >= w * h {
                return Ok((chart, stored));
            }
            met = Some((chart, stored));
            chart.rect.width = smaller.0.max(2).min(w);
            chart.rect.height = smaller.1.max(2).min(h);
            continue;
        }
        if let Some(met) = met {
            // The smaller size misses: keep the one that met.
            return Ok(met);
        }
        if eu.0 > 1.0 {
            chart.rect.width = needed_nodes(w, eu).max(w + 1);
        }
        if ev.0 > 1.0 {
            chart.rect.height = needed_nodes(h, ev).max(h + 1);
        }
    }
    Err(unreachable_target(skeleton, &chart, goal))
}

/// Refuses values that are not all finite, naming the first node's.
pub(super) fn finite(values: &[f64], channels: usize) -> Result<()> {
    match values.iter().position(|x| !x.is_finite()) {
        Some(k) => {
            let v = &values[k - k % channels..k - k % channels + channels];
            Err(Error::invalid(
                "film",
                format!("R or T is not finite: {v:?}"),
            ))
        }
        None => Ok(()),
    }
}

/// Evaluates a chart the target is not sought on at its planned size, its
/// values as stored.
pub(super) fn evaluate_unsought(
    skeleton: &Skeleton,
    chart: Chart,
    goal: Goal,
    progress: &dyn Fn(&str),
) -> Result<(Chart, Vec<f32>)> {
    let (w, h) = (chart.rect.width, chart.rect.height);
    let film = skeleton.req.film;
    let values = film.chart_flat(&chart, w, h)?;
    finite(&values, film.channels())?;
    progress(&format!(
        "  {} {w}×{h}: target not sought",
        chart_name(&chart)
    ));
    Ok((chart, values.iter().map(|&x| goal.store(x)).collect()))
}

/// The most texels one chart may have.
pub(super) const MAX_CHART_TEXELS: usize = 1 << 24;
/// A confirmed chart whose midpoint error along an axis is below this
/// fraction of what is allowed is tried smaller along it.
pub(super) const SHRINK_BELOW: f64 = 0.3;

pub(super) fn chart_name(chart: &Chart) -> String {
    match chart.coords {
        Coords::Band { c, .. } => format!(
            "side {} band cos θ {:.4}–{:.4}",
            chart.side.index(),
            c.lo,
            c.hi
        ),
        Coords::Corner { .. } => format!("side {} corner", chart.side.index()),
    }
}

/// The one-line error for a target no chart within the size limits meets,
/// naming the region.
pub(super) fn unreachable_target(skeleton: &Skeleton, chart: &Chart, goal: Goal) -> Error {
    let what = match (goal.max_abs, goal.max_de) {
        (Some(a), Some(d)) => format!("max-error {a} and max-de {d}"),
        (Some(a), None) => format!("max-error {a}"),
        (None, Some(d)) => format!("max-de {d}"),
        (None, None) => "target".into(),
    };
    let region = match chart.coords {
        Coords::Band { c, .. } => format!(
            "cos θ {:.4}–{:.4} (θ {:.2}°–{:.2}°), thickness {}–{} nm",
            c.lo,
            c.hi,
            c.hi.acos().to_degrees(),
            c.lo.acos().to_degrees(),
            skeleton.thickness_nm.0,
            skeleton.thickness_nm.1
        ),
        Coords::Corner { scale_nm, radius } => format!(
            "the grazing corner (thickness below {:.1} nm, cos θ below {radius})",
            scale_nm * radius / skeleton.optical().s(0.0)
        ),
    };
    Error::invalid(
        what,
        format!(
            "not reached within the size limits ({}×{} texels needed, at most {MAX_CHART_TEXELS} a chart) on side {} at {region}",
            chart.rect.width, chart.rect.height, skeleton.req.side.index()
        ),
    )
}

/// Packs the charts into one image.
pub(super) fn assemble(
    charts: &[(Chart, Vec<f32>)],
    thickness_nm: (f64, f64),
    max_side: usize,
    channels: usize,
) -> Result<(Atlas, Image)> {
    let sizes: Vec<(usize, usize)> = charts
        .iter()
        .map(|(c, _)| (c.rect.width, c.rect.height))
        .collect();
    let (at, width, height) = pack(&sizes, max_side).ok_or_else(|| {
        Error::invalid(
            "atlas",
            format!("its charts ({sizes:?} texels) do not fit in {max_side}×{max_side}"),
        )
    })?;
    let mut image = Image::new(width, height, channels);
    let mut placed = Vec::with_capacity(charts.len());
    for ((chart, values), (x, y)) in charts.iter().zip(at) {
        let mut chart = *chart;
        chart.rect.x = x;
        chart.rect.y = y;
        for j in 0..chart.rect.height {
            for i in 0..chart.rect.width {
                let k = (j * chart.rect.width + i) * channels;
                image
                    .texel_mut(x + i, y + j)
                    .copy_from_slice(&values[k..k + channels]);
            }
        }
        placed.push(chart);
    }
    let atlas = Atlas {
        width,
        height,
        thickness_nm,
        charts: placed,
    };
    Ok((atlas, image))
}
