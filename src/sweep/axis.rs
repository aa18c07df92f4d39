//! Axes as segments: each a uniform or graded run of nodes, the form the
//! baker refines and the sweep recognises evenly spaced runs in.

/// Where nodes crowd inside a segment of an axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Grading {
    Uniform,
    /// Quartic crowding towards the segment's start: a square-root branch
    /// point there (the substrate's critical angle) is then interpolated
    /// with second-order error, like a smooth function.
    TowardStart,
    TowardEnd,
}

/// A contiguous piece of an axis with its node spacing rule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Segment {
    pub start: f64,
    pub end: f64,
    pub grading: Grading,
    /// Number of intervals (nodes − 1) in this segment.
    pub intervals: usize,
}

/// The share of a graded segment's intervals spent in the quartic part.
const GRADED_SHARE: f64 = 0.25;

/// Distance from the crowded end as a fraction of the segment, for the
/// fraction `u` of its intervals: A·u⁴ up to `GRADED_SHARE`, then linear
/// with matching slope, so spacing far from the branch point is uniform
/// (about 1.23× the ungraded spacing) and shrinks as u³ close to it.
pub(crate) fn graded(u: f64) -> f64 {
    let u0 = GRADED_SHARE;
    let a = 1.0 / (u0.powi(4) + 4.0 * u0.powi(3) * (1.0 - u0));
    if u <= u0 {
        a * u.powi(4)
    } else {
        a * (u0.powi(4) + 4.0 * u0.powi(3) * (u - u0))
    }
}

/// The node positions of an axis made of segments (each segment's end is
/// the next one's start, listed once).
pub(crate) fn segment_nodes(segments: &[Segment]) -> Vec<f64> {
    let mut nodes = Vec::new();
    for (k, s) in segments.iter().enumerate() {
        let m = s.intervals;
        let first = if k == 0 { 0 } else { 1 };
        if m == 0 {
            if k == 0 {
                nodes.push(s.start);
            }
            continue;
        }
        let len = s.end - s.start;
        for i in first..=m {
            let u = i as f64 / m as f64;
            let x = match s.grading {
                Grading::Uniform => s.start + len * u,
                Grading::TowardStart => s.start + len * graded(u),
                Grading::TowardEnd => s.end - len * graded(1.0 - u),
            };
            // Endpoints exactly, so segments join on the same node.
            nodes.push(if i == m { s.end } else { x });
        }
    }
    nodes
}

/// Splits `intervals` among segments in proportion to their lengths, at
/// least one each.
pub(crate) fn share_intervals(segments: &mut [Segment], intervals: usize) {
    let total: f64 = segments.iter().map(|s| s.end - s.start).sum();
    let count = segments.len();
    let mut left = intervals.max(count);
    for (k, s) in segments.iter_mut().enumerate() {
        let want = if k + 1 == count {
            left
        } else {
            let share = ((s.end - s.start) / total * intervals as f64).round() as usize;
            share.clamp(1, left - (count - k - 1))
        };
        s.intervals = want;
        left -= want;
    }
}

/// A uniform segment over [start, end] with `intervals` intervals (at least
/// one), or none when the segment is a single point.
pub(crate) fn uniform(start: f64, end: f64, intervals: usize) -> Segment {
    Segment {
        start,
        end,
        grading: Grading::Uniform,
        intervals: if end > start { intervals.max(1) } else { 0 },
    }
}
