//! The μ = v·h nodes at which a film's smooth colour is computed, and the
//! cubic interpolation between them that F_eff integrates.
//!
//! F(μ) is smooth on (0, 1] but for two places. Towards grazing incidence
//! (μ → 0) it changes on the scale of μ itself (R → 1; a thin film's
//! resonances sharpen), so the first segment, [0, 1/16], has nodes graded
//! geometrically towards 0. At a dense-side critical angle μ_c (a lossless
//! substrate optically thinner than the ambient) it has a square-root
//! branch point, and is an analytic function of √|μ − μ_c| on each side,
//! so μ_c ends two segments whose nodes crowd quadratically towards it
//! (|μ − μ_c| ∝ s² there).
//! Each segment has nodes uniform in its own parameter s ∈ [0, 1], and F
//! is interpolated by cubic Lagrange polynomials in s over four nodes of
//! one segment.
//!
//! The node at μ = 0 is evaluated at [`MU_FLOOR`] instead: irid's value at
//! exactly grazing incidence (R = 1, T = 0) is not the limit of R for a
//! film between like media (a layer of zero thickness there reflects
//! nothing at any μ > 0).

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};

use crate::optics::Stack;
use crate::sweep::{critical_cos, Kind};

/// Fewest intervals a segment gets (a cubic needs four nodes).
const MIN_SEGMENT_INTERVALS: usize = 3;

/// A kink closer than this to 0 or 1 is not given a segment boundary: the
/// segment beside it would be thinner than the grid's spacing.
const KINK_MARGIN: f64 = 0.02;

/// The upper end of the grazing segment, when no kink comes first.
const GRAZING_END: f64 = 1.0 / 16.0;

/// The grazing segment's nodes are spaced in proportion to μ + ε·GRAZING_END.
const GRAZING_EPSILON: f64 = 1.0 / 64.0;

/// Where the node μ = 0 is evaluated: the limit of F from above.
pub const MU_FLOOR: f64 = 1e-9;

/// How a segment's parameter s ∈ [0, 1] maps to μ ∈ [lo, hi].
#[derive(Clone, Copy, Debug, PartialEq)]
enum Map {
    /// μ = lo + (hi − lo) s.
    Linear,
    /// μ = lo + (hi − lo) ε ((1 + 1/ε)^s − 1), ε = [`GRAZING_EPSILON`]:
    /// spacing in proportion to μ − lo + ε (hi − lo).
    Geometric,
    /// The kink is `hi`: μ = lo + (hi − lo) sin(πs/2), so √(hi − μ) ∝
    /// sin(π(1 − s)/4), analytic in s and 0 at s = 1 like 1 − s.
    ToKink,
    /// The kink is `lo`: μ = lo + (hi − lo)(1 − cos(πs/2)), so √(μ − lo) ∝
    /// sin(πs/4). (A parabola would do too, but spaces the far end twice
    /// as coarsely as a uniform grid; this, π/2 times.)
    FromKink,
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct Segment {
    lo: f64,
    hi: f64,
    map: Map,
    /// Index of the segment's first node in the grid.
    first: usize,
    /// Intervals (nodes − 1), uniform in s.
    pub(crate) intervals: usize,
}

impl Segment {
    /// μ at parameter s.
    #[inline]
    pub(crate) fn mu(&self, s: f64) -> f64 {
        let span = self.hi - self.lo;
        match self.map {
            Map::Linear => self.lo + span * s,
            Map::Geometric => self.lo + span * GRAZING_EPSILON * (geometric_base().powf(s) - 1.0),
            Map::ToKink => {
                let h = (FRAC_PI_4 * (1.0 - s)).sin();
                self.hi - span * 2.0 * h * h
            }
            Map::FromKink => {
                let h = (FRAC_PI_4 * s).sin();
                self.lo + span * 2.0 * h * h
            }
        }
    }

    /// dμ/ds at parameter s.
    #[inline]
    pub(crate) fn dmu_ds(&self, s: f64) -> f64 {
        let span = self.hi - self.lo;
        match self.map {
            Map::Linear => span,
            Map::Geometric => {
                let base = geometric_base();
                span * GRAZING_EPSILON * base.ln() * base.powf(s)
            }
            Map::ToKink => span * FRAC_PI_2 * (FRAC_PI_2 * s).cos(),
            Map::FromKink => span * FRAC_PI_2 * (FRAC_PI_2 * s).sin(),
        }
    }

    /// The parameter of μ, clamped to [0, 1].
    #[inline]
    pub(crate) fn s(&self, mu: f64) -> f64 {
        let span = self.hi - self.lo;
        let x = ((mu - self.lo) / span).clamp(0.0, 1.0);
        match self.map {
            Map::Linear => x,
            Map::Geometric => (x / GRAZING_EPSILON).ln_1p() / geometric_base().ln(),
            Map::ToKink => 1.0 - (0.5 * (1.0 - x)).sqrt().asin() / FRAC_PI_4,
            Map::FromKink => (0.5 * x).sqrt().asin() / FRAC_PI_4,
        }
    }

    /// Whether the segment starts at a kink (F is then smooth in s, not in μ,
    /// at its first interval).
    #[inline]
    pub(crate) fn kink_at_start(&self) -> bool {
        self.map == Map::FromKink
    }

    /// Whether the segment ends at a kink.
    #[inline]
    pub(crate) fn kink_at_end(&self) -> bool {
        self.map == Map::ToKink
    }

    /// The μ range of interval `k`.
    #[inline]
    pub(crate) fn interval_mu(&self, k: usize) -> (f64, f64) {
        let n = self.intervals as f64;
        (self.mu(k as f64 / n), self.mu((k + 1) as f64 / n))
    }

    /// The cubic Lagrange interpolation at parameter s in interval `k`:
    /// the grid index of the stencil's first node and the four weights.
    /// The stencil is the interval's two nodes and one more on each side,
    /// shifted inwards at the segment's ends.
    #[inline]
    pub(crate) fn stencil(&self, k: usize, s: f64) -> (usize, [f64; 4]) {
        let j0 = k.saturating_sub(1).min(self.intervals - 3);
        let u = s * self.intervals as f64 - j0 as f64;
        let (u1, u2, u3) = (u - 1.0, u - 2.0, u - 3.0);
        (
            self.first + j0,
            [
                -u1 * u2 * u3 / 6.0,
                u * u2 * u3 / 2.0,
                -u * u1 * u3 / 2.0,
                u * u1 * u2 / 6.0,
            ],
        )
    }
}

/// 1 + 1/ε of the geometric map.
#[inline]
fn geometric_base() -> f64 {
    1.0 + 1.0 / GRAZING_EPSILON
}

/// The nodes μ ∈ [0, 1] a film's smooth colour is computed at, in
/// segments that meet at a dense-side critical angle when there is one.
#[derive(Clone, Debug)]
pub struct MuGrid {
    nodes: Vec<f64>,
    segments: Vec<Segment>,
    kink: Option<f64>,
}

impl MuGrid {
    /// About `intervals` intervals over [0, 1] (at least three per
    /// segment), with a segment boundary at `kink` (a critical cos θ in
    /// (0, 1)) if given.
    pub fn new(intervals: usize, kink: Option<f64>) -> MuGrid {
        let kink = kink.filter(|&k| k > KINK_MARGIN && k < 1.0 - KINK_MARGIN);
        let grazing_end = kink.map_or(GRAZING_END, |k| GRAZING_END.min(0.5 * k));
        // A quarter of the nodes for the grazing segment, the rest by length.
        let rest = intervals - intervals / 4;
        let share = |span: f64| {
            ((rest as f64 * span / (1.0 - grazing_end)).round() as usize).max(MIN_SEGMENT_INTERVALS)
        };
        let mut shapes = vec![(
            0.0,
            grazing_end,
            Map::Geometric,
            (intervals / 4).max(MIN_SEGMENT_INTERVALS),
        )];
        match kink {
            None => shapes.push((grazing_end, 1.0, Map::Linear, share(1.0 - grazing_end))),
            Some(k) => {
                shapes.push((grazing_end, k, Map::ToKink, share(k - grazing_end)));
                shapes.push((k, 1.0, Map::FromKink, share(1.0 - k)));
            }
        }
        let mut nodes: Vec<f64> = Vec::new();
        let mut segments = Vec::new();
        for (lo, hi, map, n) in shapes {
            // Consecutive segments share their boundary node, exactly.
            let first = nodes.len().saturating_sub(1);
            let segment = Segment {
                lo,
                hi,
                map,
                first,
                intervals: n,
            };
            if let Some(last) = nodes.last_mut() {
                *last = lo;
            }
            let skip = usize::from(!nodes.is_empty());
            nodes.extend((skip..=n).map(|i| segment.mu(i as f64 / n as f64)));
            segments.push(segment);
        }
        nodes[0] = MU_FLOOR;
        *nodes.last_mut().expect("at least one segment") = 1.0;
        MuGrid {
            nodes,
            segments,
            kink,
        }
    }

    /// The grid for `stack` seen from its ambient: a boundary at the
    /// substrate's critical cos θ at 550 nm when it has one (the baker's
    /// choice too; with a dispersive substrate the kink moves a little
    /// with the wavelength).
    pub fn for_stack(stack: &Stack, intervals: usize) -> MuGrid {
        MuGrid::new(intervals, critical_cos(stack, Kind::Rgb, (380.0, 780.0)))
    }

    /// The nodes, ascending from [`MU_FLOOR`] (standing for 0) to 1.
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// The segment boundary at a critical cos θ, if there is one.
    pub fn kink(&self) -> Option<f64> {
        self.kink
    }

    pub(crate) fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// The interpolation weights of the grid's values at μ ∈ [0, 1]: the
    /// first node's index and four weights (they sum to 1).
    pub fn interpolation(&self, mu: f64) -> (usize, [f64; 4]) {
        let mu = mu.clamp(0.0, 1.0);
        let seg = self
            .segments
            .iter()
            .find(|s| mu <= s.hi)
            .unwrap_or(&self.segments[self.segments.len() - 1]);
        let s = seg.s(mu);
        let k = ((s * seg.intervals as f64) as usize).min(seg.intervals - 1);
        seg.stencil(k, s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nodes_cover_the_range_with_the_kink_a_node() {
        let g = MuGrid::new(128, None);
        assert_eq!(g.nodes().len(), 129);
        assert_eq!((g.nodes()[0], g.nodes()[128]), (MU_FLOOR, 1.0));
        assert!(g.nodes().windows(2).all(|w| w[0] < w[1]));
        assert!(g.nodes().contains(&GRAZING_END));
        // Spacing grows with μ in the grazing segment.
        assert!(g.nodes()[2] - g.nodes()[1] < 0.03 * (g.nodes()[33] - g.nodes()[32]));
        let k = (1.0f64 - (1.0 / 1.5f64).powi(2)).sqrt();
        let g = MuGrid::new(128, Some(k));
        assert!(g.nodes().windows(2).all(|w| w[0] < w[1]));
        assert!(g.nodes().contains(&k));
        assert_eq!(g.kink(), Some(k));
        assert_eq!(MuGrid::new(128, Some(0.01)).kink(), None);
    }

    /// Cubic interpolation is exact on cubics in s, on either side of the
    /// kink, and reproduces √|μ − μ_c| (which a grid in μ could not).
    #[test]
    fn interpolation_is_exact_where_it_should_be() {
        let k = 0.6;
        let g = MuGrid::new(128, Some(k));
        let at = |f: &dyn Fn(f64) -> f64, mu: f64| {
            let (first, w) = g.interpolation(mu);
            (0..4).map(|i| w[i] * f(g.nodes()[first + i])).sum::<f64>()
        };
        let kinked = |mu: f64| (mu - k).abs().sqrt() * (1.0 + 0.3 * mu);
        let (mut worst, mut grazing) = (0.0f64, 0.0f64);
        for i in 0..=1000 {
            let mu = i as f64 / 1000.0;
            let (_, w) = g.interpolation(mu);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-13);
            let e = (at(&kinked, mu) - kinked(mu)).abs();
            if mu < GRAZING_END {
                grazing = grazing.max(e);
            } else {
                worst = worst.max(e);
            }
        }
        // Smooth in s on every segment: to the interpolation's h⁴.
        println!("√|μ − μ_c| interpolated: {worst:.1e} beside the kink, {grazing:.1e} at grazing");
        assert!(worst < 1e-7 && grazing < 1e-6, "{worst} {grazing}");
        let seg = g.segments()[2];
        let cubic = |mu: f64| {
            let s = seg.s(mu);
            1.0 - 2.0 * s + 0.5 * s * s * s
        };
        for i in 0..=100 {
            let mu = k + (1.0 - k) * i as f64 / 100.0;
            assert!((at(&cubic, mu) - cubic(mu)).abs() < 1e-12, "{mu}");
        }
    }
}
