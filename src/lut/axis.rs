//! Table axes as the header writes them, and the O(1) lookup the sampler
//! uses for any increasing node list read from a file (the baker places
//! nodes by [`crate::sweep::axis`]).

use serde::{Deserialize, Serialize};

/// One axis as written in the header: the node positions are the truth, a
/// reader interpolates linearly in the axis value between them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Axis {
    /// The quantity along the axis: `thickness_nm`, `cos_theta` or
    /// `wavelength_nm` (the header's axis-name constants).
    pub name: String,
    /// The unit of the node values: `nm` for thickness and wavelength, `1`
    /// for cos θ (dimensionless).
    pub unit: String,
    /// Node positions in `unit`, strictly increasing; node i is column,
    /// row or block i of the image.
    pub nodes: Vec<f64>,
}

/// O(1) location of a value among increasing f32 nodes. An evenly spaced
/// axis is one multiplication away. Otherwise a uniform bucket table gives,
/// for each bucket, the first and last interval any value in it can fall
/// in; a value is scanned forward only when those differ (one compare on a
/// near-uniform axis, a few inside a graded cluster).
#[derive(Clone, Debug)]
pub(crate) struct Locator {
    nodes: Vec<f32>,
    inv_width: Vec<f32>,
    first: f32,
    last: f32,
    /// 1 / spacing when the nodes are evenly spaced (to 1e-6 of a spacing),
    /// else 0.
    uniform_inv_step: f32,
    bucket_scale: f32,
    /// Per bucket: the lowest interval and how many more to consider.
    buckets: Vec<(u32, u32)>,
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
        let uniform_inv_step = if n < 2 {
            0.0
        } else {
            let (a, b) = (nodes_f64[0], nodes_f64[n - 1]);
            let step = (b - a) / (n - 1) as f64;
            let even = nodes_f64
                .iter()
                .enumerate()
                .all(|(k, &x)| (x - (a + step * k as f64)).abs() <= 1e-6 * step);
            if even {
                (1.0 / step) as f32
            } else {
                0.0
            }
        };
        let count = if n < 2 { 1 } else { (8 * (n - 1)).min(1 << 16) };
        let bucket_scale = if n < 2 {
            0.0
        } else {
            count as f32 / (last - first)
        };
        // The interval holding x, found by bisection (build time only).
        let interval = |x: f64| -> usize {
            let k = nodes_f64.partition_point(|&node| node <= x);
            k.saturating_sub(1).min(n.saturating_sub(2))
        };
        let (lo_x, width) = (f64::from(first), f64::from(last - first) / count as f64);
        let buckets = (0..count)
            .map(|b| {
                // A margin of a tenth of a bucket covers the f32 rounding of
                // the bucket index at lookup (under 0.01 bucket at 65536).
                let lo = interval(lo_x + width * (b as f64 - 0.1));
                let hi = interval(lo_x + width * (b as f64 + 1.1));
                (lo as u32, (hi - lo) as u32)
            })
            .collect();
        Locator {
            nodes,
            inv_width,
            first,
            last,
            uniform_inv_step,
            bucket_scale,
            buckets,
        }
    }

    /// The interval index i (node i to i+1; 0 on a one-node axis) and the
    /// fraction within it, with the value clamped to the axis (NaN → first).
    /// Branch-free on an even axis, with i32 conversions (x86-64 converts
    /// f32 to and from usize in several instructions): it runs at every
    /// film hit of a render, where its latency is on the shading's path.
    #[inline(always)]
    pub fn locate(&self, x: f32) -> (usize, f32) {
        // f32::max and min return the operand that is not NaN.
        let x = x.max(self.first).min(self.last);
        let last_interval = self.nodes.len().saturating_sub(2) as i32;
        if self.uniform_inv_step > 0.0 {
            let s = (x - self.first) * self.uniform_inv_step;
            // SAFETY: x is clamped to [first, last] (NaN too), so s is
            // finite, ≥ 0 and at most about n − 1 < 2³¹. `as` would add a
            // saturation this cannot need, at every film hit.
            let i = unsafe { s.to_int_unchecked::<i32>() }.min(last_interval);
            return (i as usize, (s - i as f32).clamp(0.0, 1.0));
        }
        if self.nodes.len() < 2 {
            return (0, 0.0);
        }
        // SAFETY: as above; at most the bucket count (≤ 65536).
        let b = unsafe { ((x - self.first) * self.bucket_scale).to_int_unchecked::<i32>() }
            .min(self.buckets.len() as i32 - 1);
        let (lo, span) = self.buckets[b as usize];
        let mut i = lo as usize;
        if span <= 1 {
            // Most buckets: no node or one inside, settled without a branch
            // (a mispredicted one costs more than the whole lookup).
            i = (i + usize::from(self.nodes[i + 1] <= x)).min(last_interval as usize);
        } else {
            // Inside a graded cluster.
            for _ in 0..span {
                if self.nodes[i + 1] > x {
                    break;
                }
                i += 1;
            }
        }
        let f = (x - self.nodes[i]) * self.inv_width[i];
        (i, f.clamp(0.0, 1.0))
    }

    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// `x` clamped to the axis (NaN → its first node), as [`Self::locate`]
    /// clamps it.
    #[inline(always)]
    pub fn clamp(&self, x: f32) -> f32 {
        x.max(self.first).min(self.last)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::axis::{graded, segment_nodes, share_intervals, Grading, Segment};

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

    /// Both lookup paths (even axis, bucket table) against bisection over
    /// values spread across and beyond the axis.
    #[test]
    fn locate_agrees_with_bisection() {
        let even: Vec<f64> = (0..=125).map(|k| 100.0 + 4.0 * k as f64).collect();
        let mut state = 7u64;
        let mut uneven = vec![0.0f64];
        while uneven.len() < 200 {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            // Gaps from 1e-6 to 1: a graded cluster and wide cells mixed.
            let gap = 10f64.powf(-6.0 * (state >> 40) as f64 / (1u64 << 24) as f64);
            uneven.push(uneven[uneven.len() - 1] + gap);
        }
        for nodes in [&even, &uneven] {
            let loc = Locator::new(nodes);
            let f32_nodes: Vec<f32> = nodes.iter().map(|&x| x as f32).collect();
            let (lo, hi) = (f32_nodes[0], f32_nodes[f32_nodes.len() - 1]);
            for k in 0..=20_000 {
                let x = lo - 1.0 + (hi - lo + 2.0) * k as f32 / 20_000.0;
                let (i, f) = loc.locate(x);
                let clamped = x.clamp(lo, hi);
                let want = f32_nodes
                    .partition_point(|&n| n <= clamped)
                    .saturating_sub(1)
                    .min(f32_nodes.len() - 2);
                let (a, b) = (f32_nodes[i], f32_nodes[i + 1]);
                // At a node either neighbouring interval is right.
                assert!(
                    i == want || (f == 0.0 && i == want + 1) || (f == 1.0 && i + 1 == want),
                    "x {x}: interval {i}, bisection {want}"
                );
                assert!((0.0..=1.0).contains(&f));
                assert!((a + f * (b - a) - clamped).abs() <= 1e-5 * (b - a).max(1e-3));
            }
        }
    }
}
