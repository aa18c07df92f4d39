//! The baker: exact responses on a grid via the split-stack form, and the
//! segment-refining search that meets an error target.
//!
//! [`crate::sweep`] evaluates a grid (the split-stack form along the
//! thickness axis), [`grid`] lays out the starting nodes and refines
//! segments, [`check`] measures a grid against its doubled grid and
//! [`store`] rounds values as the file stores them, [`header`] writes what
//! the table records; [`atlas`] bakes the atlas layout through
//! [`crate::atlas::search`].

mod atlas;
mod check;
mod grid;
mod header;
mod store;
#[cfg(test)]
mod tests;

use super::sample::Lut;
use super::validate::{max_or_nan, validate};
use super::{BakeSpec, Resolution, MAX_AXIS_NODES, MAX_NODES};
use crate::cancel::Cancel;
use crate::color::SpectralIntegrator;
use crate::error::{Error, Result};
use crate::sweep::{Grid, Prepared, Segment};
use check::{even_subgrid, measure, Check};
use grid::{doubled, initial_axes, refine};
use header::header;
use store::{representable, stored};

/// The sweep of `spec`'s stack, kind, colour integration and wavelengths.
fn prepare(spec: &BakeSpec) -> Result<Prepared> {
    Prepared::of(
        &spec.stack,
        spec.layer,
        spec.kind,
        SpectralIntegrator::with_white(spec.sampling, spec.white),
        spec.wavelength_nm,
        Cancel::never(),
    )
}

/// Bakes a table (no progress output; see [`bake_with_progress`]).
pub fn bake(spec: &BakeSpec) -> Result<Lut> {
    bake_with_progress(spec, &|_| {})
}

/// The seed of the validation a bake records (and `irid validate` uses by
/// default), so the two report the same points.
pub const VALIDATION_SEED: u64 = 1;

/// Refinement rounds before `--max-error` gives up.
const MAX_ROUNDS: usize = 24;
/// Upper bound on (fine-grid nodes × wavelengths) evaluated in one round,
/// about ten seconds of work: a target that needs more is reported, not
/// ground out.
const MAX_WORK: usize = 1 << 30;

/// Bakes a table, calling `progress` with the fraction of the current grid
/// evaluation done (it restarts at 0 for each grid the error search tries).
///
/// Every axis is a list of segments, each uniform (or graded towards a
/// critical angle). The baker evaluates the grid with every segment
/// subdivided once more, which gives the error of the table at every edge
/// midpoint and cell centre; with `--max-error` each segment whose error
/// exceeds its share is refined by the factor the h² error law predicts,
/// and the search repeats until the whole table meets the target (each
/// round copies what it shares with the previous round's grid instead of
/// evaluating it again, with the same result bit for bit). Then the
/// table is validated against the solver at `spec.validation_points` random
/// points; around any point above the target the search refines further.
/// The validation figures go into the header. A fixed resolution is baked
/// as asked, without validation (see [`super::validate`]); with
/// `spec.check` off it is evaluated at the table's nodes only and the header
/// records no bake check.
pub fn bake_with_progress(spec: &BakeSpec, progress: &(dyn Fn(f64) + Sync)) -> Result<Lut> {
    spec.validate()?;
    if spec.layout() == super::Layout::Atlas {
        return atlas::bake_atlas(spec, &|line| log::debug!("{line}"));
    }
    let prep = prepare(spec)?;
    let mut axes = initial_axes(spec, &prep);
    if !spec.check {
        // Only a fixed resolution gets here (see BakeSpec::validate).
        let grid = Grid::new(&axes, spec.kind);
        let values = prep.eval(&grid, None, progress, Cancel::never())?;
        let data: Vec<f32> = values.iter().map(|&v| stored(v, spec.half)).collect();
        representable(&data, &grid.nodes(), spec.kind, spec.half)?;
        return Lut::from_parts(header(spec, &prep, &grid, None, None), data)
            .map_err(|why| Error::invalid("baked table", why));
    }
    let target = match spec.resolution {
        Resolution::MaxError(e) => Some(e),
        Resolution::Nodes { .. } => None,
    };
    let wavelength_work = prep.stack_grid.wavelengths_nm().len().max(1);
    let mut round = 0;
    // The last round's grid and values: nodes it shares with the next one
    // are copied, not evaluated again.
    let mut previous: Option<(Grid, Vec<f64>)> = None;
    loop {
        round += 1;
        let coarse = Grid::new(&axes, spec.kind);
        let fine = Grid::new(&axes.clone().map(|a| doubled(&a)), spec.kind);
        within_limits(&coarse, &fine, wavelength_work, round, target)?;
        within_budget(&coarse, &fine, prep.channels, target)?;
        let clock = std::time::Instant::now();
        let values = prep.eval(&fine, previous.as_ref(), progress, Cancel::never())?;
        let eval_s = clock.elapsed().as_secs_f64();
        // The coarse table as it would be stored: the check interpolates it.
        let data = even_subgrid(&fine, &values, prep.channels, spec.half);
        let check = measure(&coarse, &fine, &values, &data, prep.channels);
        log::debug!(
            "bake round {round}: grid {:?} check {:.3e} worst at {:?} eval {eval_s:.3}s measure {:.3}s",
            coarse.axes.each_ref().map(|a| a.nodes.len()),
            check.max_all,
            [0, 1, 2].map(|a| fine.axes[a].nodes[check.worst_at[a]]),
            clock.elapsed().as_secs_f64() - eval_s,
        );
        match target {
            Some(e) if check.max_all > e => refine_to_share(&mut axes, &coarse, &check, e),
            _ => {
                representable(&data, &coarse.nodes(), spec.kind, spec.half)?;
                let header = header(spec, &prep, &coarse, Some(&check), target);
                let lut = Lut::from_parts(header, data)
                    .map_err(|why| Error::invalid("baked table", why))?;
                match target {
                    Some(t) if spec.validation_points > 0 => {
                        if let Some(lut) = validated(lut, spec, t, &mut axes)? {
                            return Ok(lut);
                        }
                    }
                    _ => return Ok(lut),
                }
            }
        }
        previous = Some((fine, values));
    }
}

/// Refuses a round whose grids exceed the size limits (or one round too
/// many): the error target, or a fixed resolution, is what is too large.
fn within_limits(
    coarse: &Grid,
    fine: &Grid,
    wavelength_work: usize,
    round: usize,
    target: Option<f64>,
) -> Result<()> {
    if fine.total().saturating_mul(wavelength_work) <= MAX_WORK
        && fine
            .axes
            .iter()
            .all(|a| a.nodes.len() <= 2 * MAX_AXIS_NODES)
        && coarse.total() <= MAX_NODES
        && round <= MAX_ROUNDS
    {
        return Ok(());
    }
    Err(match target {
        Some(target) => Error::invalid(
            "max-error",
            format!(
                "{target} is not reached within the size limits (the last grid tried has {} nodes)",
                coarse.total()
            ),
        ),
        // A fixed grid whose error check (every interval halved) would
        // exceed the limits: the resolution itself is what is too large.
        None => Error::invalid(
            "resolution",
            format!(
                "{} nodes is too large to bake and check within the size limits",
                coarse.total()
            ),
        ),
    })
}

/// Refuses a round whose memory would exceed the budget (see
/// [`crate::limits`]): the exact values at the fine grid's nodes (f64) and
/// the last round's, about a quarter as many, kept for reuse; the coarse
/// table as stored (f32) and the sampler's layout of it (32 bytes a node).
fn within_budget(coarse: &Grid, fine: &Grid, channels: usize, target: Option<f64>) -> Result<()> {
    let (fine_n, coarse_n) = (fine.total() as u64, coarse.total() as u64);
    let estimate = crate::limits::product(&[fine_n, channels as u64], 10).and_then(|v| {
        v.checked_add(crate::limits::product(
            &[coarse_n],
            4 * channels as u64 + 32,
        )?)
    });
    let what = match target {
        Some(target) => {
            format!("max-error {target:e}: a grid of {coarse_n} nodes checked at {fine_n}")
        }
        None => format!("resolution: a grid of {coarse_n} nodes checked at {fine_n}"),
    };
    crate::limits::check_allocation(&what, estimate)
}

/// Validates a table that meets `target` at the check's points against the
/// solver at random points: the table with the validation recorded, or
/// `None` after refining `axes` around the worst point when it misses there.
///
/// Midpoints are where interpolation error peaks for a smooth response, but
/// a feature narrower than the grid (a resonance near grazing incidence)
/// can peak between them.
fn validated(
    mut lut: Lut,
    spec: &BakeSpec,
    target: f64,
    axes: &mut [Vec<Segment>; 3],
) -> Result<Option<Lut>> {
    let stats = validate(&lut, spec.validation_points, VALIDATION_SEED)?;
    let worst = max_or_nan(&stats.figures.max_abs);
    if worst <= target {
        lut.set_validation(stats);
        return Ok(Some(lut));
    }
    for (a, segments) in axes.iter_mut().enumerate() {
        let x = stats.figures.worst_point[a];
        if let Some(k) = segments
            .iter()
            .position(|s| s.intervals > 0 && x >= s.start && x <= s.end)
        {
            let seg = segments[k];
            let finer = refine(&seg, 2 * seg.intervals);
            segments.splice(k..=k, finer);
        }
    }
    Ok(None)
}

/// Refines every segment whose check error exceeds its share of the target
/// `e` (split evenly over the axes the grid varies along) by the factor the
/// h² error law predicts; when only cell centres fail, splits the segments
/// around the worst one.
fn refine_to_share(axes: &mut [Vec<Segment>; 3], coarse: &Grid, check: &Check, e: f64) {
    let dims = coarse
        .axes
        .iter()
        .filter(|a| a.nodes.len() > 1)
        .count()
        .max(1);
    let share = e / dims as f64;
    let mut refined = false;
    for (a, segments) in axes.iter_mut().enumerate() {
        let mut next = Vec::with_capacity(segments.len() + 4);
        for (k, seg) in segments.iter().enumerate() {
            let err = check.segment_max[a][k];
            if seg.intervals == 0 || err <= share {
                next.push(*seg);
                continue;
            }
            refined = true;
            // Interpolation error falls as h²; aim 10% past the share,
            // but at most 4× per round: near a singularity (a gain
            // film's lasing pole) the h² law does not hold yet.
            let factor = ((err / share).sqrt() * 1.1).min(4.0);
            let m = ((seg.intervals as f64 * factor).ceil() as usize).max(seg.intervals + 1);
            next.extend(refine(seg, m));
        }
        *segments = next;
    }
    if !refined {
        // Only cell centres fail: split the segments around the worst one.
        for (a, segments) in axes.iter_mut().enumerate() {
            let i = check.worst_at[a];
            if i % 2 == 1 {
                let k = coarse.axes[a].segment_of_interval[(i - 1) / 2];
                segments[k].intervals *= 2;
            }
        }
    }
}
