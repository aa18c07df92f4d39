//! The nodes of a grid as lists of segments, and how the error search
//! refines them.

use super::sweep::Prepared;
use crate::lut::axis::{segment_nodes, share_intervals, Grading, Segment};
use crate::lut::{BakeSpec, Kind, Resolution};

/// The nodes of one axis and the segment each interval belongs to.
#[derive(Clone, Debug)]
pub(super) struct AxisGrid {
    pub(super) segments: Vec<Segment>,
    pub(super) nodes: Vec<f64>,
    pub(super) segment_of_interval: Vec<usize>,
}

impl AxisGrid {
    pub(super) fn new(segments: &[Segment]) -> AxisGrid {
        let segment_of_interval = segments
            .iter()
            .enumerate()
            .flat_map(|(k, s)| std::iter::repeat_n(k, s.intervals))
            .collect();
        AxisGrid {
            segments: segments.to_vec(),
            nodes: segment_nodes(segments),
            segment_of_interval,
        }
    }
}

impl AxisGrid {
    /// An axis with exactly these nodes (increasing), each interval its own
    /// segment: evenly spaced runs are still recognised by the sweep, which
    /// compares the intervals' steps.
    pub(super) fn from_nodes(nodes: &[f64]) -> AxisGrid {
        let segments: Vec<Segment> = match nodes {
            [only] => vec![uniform(*only, *only, 0)],
            _ => nodes
                .windows(2)
                .map(|w| Segment {
                    start: w[0],
                    end: w[1],
                    grading: Grading::Uniform,
                    intervals: 1,
                })
                .collect(),
        };
        AxisGrid {
            segment_of_interval: (0..nodes.len().saturating_sub(1)).collect(),
            segments,
            nodes: nodes.to_vec(),
        }
    }
}

/// Node positions of one grid: thickness, cos θ, wavelength (a single
/// unused node for the rgb kind).
#[derive(Clone)]
pub(super) struct Grid {
    pub(super) axes: [AxisGrid; 3],
    pub(super) spectral: bool,
}

impl Grid {
    /// The rgb grid of these thickness and cos θ nodes.
    pub(super) fn rgb_of_nodes(thickness_nm: &[f64], cos_theta: &[f64]) -> Grid {
        Grid {
            axes: [
                AxisGrid::from_nodes(thickness_nm),
                AxisGrid::from_nodes(cos_theta),
                AxisGrid::from_nodes(&[0.0]),
            ],
            spectral: false,
        }
    }

    pub(super) fn new(axes: &[Vec<Segment>; 3], kind: Kind) -> Grid {
        Grid {
            axes: [
                AxisGrid::new(&axes[0]),
                AxisGrid::new(&axes[1]),
                AxisGrid::new(&axes[2]),
            ],
            spectral: kind == Kind::Spectral,
        }
    }

    pub(super) fn total(&self) -> usize {
        self.axes.iter().map(|a| a.nodes.len()).product()
    }

    pub(super) fn nodes(&self) -> [&[f64]; 3] {
        self.axes.each_ref().map(|a| &a.nodes[..])
    }
}

pub(super) fn doubled(segments: &[Segment]) -> Vec<Segment> {
    segments
        .iter()
        .map(|s| Segment {
            intervals: 2 * s.intervals,
            ..*s
        })
        .collect()
}

/// A segment with `intervals` intervals in place of its own. A uniform one
/// is also halved, so that refinement concentrates where the error is (a
/// film near zero thickness at grazing incidence); a graded one keeps its
/// grading.
pub(super) fn refine(seg: &Segment, intervals: usize) -> Vec<Segment> {
    if seg.grading == Grading::Uniform {
        let mid = 0.5 * (seg.start + seg.end);
        let half = intervals.div_ceil(2);
        vec![uniform(seg.start, mid, half), uniform(mid, seg.end, half)]
    } else {
        vec![Segment { intervals, ..*seg }]
    }
}

pub(super) fn uniform(start: f64, end: f64, intervals: usize) -> Segment {
    Segment {
        start,
        end,
        grading: Grading::Uniform,
        intervals: if end > start { intervals.max(1) } else { 0 },
    }
}

/// `count` equal uniform segments of `per` intervals each over a range.
pub(super) fn split_uniform(start: f64, end: f64, count: usize, per: usize) -> Vec<Segment> {
    if end <= start {
        return vec![uniform(start, start, 0)];
    }
    (0..count)
        .map(|k| {
            let a = start + (end - start) * k as f64 / count as f64;
            let b = if k + 1 == count {
                end
            } else {
                start + (end - start) * (k + 1) as f64 / count as f64
            };
            uniform(a, b, per)
        })
        .collect()
}

/// The starting grid. A fixed `--resolution` is one uniform segment per
/// axis (graded around a critical angle). For an error target the axes
/// start coarse and split into segments that refine independently:
/// thickness in pieces of about 50 nm (the response of a film is hardest
/// near zero thickness at grazing incidence, where it changes on a scale
/// proportional to cos θ), cos θ in quarters, wavelength as one piece.
pub(super) fn initial_axes(spec: &BakeSpec, prep: &Prepared) -> [Vec<Segment>; 3] {
    let (t0, t1) = spec.thickness_nm;
    let (c0, c1) = spec.cos_theta;
    let (w0, w1) = match spec.kind {
        Kind::Rgb => (0.0, 0.0),
        Kind::Spectral => spec.wavelength_nm,
    };
    let critical = prep
        .critical_cos
        .filter(|&cc| cc > c0 + 1e-6 && cc < c1 - 1e-6);
    let graded = |c_int: usize| {
        let cc = critical.unwrap_or(c0);
        let mut segments = vec![
            Segment {
                start: c0,
                end: cc,
                grading: Grading::TowardEnd,
                intervals: 0,
            },
            Segment {
                start: cc,
                end: c1,
                grading: Grading::TowardStart,
                intervals: 0,
            },
        ];
        share_intervals(&mut segments, c_int.max(2));
        segments
    };
    match spec.resolution {
        Resolution::Nodes {
            thickness,
            angle,
            wavelength,
        } => [
            vec![uniform(t0, t1, thickness - 1)],
            match critical {
                Some(_) if angle >= 3 => graded(angle - 1),
                _ => vec![uniform(c0, c1, angle - 1)],
            },
            vec![uniform(w0, w1, wavelength.saturating_sub(1))],
        ],
        Resolution::MaxError(_) => {
            let pieces = (((t1 - t0) / 50.0).round() as usize).clamp(1, 32);
            [
                split_uniform(t0, t1, pieces, 4),
                match critical {
                    Some(_) => graded(16),
                    None => split_uniform(c0, c1, 4, 4),
                },
                vec![uniform(w0, w1, ((w1 - w0) / 20.0).ceil() as usize)],
            ]
        }
    }
}
