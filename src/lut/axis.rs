//! Table axes: how the baker places nodes, and the O(1) lookup the sampler
//! uses for any increasing node list read from a file.

use serde::{Deserialize, Serialize};

/// One axis as written in the header: the node positions are the truth, a
/// reader interpolates linearly in the axis value between them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Axis {
    pub name: String,
    pub unit: String,
    pub nodes: Vec<f64>,
}

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
fn graded(u: f64) -> f64 {
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

/// O(1) location of a value among increasing f32 nodes: a uniform bucket
/// table gives a starting node, from which a short forward scan finishes
/// (one step on a uniform axis; a few inside a graded cluster).
#[derive(Clone, Debug)]
pub(crate) struct Locator {
    nodes: Vec<f32>,
    inv_width: Vec<f32>,
    first: f32,
    last: f32,
    bucket_scale: f32,
    buckets: Vec<u32>,
}

impl Locator {
    /// `nodes` must be non-empty and strictly increasing (checked by the
    /// loader before this is built).
    pub fn new(nodes_f64: &[f64]) -> Locator {
        let nodes: Vec<f32> = nodes_f64.iter().map(|&x| x as f32).collect();
        let n = nodes.len();
        let first = nodes[0];
        let last = nodes[n - 1];
        let inv_width = nodes
            .windows(2)
            .map(|w| 1.0 / (w[1] - w[0]))
            .chain(std::iter::once(0.0))
            .collect();
        let count = if n < 2 { 1 } else { (8 * (n - 1)).min(1 << 16) };
        let bucket_scale = if n < 2 {
            0.0
        } else {
            count as f32 / (last - first)
        };
        let mut buckets = Vec::with_capacity(count);
        let mut i = 0usize;
        for b in 0..count {
            let lo = first + b as f32 / bucket_scale.max(f32::MIN_POSITIVE);
            while i + 2 < n && nodes[i + 1] <= lo {
                i += 1;
            }
            // One node back: rounding in `lo` must never start past the value.
            buckets.push(i.saturating_sub(1) as u32);
        }
        Locator {
            nodes,
            inv_width,
            first,
            last,
            bucket_scale,
            buckets,
        }
    }

    /// The interval index i (node i to i+1; 0 on a one-node axis) and the
    /// fraction within it, with the value clamped to the axis (NaN → first).
    #[inline]
    pub fn locate(&self, x: f32) -> (usize, f32) {
        let n = self.nodes.len();
        let x = if x >= self.first {
            if x <= self.last {
                x
            } else {
                self.last
            }
        } else {
            self.first
        };
        let b = (((x - self.first) * self.bucket_scale) as usize).min(self.buckets.len() - 1);
        let mut i = self.buckets[b] as usize;
        while i + 2 < n && self.nodes[i + 1] <= x {
            i += 1;
        }
        let f = (x - self.nodes[i]) * self.inv_width[i];
        (i, f.clamp(0.0, 1.0))
    }

    pub fn len(&self) -> usize {
        self.nodes.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn graded_nodes_join_and_locate() {
        let mut segs = [
            Segment {
                start: 0.0,
                end: 0.7,
                grading: Grading::TowardEnd,
                intervals: 0,
            },
            Segment {
                start: 0.7,
                end: 1.0,
                grading: Grading::TowardStart,
                intervals: 0,
            },
        ];
        share_intervals(&mut segs, 40);
        assert_eq!(segs[0].intervals + segs[1].intervals, 40);
        let nodes = segment_nodes(&segs);
        assert_eq!(nodes.len(), 41);
        assert!(nodes.windows(2).all(|w| w[1] > w[0]));
        assert!(nodes.contains(&0.7));
        assert!((graded(1.0) - 1.0).abs() < 1e-15);
        let loc = Locator::new(&nodes);
        for k in 0..=10_000 {
            let x = k as f32 / 10_000.0;
            let (i, f) = loc.locate(x);
            let (a, b) = (nodes[i] as f32, nodes[i + 1] as f32);
            assert!(x >= a && x <= b, "{x} not in [{a}, {b}]");
            assert!((a + f * (b - a) - x).abs() < 1e-6);
        }
        assert_eq!(loc.locate(-1.0), (0, 0.0));
        assert_eq!(loc.locate(f32::NAN), (0, 0.0));
        assert_eq!(loc.locate(2.0), (39, 1.0));
        assert_eq!(Locator::new(&[5.0]).locate(3.0), (0, 0.0));
    }
}
