//! Choosing an atlas for an error target at the cost of a few bakes.
//!
//! For each side of the film:
//!
//! 1. **Skeleton.** The cos θ range is cut into pieces at a dense-side
//!    critical angle (a point, or for a dispersive ambient the band of
//!    angles it moves over); a free-standing film near zero thickness gets
//!    a polar corner chart; and the angle below which the film's fringes
//!    are narrower than the colour integration resolves (where the
//!    integrated colour itself varies by more than any grid follows, the
//!    *aliased* strip) is found from the layer's cavity: for the exact
//!    sampling, where even its finest integration
//!    ([`crate::color::refine`]) steps over them.
//! 2. **Probe.** Each piece is evaluated once on a coarse chart and its
//!    doubled grid. The interpolation error at every midpoint, measured at
//!    two spacings, gives the local spacing the target needs along u and v
//!    (the error falling as h^α, α from the two spacings).
//! 3. **Layout.** From those needs, the bands each piece is cut into, and
//!    each band's optical-thickness scale p₀ and cos θ crowding, are chosen
//!    in closed form to minimize the texels (a dynamic programme over the
//!    probe's rows).
//! 4. **Confirm.** Each chart is evaluated with its doubled grid and its
//!    midpoint errors checked (grown where short), then the whole atlas is
//!    measured against the solver at random points.
//!
//! Each step is a file: `skeleton.rs`, `probe.rs`, `layout.rs`,
//! `confirm.rs`, and `measure.rs` for the random points; [`build`] here
//! runs them in order.

use rand::{Rng, SeedableRng};
use rayon::prelude::*;

use super::chart::{Chart, Coords, CosAxis, LogAxis, Optical, Rect};
use super::eval::Film;
use super::{pack, Atlas, Image, MAX_CHARTS};
use crate::color::delta_e2000_rgb;
use crate::error::{Error, Result};
use crate::stats::{summarize, AtlasFigures};
use crate::sweep::Side;

mod confirm;
mod layout;
mod measure;
mod probe;
mod skeleton;

use confirm::*;
use layout::*;
use measure::meets;
pub use measure::{
    figures, measure, random_points, solve_points, SideExact, SideMeasurement,
    CRITICAL_BAND_POINTS, CRITICAL_BAND_SEED,
};
use probe::*;
pub(super) use skeleton::aliased_edge;
use skeleton::*;

/// What the atlas must meet, at every point of the domain a table can
/// follow (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Goal {
    /// The largest absolute error in any channel.
    pub max_abs: Option<f64>,
    /// The largest CIEDE2000 of the reflected or transmitted colour.
    pub max_de: Option<f64>,
    /// Texels stored as f16 (else f32).
    pub half: bool,
}

/// One side of the film to build charts for.
pub struct SideRequest<'a> {
    /// The film as seen from this side.
    pub film: &'a Film,
    /// Which side the light arrives from.
    pub side: Side,
    /// The cos θ range (in the medium the light arrives from).
    pub cos: (f64, f64),
    /// What this side's charts must meet.
    pub goal: Goal,
}

/// What [`build`] found for one side.
#[derive(Clone, Debug, PartialEq)]
pub struct SideReport {
    /// The side.
    pub side: Side,
    /// cos θ below which the integrated colour is aliased (see the module
    /// docs): the target is not sought there; 0 when nowhere.
    pub aliased_below: f64,
    /// The critical-angle band [lo, hi] (equal ends for a non-dispersive
    /// ambient), when the side has one inside its range.
    pub critical: Option<(f64, f64)>,
    /// The critical band [lo, hi] of a dispersive ambient when the target
    /// is not sought there (its layout for the target would take more than
    /// [`CRITICAL_BAND_TEXELS`]).
    pub unsought_band: Option<(f64, f64)>,
}

/// An atlas, its texels and what was found.
#[derive(Clone, Debug)]
pub struct Built {
    /// Where every chart is.
    pub atlas: Atlas,
    /// The film's channels per texel (R.r, R.g, R.b, T.r, T.g, T.b for a
    /// colour film: see [`Film::channels`]), rounded as stored.
    pub image: Image,
    /// Per side.
    pub sides: Vec<SideReport>,
    /// Per side: the atlas against the solver at random points.
    pub measured: Vec<SideMeasurement>,
}

/// Probe sizes: nodes along u and v of each piece's coarse chart.
const PROBE_U: usize = 129;
const PROBE_V: usize = 33;
/// The probe's optical-thickness scale and cos θ crowding.
const PROBE_P0_NM: f64 = 150.0;
const PROBE_OFFSET: f64 = 0.05;
/// Scales p₀ (nm; 0: uniform) and cos θ offsets (< 0: uniform) a band may take.
const P0_CHOICES: [f64; 6] = [0.0, 40.0, 80.0, 160.0, 320.0, 640.0];
const OFFSET_CHOICES: [f64; 6] = [0.005, 0.02, 0.05, 0.2, 1.0, -1.0];
/// Bands one piece may be cut into.
const MAX_BANDS_PER_PIECE: usize = 6;
/// The corner chart's radius in its polar coordinates.
const CORNER_RADIUS: f64 = 0.3;
/// Fringes narrower than this many wavelength steps of the integration
/// count as aliased: at one step the integrated colour of a free-standing
/// film still varies by 1e-3 over 0.3 nm of optical thickness near
/// grazing incidence, at two it follows a 1 nm grid.
const ALIASING_STEPS: f64 = 1.5;
/// Row intervals of a piece the target applies nowhere in (inside the
/// aliased strip), and the rows of any piece the probe found no error in.
const UNTARGETED_INTERVALS: f64 = 16.0;
/// Rounds of growing a chart that misses its target.
const MAX_GROWTH: usize = 6;
/// The most texels of the band of cos θ over which a dispersive ambient's
/// critical angle moves (light from a denser side). When the probe's layout
/// for the target would take more, the target is not sought there: the
/// layout is scaled down to this many texels and the band's measured error
/// is stated apart. Each sampled wavelength
/// has its own critical angle there, with a square-root branch in cos θ
/// and leaky resonances of the layer whose widths vanish at it, so the
/// integrated colour has features along thickness that a linear
/// interpolation misses by an error falling only as h^0.8, on curves that
/// move with the angle: the mirror-10 stack seen from its glass side asks
/// for about a million texels in a band 0.6° wide
/// (docs/limits.md#the-mirror-from-its-glass-side).
pub const CRITICAL_BAND_TEXELS: usize = 1 << 16;
/// A critical band narrower than this (in cos θ) is a single angle.
const CRITICAL_BAND_MIN_WIDTH: f64 = 1e-7;

/// A piece of a side's cos θ range and how its bands' nodes crowd.
#[derive(Clone, Copy, Debug)]
struct Piece {
    lo: f64,
    hi: f64,
    warp: PieceWarp,
    /// A dispersive critical band, where the target is sought only when
    /// its layout fits in [`CRITICAL_BAND_TEXELS`].
    capped: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum PieceWarp {
    /// Towards `lo` on a scale chosen per band (grazing incidence).
    Log,
    /// Square-root crowding towards this end (a critical angle).
    Sqrt(f64),
    /// Uniform (inside a critical band).
    Uniform,
}

impl Piece {
    fn axis(&self, lo: f64, hi: f64, offset: f64) -> CosAxis {
        match self.warp {
            PieceWarp::Log => CosAxis {
                lo,
                hi,
                anchor: self.lo,
                offset,
            },
            PieceWarp::Sqrt(anchor) => CosAxis {
                lo,
                hi,
                anchor,
                offset: 0.0,
            },
            PieceWarp::Uniform => CosAxis::uniform(lo, hi),
        }
    }
}

/// Everything fixed about one side before its charts are sized.
struct Skeleton<'a> {
    req: &'a SideRequest<'a>,
    thickness_nm: (f64, f64),
    pieces: Vec<Piece>,
    corner: Option<Chart>,
    aliased_below: f64,
    critical: Option<(f64, f64)>,
}

impl Skeleton<'_> {
    fn optical(&self) -> Optical {
        self.req.film.optical
    }

    /// How much of the target applies at (d, c): all of it inside the
    /// domain above the aliased strip and outside the corner chart, none
    /// elsewhere (the strip's nodes take the density of the nearest rows
    /// the target applies to: see [`fill_untargeted`]).
    fn weight(&self, d: f64, c: f64) -> f64 {
        let (d0, d1) = self.thickness_nm;
        let (c0, c1) = self.req.cos;
        let inside = d >= d0 - 1e-9
            && d <= d1 * (1.0 + 1e-12) + 1e-9
            && c >= c0
            && c <= c1
            && !self.corner.is_some_and(|k| k.in_corner(d, c));
        if inside && c >= self.aliased_below {
            1.0
        } else {
            0.0
        }
    }
}

/// The optical-thickness axis of a band over cos θ [lo, hi]: the domain's
/// thicknesses at those angles, or for a single thickness that thickness
/// itself (see [`Chart::point`]).
fn band_p(skeleton: &Skeleton, p0_nm: f64, lo: f64, hi: f64) -> LogAxis {
    let (d0, d1) = skeleton.thickness_nm;
    let optical = skeleton.optical();
    if d1 <= d0 {
        return LogAxis {
            p0_nm: 0.0,
            lo_nm: d0,
            hi_nm: d0,
        };
    }
    LogAxis {
        p0_nm,
        lo_nm: d0 * optical.s(lo),
        hi_nm: d1 * optical.s(hi),
    }
}

/// The error of one channel's value `got` against `exact`: absolute, and
/// relative to the exact value where that exceeds 1 in magnitude. Values
/// up to 1 (every passive film's R and T) are held to the target in
/// absolute terms; the larger values of a gain film are stored as f16, a
/// floating format whose rounding grows with the value, and are held to it
/// relative to their size.
pub fn scaled_error(got: f64, exact: f64) -> f64 {
    (got - exact).abs() / exact.abs().max(1.0)
}

/// The error of the midpoint of two nodes' values `a`, `b` against the
/// exact values there, as a fraction of what each target allows an axis
/// (`shares`: absolute ([`scaled_error`]), ΔE00; ΔE00 for six colour
/// channels only).
fn normalized_error(a: &[f64], b: &[f64], exact: &[f64], shares: (f64, f64)) -> f64 {
    let got = |k: usize| 0.5 * (a[k] + b[k]);
    let mut e = 0.0f64;
    if shares.0.is_finite() {
        let abs = (0..exact.len())
            .map(|k| scaled_error(got(k), exact[k]))
            .fold(0.0, f64::max);
        e = e.max(abs / shares.0);
    }
    if shares.1.is_finite() && exact.len() == 6 {
        let de = delta_e2000_rgb([got(0), got(1), got(2)], [exact[0], exact[1], exact[2]]).max(
            delta_e2000_rgb([got(3), got(4), got(5)], [exact[3], exact[4], exact[5]]),
        );
        e = e.max(if de.is_nan() {
            f64::INFINITY
        } else {
            de / shares.1
        });
    }
    e
}

impl Goal {
    /// What one axis's interpolation may add: half of each target, less
    /// what storage rounds a value by, in the terms of [`scaled_error`]
    /// (a floating format rounds a value above 1 by no more, relative to
    /// it, than it rounds 1).
    fn shares(&self) -> Result<(f64, f64)> {
        let rounding = if self.half {
            f16_half_ulp(1.0)
        } else {
            f32::EPSILON as f64
        };
        let abs = match self.max_abs {
            Some(t) if rounding >= 0.9 * t => {
                return Err(Error::invalid(
                    "max-error",
                    format!(
                        "{t} cannot be met with {} texels, which round values near 1 (and larger ones relative to their size) by up to {rounding:.2e}",
                        if self.half { "f16" } else { "f32" }
                    ),
                ))
            }
            Some(t) => 0.5 * (t - rounding),
            None => f64::INFINITY,
        };
        let de = self.max_de.map_or(f64::INFINITY, |t| 0.5 * t);
        Ok((abs, de))
    }

    fn store(&self, v: f64) -> f32 {
        if self.half {
            half::f16::from_f32(v as f32).to_f32()
        } else {
            v as f32
        }
    }
}

/// Half an f16 ulp at magnitude `v`.
fn f16_half_ulp(v: f64) -> f64 {
    if v < 6.2e-5 {
        return 2f64.powi(-25);
    }
    2f64.powf(v.log2().floor() - 11.0)
}

/// Builds the atlas of `sides` over `thickness_nm` that meets each side's
/// goal, its textures at most `max_side` texels a side. `progress` gets one
/// line per stage.
pub fn build(
    sides: &[SideRequest],
    thickness_nm: (f64, f64),
    max_side: usize,
    points: &[Vec<[f32; 2]>],
    progress: &dyn Fn(&str),
) -> Result<Built> {
    let mut reports = Vec::new();
    let mut skeletons = Vec::new();
    for req in sides {
        let skeleton = skeleton(req, thickness_nm, req.goal)?;
        progress(&describe(&skeleton));
        reports.push(SideReport {
            side: req.side,
            aliased_below: skeleton.aliased_below,
            critical: skeleton.critical,
            unsought_band: None,
        });
        skeletons.push(skeleton);
    }
    let mut charts: Vec<(Chart, Vec<f32>)> = Vec::new();
    let mut owner = Vec::new();
    for (k, skeleton) in skeletons.iter().enumerate() {
        let goal = skeleton.req.goal;
        for planned in layout(skeleton, goal, progress)? {
            charts.push(if planned.sought {
                confirm(skeleton, planned.chart, goal, max_side, progress)?
            } else {
                reports[k].unsought_band = skeleton.critical;
                evaluate_unsought(skeleton, planned.chart, goal, progress)?
            });
            owner.push(k);
        }
    }
    if charts.len() > MAX_CHARTS {
        return Err(Error::invalid(
            "atlas",
            format!(
                "{} charts needed, at most {MAX_CHARTS} fit the shader's parameters",
                charts.len()
            ),
        ));
    }
    let exact = solve_points(sides, &reports, points, thickness_nm)?;
    for round in 0.. {
        let channels = sides.first().map_or(6, |s| s.film.channels());
        let (atlas, image) = assemble(&charts, thickness_nm, max_side, channels)?;
        let measured = measure(&atlas, &image, sides, &reports, &exact);
        let missed = measured
            .iter()
            .zip(&skeletons)
            .find(|(m, s)| !meets(&m.resolved, s.req.goal));
        let Some((m, skeleton)) = missed else {
            return Ok(Built {
                atlas,
                image,
                sides: reports,
                measured,
            });
        };
        let [d, c] = m.resolved.worst_point;
        let k = atlas
            .chart_for(d, c, skeleton.req.side)
            .expect("the side has charts");
        if round >= MAX_GROWTH {
            return Err(unreachable_target(
                skeleton,
                &charts[k].0,
                skeleton.req.goal,
            ));
        }
        // A feature between the midpoints: grow the chart of the worst point.
        progress(&format!(
            "random points: {:.2e} at thickness {d:.2} nm, cos θ {c:.4}: growing {}",
            m.resolved.max_all(),
            chart_name(&charts[k].0)
        ));
        let mut grown = charts[k].0;
        grown.rect.width = grown.rect.width * 5 / 4 + 1;
        grown.rect.height = grown.rect.height * 5 / 4 + 1;
        let owner = &skeletons[owner[k]];
        charts[k] = confirm(owner, grown, owner.req.goal, max_side, progress)?;
    }
    unreachable!("the loop returns")
}

/// One line on what was found about a side before its charts are sized.
fn describe(skeleton: &Skeleton) -> String {
    format!(
        "side {}: {} piece(s) of cos θ{}{}{}",
        skeleton.req.side.index(),
        skeleton.pieces.len(),
        if skeleton.corner.is_some() {
            ", a corner chart"
        } else {
            ""
        },
        match skeleton.critical {
            Some((a, b)) => format!(", critical angle at cos θ {a:.4}–{b:.4}"),
            None => String::new(),
        },
        if skeleton.aliased_below > 0.0 {
            format!(
                ", fringes aliased below cos θ {:.4}",
                skeleton.aliased_below
            )
        } else {
            String::new()
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atlas::Optical;

    fn band(width: usize, height: usize) -> Chart {
        Chart {
            side: Side::Front,
            optical: Optical { a: 0.5, floor: 0.5 },
            coords: Coords::Band {
                p: LogAxis {
                    p0_nm: 0.0,
                    lo_nm: 0.0,
                    hi_nm: 100.0,
                },
                c: CosAxis::uniform(0.72, 0.74),
            },
            rect: Rect {
                x: 0,
                y: 0,
                width,
                height,
            },
        }
    }

    /// A critical band cuts the range where it lies inside it; a dispersive
    /// band reaching past an end of the range keeps its part inside; a
    /// single critical angle at an end, or a band outside, cuts nothing.
    #[test]
    fn the_critical_band_as_it_cuts_the_range() {
        let band = (0.7254, 0.7352);
        assert_eq!(within((0.0, 1.0), band), Some(band));
        assert_eq!(within((0.73, 1.0), band), Some((0.73, 0.7352)));
        assert_eq!(within((0.0, 0.73), band), Some((0.7254, 0.73)));
        assert_eq!(within((0.728, 0.73), band), Some((0.728, 0.73)));
        assert_eq!(within((0.8, 1.0), band), None);
        assert_eq!(within((0.5, 0.7254), band), None);
        assert_eq!(within((0.73, 1.0), (0.73, 0.73)), None);
        assert_eq!(within((0.0, 1.0), (0.73, 0.73)), Some((0.73, 0.73)));
    }

    /// Over the budget, every chart shrinks by one factor on both axes to
    /// about the budget, keeping two nodes on an axis that had them and a
    /// single-thickness chart's one column; within it, nothing changes.
    #[test]
    fn fit_budget_scales_every_chart_alike() {
        let mut charts = vec![band(2000, 400), band(600, 100), band(1, 50), band(3, 3)];
        fit_budget(&mut charts, 1 << 16);
        let total = texels(&charts);
        assert!(total <= (1 << 16) + 100 && total > 60_000, "{total}");
        let scale = charts[0].rect.width as f64 / 2000.0;
        assert!((charts[0].rect.height as f64 / 400.0 - scale).abs() < 0.01);
        assert!((charts[1].rect.width as f64 / 600.0 - scale).abs() < 0.01);
        assert_eq!(charts[2].rect.width, 1);
        assert_eq!((charts[3].rect.width, charts[3].rect.height), (2, 2));
        let before: Vec<Rect> = charts.iter().map(|c| c.rect).collect();
        fit_budget(&mut charts, 1 << 17);
        assert_eq!(before, charts.iter().map(|c| c.rect).collect::<Vec<_>>());
    }
}
