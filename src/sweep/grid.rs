//! The nodes a sweep evaluates: per axis (thickness, cos θ, wavelength) a
//! list of segments and the nodes they place.

use super::axis::{segment_nodes, uniform, Grading, Segment};
use super::Kind;

/// The nodes of one axis and the segment each interval belongs to.
#[derive(Clone, Debug)]
pub(crate) struct AxisGrid {
    pub(crate) segments: Vec<Segment>,
    pub(crate) nodes: Vec<f64>,
    pub(crate) segment_of_interval: Vec<usize>,
}

impl AxisGrid {
    pub(crate) fn new(segments: &[Segment]) -> AxisGrid {
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
    pub(crate) fn from_nodes(nodes: &[f64]) -> AxisGrid {
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
pub(crate) struct Grid {
    pub(crate) axes: [AxisGrid; 3],
    pub(crate) spectral: bool,
}

impl Grid {
    /// The rgb grid of these thickness and cos θ nodes.
    pub(crate) fn rgb_of_nodes(thickness_nm: &[f64], cos_theta: &[f64]) -> Grid {
        Grid {
            axes: [
                AxisGrid::from_nodes(thickness_nm),
                AxisGrid::from_nodes(cos_theta),
                AxisGrid::from_nodes(&[0.0]),
            ],
            spectral: false,
        }
    }

    pub(crate) fn new(axes: &[Vec<Segment>; 3], kind: Kind) -> Grid {
        Grid {
            axes: [
                AxisGrid::new(&axes[0]),
                AxisGrid::new(&axes[1]),
                AxisGrid::new(&axes[2]),
            ],
            spectral: kind == Kind::Spectral,
        }
    }

    pub(crate) fn total(&self) -> usize {
        self.axes.iter().map(|a| a.nodes.len()).product()
    }

    pub(crate) fn nodes(&self) -> [&[f64]; 3] {
        self.axes.each_ref().map(|a| &a.nodes[..])
    }
}
