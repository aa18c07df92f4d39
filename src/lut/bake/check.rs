//! The bake check: the stored coarse table interpolated at every node of the
//! grid with each interval halved, against the exact values there.

use super::store::stored;
use crate::sweep::Grid;

pub(super) struct Check {
    /// Per channel, over every fine point.
    pub(super) max_channel: Vec<f64>,
    pub(super) max_all: f64,
    /// Per axis and segment: the largest error (over channels) at fine
    /// points that are midpoints along that axis inside that segment.
    pub(super) segment_max: [Vec<f64>; 3],
    pub(super) points: usize,
    /// Fine indices of the worst point.
    pub(super) worst_at: [usize; 3],
}

/// Compares exact values at every fine node with the multilinear
/// interpolation of the stored coarse table `data` (the fine values at even
/// indices, rounded as stored: see [`even_subgrid`]).
pub(super) fn measure(
    coarse: &Grid,
    fine: &Grid,
    values: &[f64],
    data: &[f32],
    channels: usize,
) -> Check {
    let dims = fine.axes.each_ref().map(|a| a.nodes.len());
    let coarse_dims = coarse.axes.each_ref().map(|a| a.nodes.len());
    // Interpolation weight of the right-hand coarse neighbour at each odd
    // fine index (1/2 on uniform segments, not on graded ones).
    let weights: Vec<Vec<f64>> = fine
        .axes
        .iter()
        .map(|a| {
            (0..a.nodes.len())
                .map(|i| {
                    if i % 2 == 1 {
                        (a.nodes[i] - a.nodes[i - 1]) / (a.nodes[i + 1] - a.nodes[i - 1])
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    let strides = [channels, dims[0] * channels, dims[0] * dims[1] * channels];
    let coarse_strides = [
        channels,
        coarse_dims[0] * channels,
        coarse_dims[0] * coarse_dims[1] * channels,
    ];
    let mut check = Check {
        max_channel: vec![0.0; channels],
        max_all: 0.0,
        segment_max: coarse.axes.clone().map(|a| vec![0.0; a.segments.len()]),
        points: 0,
        worst_at: [0; 3],
    };
    let mut corners = [(0usize, 1.0f64); 8];
    for w in 0..dims[2] {
        for c in 0..dims[1] {
            for t in 0..dims[0] {
                let at_idx = [t, c, w];
                let at = t * strides[0] + c * strides[1] + w * strides[2];
                // Corners of the coarse cell: each odd axis contributes its
                // two neighbours, the coarse nodes i / 2 and i / 2 + 1.
                corners[0] = ((0..3).map(|a| at_idx[a] / 2 * coarse_strides[a]).sum(), 1.0);
                let mut count = 1;
                for a in 0..3 {
                    let i = at_idx[a];
                    if i % 2 == 1 {
                        let wt = weights[a][i];
                        for k in 0..count {
                            let (base, cw) = corners[k];
                            corners[k] = (base, cw * (1.0 - wt));
                            corners[count + k] = (base + coarse_strides[a], cw * wt);
                        }
                        count *= 2;
                    }
                }
                let mut worst = 0.0f64;
                for ch in 0..channels {
                    let interp: f64 = corners[..count]
                        .iter()
                        .map(|&(base, wt)| wt * f64::from(data[base + ch]))
                        .sum();
                    let err = (interp - values[at + ch]).abs();
                    check.max_channel[ch] = check.max_channel[ch].max(err);
                    worst = worst.max(err);
                }
                if worst > check.max_all {
                    check.max_all = worst;
                    check.worst_at = at_idx;
                }
                // Edge midpoints measure one axis's spacing alone; cell
                // centres mix them and only break ties (see the caller).
                let mut odd = (0..3).filter(|&a| at_idx[a] % 2 == 1);
                if let (Some(a), None) = (odd.next(), odd.next()) {
                    let k = coarse.axes[a].segment_of_interval[(at_idx[a] - 1) / 2];
                    let m = &mut check.segment_max[a][k];
                    *m = m.max(worst);
                }
                check.points += 1;
            }
        }
    }
    check
}

/// The coarse table: fine values at even indices, rounded as stored.
pub(super) fn even_subgrid(fine: &Grid, values: &[f64], channels: usize, half: bool) -> Vec<f32> {
    let dims = fine.axes.each_ref().map(|a| a.nodes.len());
    let mut out = Vec::with_capacity(values.len() / 4);
    for w in (0..dims[2]).step_by(2) {
        for c in (0..dims[1]).step_by(2) {
            for t in (0..dims[0]).step_by(2) {
                let at = ((w * dims[1] + c) * dims[0] + t) * channels;
                out.extend(values[at..at + channels].iter().map(|&v| stored(v, half)));
            }
        }
    }
    out
}
