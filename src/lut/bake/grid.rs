//! The baker's starting grid as lists of segments, and how the error
//! search refines them.

use crate::lut::{BakeSpec, Kind, Resolution};
use crate::sweep::{share_intervals, uniform, Grading, Prepared, Segment};

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
