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

use rand::{Rng, SeedableRng};
use rayon::prelude::*;

use super::chart::{Chart, Coords, CosAxis, LogAxis, Optical, Rect};
use super::eval::Film;
use super::{pack, Atlas, Image, MAX_CHARTS};
use crate::color::delta_e2000_rgb;
use crate::error::{Error, Result};
use crate::sweep::Side;

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

/// The pieces, corner and aliased strip of one side (see the module docs).
fn skeleton<'a>(
    req: &'a SideRequest<'a>,
    thickness_nm: (f64, f64),
    goal: Goal,
) -> Result<Skeleton<'a>> {
    let (c0, c1) = req.cos;
    let critical = critical_band(req.film)?.and_then(|(a, b)| within((c0, c1), (a, b)));
    let pieces = match critical {
        Some((a, b)) => {
            let mut p = Vec::new();
            if a > c0 + EDGE {
                p.push(Piece {
                    lo: c0,
                    hi: a,
                    warp: PieceWarp::Sqrt(a),
                    capped: false,
                });
            }
            if b > a + CRITICAL_BAND_MIN_WIDTH {
                p.push(Piece {
                    lo: a,
                    hi: b,
                    warp: PieceWarp::Uniform,
                    capped: true,
                });
            }
            if b < c1 - EDGE {
                p.push(Piece {
                    lo: b,
                    hi: c1,
                    warp: PieceWarp::Sqrt(b),
                    capped: false,
                });
            }
            p
        }
        None => vec![Piece {
            lo: c0,
            hi: c1,
            warp: if c1 > c0 {
                PieceWarp::Log
            } else {
                PieceWarp::Uniform
            },
            capped: false,
        }],
    };
    let corner = corner_chart(req, thickness_nm, goal)?;
    let aliased_below = aliasing_floor(req, thickness_nm, goal)?;
    Ok(Skeleton {
        req,
        thickness_nm,
        pieces,
        corner,
        aliased_below,
        critical,
    })
}

/// How far inside the cos θ range a critical angle must be to cut it.
const EDGE: f64 = 1e-6;

/// The critical band `(a, b)` as it cuts the cos θ `range`: whole when it is
/// inside, else a dispersive band's part inside the range (a range that
/// starts or ends inside the band still has the band's charts, not a search
/// through it); `None` when it does not cut the range.
fn within(range: (f64, f64), (a, b): (f64, f64)) -> Option<(f64, f64)> {
    let (c0, c1) = range;
    if a > c0 + EDGE && b < c1 - EDGE {
        return Some((a, b));
    }
    let (lo, hi) = (a.max(c0), b.min(c1));
    (b > a + CRITICAL_BAND_MIN_WIDTH && hi > lo + CRITICAL_BAND_MIN_WIDTH).then_some((lo, hi))
}

/// The range of cos θ over which a lossless substrate optically thinner
/// than the ambient has its critical angle, over the integration's
/// wavelengths.
fn critical_band(film: &Film) -> Result<Option<(f64, f64)>> {
    let stack = film.stack();
    let mut band: Option<(f64, f64)> = None;
    for &w in film.wavelengths_nm() {
        let (n0, ns) = (stack.ambient.index_at(w)?, stack.substrate.index_at(w)?);
        if ns.im != 0.0 || ns.re >= n0.re {
            continue;
        }
        let c = (1.0 - (ns.re / n0.re).powi(2)).sqrt();
        band = Some(band.map_or((c, c), |(a, b)| (a.min(c), b.max(c))));
    }
    Ok(band)
}

/// A polar corner chart when the film's surroundings reflect nothing at
/// grazing incidence near its least thickness: there R jumps from its
/// value at zero thickness to 1 across a ratio of thickness to cos θ.
fn corner_chart(req: &SideRequest, thickness_nm: (f64, f64), goal: Goal) -> Result<Option<Chart>> {
    let film = req.film;
    let optical = film.optical;
    let (d0, d1) = thickness_nm;
    let c = 1e-3;
    if req.cos.0 > 0.05 || d1 <= d0 {
        return Ok(None);
    }
    // The response along the grazing row, from the least thickness out.
    let ratios: Vec<f64> = (0..=48).map(|k| 1e-2 * 1.25f64.powi(k)).collect();
    let points: Vec<(f64, f64)> = std::iter::once((d0, c))
        .chain(ratios.iter().map(|r| (d0 + r * c / optical.s(c), c)))
        .collect();
    let ch = film.channels();
    let values = film.points_flat(&points)?;
    let lum = |k: usize| film.brightness(&values[k * ch..(k + 1) * ch]);
    let (start, end) = (lum(0), lum(points.len() - 1));
    // Bands cannot follow a jump at the corner itself: the cell that holds
    // it misses by about half the jump, so any jump past twice the target
    // takes the chart (at a loose target too: 2e-2 on a soap film's jump of
    // 1 took none, and its bands grew without end).
    let tolerance = goal.max_abs.unwrap_or(1e-3).max(1e-3);
    if (end - start).abs() < 2.0 * tolerance || d0 > 0.0 {
        return Ok(None);
    }
    // The ratio p / cos θ at which the jump is half done is one unit of ρ.
    let half = 0.5 * (start + end);
    let k = (1..points.len())
        .position(|k| (lum(k) - start).abs() >= (half - start).abs())
        .unwrap_or(ratios.len() - 1);
    let scale_nm = ratios[k].max(1e-3);
    Ok(Some(Chart {
        side: req.side,
        optical,
        coords: Coords::Corner {
            scale_nm,
            radius: CORNER_RADIUS,
        },
        rect: Rect {
            x: 0,
            y: 0,
            width: 2,
            height: 2,
        },
    }))
}

/// The cos θ below which the film's colour integration is aliased, at
/// its largest thickness or a few below (0 when nowhere, or the colour is
/// not integrated over many wavelengths). The exact sampling integrates
/// more finely where fringes are narrow, and is aliased only where its
/// finest integration is ([`crate::color::refine::Refinement::resolves`]);
/// another sampling is taken as aliased where some wavelength has a fringe
/// narrower than [`ALIASING_STEPS`] of its steps that changes R by enough
/// to move the colour by the target through that one wavelength's weight.
fn aliasing_floor(req: &SideRequest, thickness_nm: (f64, f64), goal: Goal) -> Result<f64> {
    let film = req.film;
    if let Some(floor) = film.spectral_aliased_below() {
        return Ok(floor);
    }
    let w = film.wavelengths_nm();
    if w.len() < 4 {
        return Ok(0.0);
    }
    let step = (w[w.len() - 1] - w[0]) / (w.len() - 1) as f64;
    let visible = goal.max_abs.unwrap_or(1e-3) / film.largest_weight().max(1e-12);
    let (c0, c1) = req.cos;
    let layer = &film.stack().layers[film.layer() - 1].material;
    // Every wavelength within a few steps, so that a narrow stop band of a
    // mirror is not stepped over.
    let stride = ((4.0 / step).floor() as usize).max(1);
    // The thicker the layer, the narrower its fringes in wavelength, unless
    // it absorbs them away: a few thicknesses down from the largest.
    let thicknesses: Vec<f64> = (0..5)
        .map(|k| thickness_nm.1 / f64::from(1 << k))
        .filter(|&d| d >= thickness_nm.0 && d > 0.0)
        .collect();
    let aliased = |c: f64| -> Result<bool> {
        // The exact colour integrates more finely where fringes are narrow:
        // it is aliased only where even its finest integration is.
        if let Some(refinement) = film.refinement() {
            return Ok(thicknesses.iter().any(|&d| !refinement.resolves(d, c)));
        }
        for &lambda in w.iter().step_by(stride) {
            let n = layer.index_at(lambda)?.re.max(1e-6);
            for &d in &thicknesses {
                let (y, visibility) = film.fringe(lambda, c, d)?;
                let p = d * film.optical.s(c);
                if p <= 0.0 || y.is_nan() || y <= 0.0 || visibility < visible {
                    continue;
                }
                // Fringe width in round-trip phase 2|1 − |y||/√|y| (a gain
                // layer's round trip can exceed 1), in wavelength through
                // dδ/dλ = 4π n p / λ².
                let width = 2.0 * (1.0 - y).abs() / y.sqrt() * lambda * lambda
                    / (4.0 * std::f64::consts::PI * n * p);
                if width < ALIASING_STEPS * step {
                    return Ok(true);
                }
            }
        }
        Ok(false)
    };
    aliased_edge((c0, c1), &aliased)
}

/// Per probe row: how dense each band over it must be (see [`cut_bands`]).
struct RowNeeds {
    /// cos θ of each probe node row.
    c: Vec<f64>,
    /// Per p₀ choice and node row: max over the row of 1 / (needed p
    /// spacing · dU/dp), U = ln(1 + p/p₀) (or p): a band over the row needs
    /// (U(hi) − U(lo)) times this many intervals.
    u: Vec<Vec<f64>>,
    /// Per offset choice and row interval: max of 1 / (needed cos θ spacing
    /// · dW/dc), likewise.
    v: Vec<Vec<f64>>,
}

/// The largest normalized midpoint errors at one spacing and at twice it.
type Pair = (f64, f64);

/// A chart's midpoint errors along u and v, and its exact node values
/// ([`Film::channels`] per node, row-major).
type Checked = ((Pair, Pair), Vec<f64>);

fn merge(a: Pair, b: Pair) -> Pair {
    (a.0.max(b.0), a.1.max(b.1))
}

/// The error's exponent from the largest errors at one spacing and at twice
/// it, within [1, 2] (2 for a smooth function at fine enough spacing).
fn exponent((e1, e2): Pair) -> f64 {
    if e1 > 0.0 && e2 > e1 {
        (e2 / e1).log2().clamp(1.0, 2.0)
    } else {
        2.0
    }
}

/// Nodes an axis of `n` nodes needs so that its normalized midpoint error
/// `e` (measured with `e` at twice the spacing too) falls to 1.
fn needed_nodes(n: usize, (e1, e2): Pair) -> usize {
    if e1.is_nan() || e1 <= 0.0 || n < 2 {
        return n.max(2);
    }
    nodes_for((n - 1) as f64 * e1.powf(1.0 / exponent((e1, e2))))
}

/// Nodes for an axis that needs `x` intervals (5 % to spare).
fn nodes_for(x: f64) -> usize {
    if !x.is_finite() || x > 1e9 {
        return 1 << 30;
    }
    ((x * 1.05).ceil() as usize + 1).max(2)
}

/// Normalized midpoint errors of one axis at node k of a line of fine
/// values `at(k)`: between its neighbours, and between the ones two away.
fn midpoint_pair<'a>(at: &dyn Fn(usize) -> &'a [f64], k: usize, n: usize, shares: Pair) -> Pair {
    let err = |a: usize, b: usize| normalized_error(at(a), at(b), at(k), shares);
    let e1 = err(k - 1, k + 1);
    let e2 = if k >= 2 && k + 2 < n {
        err(k - 2, k + 2)
    } else {
        0.0
    };
    (e1, e2)
}

/// Evaluates the probe of one piece and what it asks of its bands.
fn probe(skeleton: &Skeleton, piece: &Piece, shares: Pair) -> Result<RowNeeds> {
    let optical = skeleton.optical();
    let (probe_p, probe_c) = (
        band_p(skeleton, PROBE_P0_NM, piece.lo, piece.hi),
        piece.axis(piece.lo, piece.hi, PROBE_OFFSET),
    );
    let chart = Chart {
        side: skeleton.req.side,
        optical,
        coords: Coords::Band {
            p: probe_p,
            c: probe_c,
        },
        rect: Rect {
            x: 0,
            y: 0,
            width: PROBE_U,
            height: PROBE_V,
        },
    };
    let (nu, nv) = (2 * PROBE_U - 1, 2 * PROBE_V - 1);
    let fine = skeleton.req.film.chart_flat(&chart, nu, nv)?;
    let ch = skeleton.req.film.channels();
    let node = |k: usize| &fine[k * ch..(k + 1) * ch];
    let mut sized = chart;
    sized.rect.width = nu;
    sized.rect.height = nv;
    let (dx, dy) = (1.0 / (PROBE_U - 1) as f64, 1.0 / (PROBE_V - 1) as f64);
    let rows: Vec<(Vec<f64>, Vec<f64>)> = (0..nv)
        .into_par_iter()
        .map(|jj| {
            let c = sized.node(0, jj).1;
            let mut u = vec![0.0; P0_CHOICES.len()];
            let mut v = vec![0.0; OFFSET_CHOICES.len()];
            let odd_row = jj % 2 == 1;
            let mut errors = Vec::new();
            let mut pair = (0.0, 0.0);
            for i in (0..nu).filter(|i| (i % 2 == 1) != odd_row) {
                let d = sized.node(i, jj).0;
                let weight = skeleton.weight(d, c);
                if weight == 0.0 || (!odd_row && (i == 0 || i + 1 == nu)) {
                    continue;
                }
                let e = if odd_row {
                    midpoint_pair(&|k| node(k * nu + i), jj, nv, shares)
                } else {
                    midpoint_pair(&|k| node(jj * nu + k), i, nu, shares)
                };
                let e = (weight * e.0, weight * e.1);
                pair = merge(pair, e);
                errors.push((d * optical.s(c), e.0));
            }
            let alpha = exponent(pair);
            for (p, e) in errors.into_iter().filter(|e| e.1 > 0.0) {
                if odd_row {
                    let h = dy * e.powf(-1.0 / alpha) / probe_c.density(c);
                    for (k, &o) in OFFSET_CHOICES.iter().enumerate() {
                        let slope = piece.axis(piece.lo, piece.hi, o).slope(c);
                        v[k] = f64::max(v[k], 1.0 / (h * slope));
                    }
                } else {
                    let h = dx * e.powf(-1.0 / alpha) / probe_p.density(p);
                    for (k, &p0) in P0_CHOICES.iter().enumerate() {
                        let slope = if p0 > 0.0 { 1.0 / (p0 + p) } else { 1.0 };
                        u[k] = f64::max(u[k], 1.0 / (h * slope));
                    }
                }
            }
            (u, v)
        })
        .collect();
    let needs = RowNeeds {
        c: (0..PROBE_V).map(|j| chart.node(0, j).1).collect(),
        u: (0..P0_CHOICES.len())
            .map(|k| (0..PROBE_V).map(|j| rows[2 * j].0[k]).collect())
            .collect(),
        v: (0..OFFSET_CHOICES.len())
            .map(|k| (0..PROBE_V - 1).map(|j| rows[2 * j + 1].1[k]).collect())
            .collect(),
    };
    Ok(needs)
}

/// A chart the layout chose, and whether the target is sought on it.
struct Planned {
    chart: Chart,
    sought: bool,
}

/// The bands of every piece of a side (and its corner), sized from the
/// probes.
fn layout(skeleton: &Skeleton, goal: Goal, progress: &dyn Fn(&str)) -> Result<Vec<Planned>> {
    let shares = goal.shares()?;
    let mut charts = Vec::new();
    if let Some(corner) = skeleton.corner {
        charts.push(Planned {
            chart: size_corner(skeleton, corner, shares)?,
            sought: true,
        });
    }
    let mut needs = Vec::new();
    for piece in &skeleton.pieces {
        needs.push(if piece.hi > piece.lo {
            Some(probe(skeleton, piece, shares)?)
        } else {
            None
        });
    }
    fill_untargeted(&skeleton.pieces, &mut needs);
    for (piece, needs) in skeleton.pieces.iter().zip(&needs) {
        let mut sought = true;
        let Some(needs) = needs else {
            let chart = flat_band(skeleton, piece);
            charts.push(Planned { chart, sought });
            continue;
        };
        let mut bands = cut_bands(skeleton, piece, needs);
        let predicted = texels(&bands);
        if piece.capped && predicted > CRITICAL_BAND_TEXELS {
            fit_budget(&mut bands, CRITICAL_BAND_TEXELS);
            sought = false;
        }
        progress(&format!(
            "side {} cos θ {:.4}–{:.4}: {} band(s), {predicted} texels predicted{}",
            skeleton.req.side.index(),
            piece.lo,
            piece.hi,
            bands.len(),
            if sought {
                String::new()
            } else {
                format!(
                    "; the target is not sought in this critical band, which takes {}",
                    texels(&bands)
                )
            }
        ));
        charts.extend(bands.into_iter().map(|chart| Planned { chart, sought }));
    }
    Ok(charts)
}

fn texels(charts: &[Chart]) -> usize {
    charts.iter().map(|b| b.rect.width * b.rect.height).sum()
}

/// Scales every chart down by one factor along both axes so that together
/// they take at most about `budget` texels (at least two nodes per axis
/// that had them).
fn fit_budget(charts: &mut [Chart], budget: usize) {
    let total = texels(charts);
    if total <= budget {
        return;
    }
    let scale = (budget as f64 / total as f64).sqrt();
    let shrink = |n: usize| ((n as f64 * scale).round() as usize).max(n.min(2));
    for chart in charts {
        chart.rect.width = shrink(chart.rect.width);
        chart.rect.height = shrink(chart.rect.height);
    }
}

/// Gives the probe rows the target does not apply to (the aliased strip)
/// the needs of the nearest rows it does apply to, so that they hold a
/// smooth continuation of the response at the resolution around them:
/// along u the nearest targeted row's (in the piece, else in the nearest
/// piece above, else below), along v the nearest targeted interval's in the
/// piece, else [`UNTARGETED_INTERVALS`] over the piece.
fn fill_untargeted(pieces: &[Piece], needs: &mut [Option<RowNeeds>]) {
    let targeted = |list: &[f64]| list.iter().any(|&x| x > 0.0);
    let row_u = |n: &RowNeeds, j: usize| -> Vec<f64> { n.u.iter().map(|l| l[j]).collect() };
    // The u needs of the lowest (else highest) targeted row of each piece.
    let lowest: Vec<Option<Vec<f64>>> = needs
        .iter()
        .map(|n| {
            let n = n.as_ref()?;
            (0..n.c.len())
                .find(|&j| targeted(&row_u(n, j)))
                .map(|j| row_u(n, j))
        })
        .collect();
    for k in 0..needs.len() {
        let fallback = (k + 1..lowest.len())
            .chain((0..k).rev())
            .find_map(|m| lowest[m].clone());
        let Some(n) = needs[k].as_mut() else { continue };
        let rows = n.c.len();
        let nearest = |pred: &dyn Fn(usize) -> bool, j: usize| {
            (0..rows)
                .filter(|&m| pred(m))
                .min_by_key(|&m| m.abs_diff(j))
        };
        let has_u: Vec<bool> = (0..rows).map(|j| targeted(&row_u(n, j))).collect();
        for j in (0..rows).filter(|&j| !has_u[j]) {
            let source = nearest(&|m| has_u[m], j)
                .map(|m| row_u(n, m))
                .or(fallback.clone());
            for (list, v) in n.u.iter_mut().zip(source.unwrap_or_default()) {
                list[j] = v;
            }
        }
        let intervals = rows - 1;
        let has_v: Vec<bool> = (0..intervals)
            .map(|j| n.v.iter().any(|l| l[j] > 0.0))
            .collect();
        for j in (0..intervals).filter(|&j| !has_v[j]) {
            match (0..intervals)
                .filter(|&m| has_v[m])
                .min_by_key(|&m| m.abs_diff(j))
            {
                Some(m) => n.v.iter_mut().for_each(|l| l[j] = l[m]),
                None => {
                    for (o, list) in n.v.iter_mut().enumerate() {
                        let span = pieces[k]
                            .axis(pieces[k].lo, pieces[k].hi, OFFSET_CHOICES[o])
                            .span();
                        list[j] = UNTARGETED_INTERVALS / span.max(1e-300);
                    }
                }
            }
        }
    }
}

/// A two-row band for a single cos θ.
fn flat_band(skeleton: &Skeleton, piece: &Piece) -> Chart {
    Chart {
        side: skeleton.req.side,
        optical: skeleton.optical(),
        coords: Coords::Band {
            p: band_p(skeleton, PROBE_P0_NM, piece.lo, piece.hi),
            c: CosAxis::uniform(piece.lo, piece.hi),
        },
        rect: Rect {
            x: 0,
            y: 0,
            width: PROBE_U,
            height: 2,
        },
    }
}

/// The cheapest band of `piece` over probe rows a..=b: its texels and chart,
/// with the p₀ and crowding that need the fewest.
fn best_band(
    skeleton: &Skeleton,
    piece: &Piece,
    needs: &RowNeeds,
    a: usize,
    b: usize,
) -> (usize, Chart) {
    let optical = skeleton.optical();
    let (lo, hi) = (needs.c[a], needs.c[b]);
    let mut best: Option<(usize, Chart)> = None;
    for (k, &p0) in P0_CHOICES.iter().enumerate() {
        let p = band_p(skeleton, p0, lo, hi);
        let need_u = needs.u[k][a..=b].iter().fold(0.0f64, |m, &x| m.max(x));
        let nu = if p.hi_nm > p.lo_nm {
            nodes_for(p.span() * need_u)
        } else {
            1
        };
        let choices = if piece.warp == PieceWarp::Log {
            OFFSET_CHOICES.len()
        } else {
            1
        };
        for (o, &offset) in OFFSET_CHOICES.iter().enumerate().take(choices) {
            let c = piece.axis(lo, hi, offset);
            let need_v = needs.v[o][a..b].iter().fold(0.0f64, |m, &x| m.max(x));
            let nv = nodes_for(c.span() * need_v);
            let texels = nu.saturating_mul(nv).saturating_add(nu);
            if best.as_ref().is_none_or(|(t, _)| texels < *t) {
                let rect = Rect {
                    x: 0,
                    y: 0,
                    width: nu,
                    height: nv,
                };
                let side = skeleton.req.side;
                let coords = Coords::Band { p, c };
                best = Some((
                    texels,
                    Chart {
                        side,
                        optical,
                        coords,
                        rect,
                    },
                ));
            }
        }
    }
    best.expect("a band choice")
}

/// The bands one piece is cut into: a dynamic programme over the probe's
/// node rows as band edges.
fn cut_bands(skeleton: &Skeleton, piece: &Piece, needs: &RowNeeds) -> Vec<Chart> {
    let rows = needs.c.len();
    let cost: Vec<Vec<usize>> = (0..rows)
        .map(|a| {
            (0..rows)
                .map(|b| {
                    if b > a {
                        best_band(skeleton, piece, needs, a, b).0
                    } else {
                        usize::MAX
                    }
                })
                .collect()
        })
        .collect();
    // best[k][b]: the cheapest cut of rows 0..=b into k + 1 bands, and the
    // start of its last band.
    let mut best = vec![vec![(usize::MAX, 0usize); rows]; MAX_BANDS_PER_PIECE];
    for b in 1..rows {
        best[0][b] = (cost[0][b], 0);
    }
    for k in 1..MAX_BANDS_PER_PIECE {
        for b in 1..rows {
            for a in 1..b {
                let total = best[k - 1][a].0.saturating_add(cost[a][b]);
                if total < best[k][b].0 {
                    best[k][b] = (total, a);
                }
            }
        }
    }
    let last = rows - 1;
    let mut k = (0..MAX_BANDS_PER_PIECE)
        .min_by_key(|&k| best[k][last].0)
        .unwrap_or(0);
    let mut cuts = vec![last];
    let mut b = last;
    while k > 0 {
        b = best[k][b].1;
        cuts.push(b);
        k -= 1;
    }
    cuts.push(0);
    cuts.reverse();
    cuts.windows(2)
        .map(|w| best_band(skeleton, piece, needs, w[0], w[1]).1)
        .collect()
}

/// The corner chart's size, from a probe of it.
fn size_corner(skeleton: &Skeleton, corner: Chart, shares: Pair) -> Result<Chart> {
    let (n_phi, n_rho) = (33, 9);
    let (errors, _) = chart_check(skeleton, &corner, n_phi, n_rho, shares)?;
    let mut chart = corner;
    chart.rect.width = needed_nodes(n_phi, errors.0);
    chart.rect.height = needed_nodes(n_rho, errors.1);
    Ok(chart)
}

/// The largest normalized midpoint errors of `chart` at `w` × `h` nodes,
/// along u and along v (each at the nodes' spacing and at twice it), over
/// the points it serves that the target applies to; and the exact values
/// at its nodes, row-major.
fn chart_check(
    skeleton: &Skeleton,
    chart: &Chart,
    w: usize,
    h: usize,
    shares: Pair,
) -> Result<Checked> {
    let (nu, nv) = (2 * w - 1, 2 * h - 1);
    let fine = skeleton.req.film.chart_flat(chart, nu, nv)?;
    let ch = skeleton.req.film.channels();
    let node = |k: usize| &fine[k * ch..(k + 1) * ch];
    let mut sized = *chart;
    sized.rect.width = nu;
    sized.rect.height = nv;
    let corner = matches!(chart.coords, Coords::Corner { .. });
    let (d0, d1) = skeleton.thickness_nm;
    let (c0, c1) = skeleton.req.cos;
    let weight = |d: f64, c: f64| {
        if !corner {
            skeleton.weight(d, c)
        } else if chart.in_corner(d, c) && d >= d0 && d <= d1 && c >= c0 && c <= c1 {
            1.0
        } else {
            0.0
        }
    };
    let per_row: Vec<(Pair, Pair)> = (0..nv)
        .into_par_iter()
        .map(|j| {
            let (mut eu, mut ev) = ((0.0, 0.0), (0.0, 0.0));
            for i in 0..nu {
                let (odd_i, odd_j) = (i % 2 == 1, j % 2 == 1);
                if odd_i == odd_j {
                    continue;
                }
                let (d, c) = sized.node(i, j);
                let w = weight(d, c);
                if w == 0.0 {
                    continue;
                }
                let scaled = |e: Pair| (w * e.0, w * e.1);
                if odd_i {
                    eu = merge(
                        eu,
                        scaled(midpoint_pair(&|k| node(j * nu + k), i, nu, shares)),
                    );
                } else {
                    ev = merge(
                        ev,
                        scaled(midpoint_pair(&|k| node(k * nu + i), j, nv, shares)),
                    );
                }
            }
            (eu, ev)
        })
        .collect();
    let errors = per_row.iter().fold(((0.0, 0.0), (0.0, 0.0)), |a, b| {
        (merge(a.0, b.0), merge(a.1, b.1))
    });
    let coarse = (0..h)
        .flat_map(|j| (0..w).map(move |i| 2 * j * nu + 2 * i))
        .flat_map(|k| node(k).iter().copied())
        .collect();
    Ok((errors, coarse))
}

/// Refuses a chart check whose memory would exceed the budget (see
/// [`crate::limits`]): `channels` exact values (f64) at each node of the
/// doubled grid, and the chart's own nodes kept from them.
fn within_budget(goal: Goal, w: usize, h: usize, channels: usize) -> Result<()> {
    let (coarse, fine) = (w as u64 * h as u64, (2 * w as u64 - 1) * (2 * h as u64 - 1));
    let estimate = crate::limits::product(&[fine.saturating_add(coarse)], channels as u64 * 8);
    let target = match (goal.max_abs, goal.max_de) {
        (Some(e), Some(de)) => format!("max-error {e:e}, max-de {de}"),
        (Some(e), None) => format!("max-error {e:e}"),
        (None, Some(de)) => format!("max-de {de}"),
        (None, None) => "atlas".to_string(),
    };
    crate::limits::check_allocation(
        &format!("{target}: a grid of {coarse} nodes checked at {fine}"),
        estimate,
    )
}

/// Evaluates a chart with its doubled grid and grows it until its midpoint
/// errors meet the target; returns it with its values as stored
/// ([`Film::channels`] per node, row-major).
fn confirm(
    skeleton: &Skeleton,
    chart: Chart,
    goal: Goal,
    max_side: usize,
    progress: &dyn Fn(&str),
) -> Result<(Chart, Vec<f32>)> {
    let mut chart = chart;
    // A chart that met the target and was then tried smaller.
    let mut met: Option<(Chart, Vec<f32>)> = None;
    for _ in 0..MAX_GROWTH {
        let (w, h) = (chart.rect.width, chart.rect.height);
        if w > max_side || h > max_side || w.saturating_mul(h) > MAX_CHART_TEXELS {
            return Err(unreachable_target(skeleton, &chart, goal));
        }
        let ch = skeleton.req.film.channels();
        within_budget(goal, w, h, ch)?;
        let ((eu, ev), values) = chart_check(skeleton, &chart, w, h, goal.shares()?)?;
        finite(&values, ch)?;
        progress(&format!(
            "  {} {w}×{h}: midpoint error {:.2} (u) {:.2} (v) of what is allowed",
            chart_name(&chart),
            eu.0,
            ev.0
        ));
        if eu.0 <= 1.0 && ev.0 <= 1.0 {
            let stored = values.iter().map(|&x| goal.store(x)).collect();
            // The probe predicts from coarse spacings, where the error has
            // not reached its h² law: an axis far inside the target is
            // tried once at the size its measured error asks for.
            let smaller = (
                if eu.0 < SHRINK_BELOW {
                    needed_nodes(w, eu)
                } else {
                    w
                },
                if ev.0 < SHRINK_BELOW {
                    needed_nodes(h, ev)
                } else {
                    h
                },
            );
            if met.is_some() || smaller.0.max(2) * smaller.1.max(2) >= w * h {
                return Ok((chart, stored));
            }
            met = Some((chart, stored));
            chart.rect.width = smaller.0.max(2).min(w);
            chart.rect.height = smaller.1.max(2).min(h);
            continue;
        }
        if let Some(met) = met {
            // The smaller size misses: keep the one that met.
            return Ok(met);
        }
        if eu.0 > 1.0 {
            chart.rect.width = needed_nodes(w, eu).max(w + 1);
        }
        if ev.0 > 1.0 {
            chart.rect.height = needed_nodes(h, ev).max(h + 1);
        }
    }
    Err(unreachable_target(skeleton, &chart, goal))
}

/// Refuses values that are not all finite, naming the first node's.
fn finite(values: &[f64], channels: usize) -> Result<()> {
    match values.iter().position(|x| !x.is_finite()) {
        Some(k) => {
            let v = &values[k - k % channels..k - k % channels + channels];
            Err(Error::invalid(
                "film",
                format!("R or T is not finite: {v:?}"),
            ))
        }
        None => Ok(()),
    }
}

/// Evaluates a chart the target is not sought on at its planned size, its
/// values as stored.
fn evaluate_unsought(
    skeleton: &Skeleton,
    chart: Chart,
    goal: Goal,
    progress: &dyn Fn(&str),
) -> Result<(Chart, Vec<f32>)> {
    let (w, h) = (chart.rect.width, chart.rect.height);
    let film = skeleton.req.film;
    let values = film.chart_flat(&chart, w, h)?;
    finite(&values, film.channels())?;
    progress(&format!(
        "  {} {w}×{h}: target not sought",
        chart_name(&chart)
    ));
    Ok((chart, values.iter().map(|&x| goal.store(x)).collect()))
}

/// The most texels one chart may have.
const MAX_CHART_TEXELS: usize = 1 << 24;
/// A confirmed chart whose midpoint error along an axis is below this
/// fraction of what is allowed is tried smaller along it.
const SHRINK_BELOW: f64 = 0.3;

fn chart_name(chart: &Chart) -> String {
    match chart.coords {
        Coords::Band { c, .. } => format!(
            "side {} band cos θ {:.4}–{:.4}",
            chart.side.index(),
            c.lo,
            c.hi
        ),
        Coords::Corner { .. } => format!("side {} corner", chart.side.index()),
    }
}

/// The one-line error for a target no chart within the size limits meets,
/// naming the region.
fn unreachable_target(skeleton: &Skeleton, chart: &Chart, goal: Goal) -> Error {
    let what = match (goal.max_abs, goal.max_de) {
        (Some(a), Some(d)) => format!("max-error {a} and max-de {d}"),
        (Some(a), None) => format!("max-error {a}"),
        (None, Some(d)) => format!("max-de {d}"),
        (None, None) => "target".into(),
    };
    let region = match chart.coords {
        Coords::Band { c, .. } => format!(
            "cos θ {:.4}–{:.4} (θ {:.2}°–{:.2}°), thickness {}–{} nm",
            c.lo,
            c.hi,
            c.hi.acos().to_degrees(),
            c.lo.acos().to_degrees(),
            skeleton.thickness_nm.0,
            skeleton.thickness_nm.1
        ),
        Coords::Corner { scale_nm, radius } => format!(
            "the grazing corner (thickness below {:.1} nm, cos θ below {radius})",
            scale_nm * radius / skeleton.optical().s(0.0)
        ),
    };
    Error::invalid(
        what,
        format!(
            "not reached within the size limits ({}×{} texels needed, at most {MAX_CHART_TEXELS} a chart) on side {} at {region}",
            chart.rect.width, chart.rect.height, skeleton.req.side.index()
        ),
    )
}

/// Packs the charts into one image.
fn assemble(
    charts: &[(Chart, Vec<f32>)],
    thickness_nm: (f64, f64),
    max_side: usize,
    channels: usize,
) -> Result<(Atlas, Image)> {
    let sizes: Vec<(usize, usize)> = charts
        .iter()
        .map(|(c, _)| (c.rect.width, c.rect.height))
        .collect();
    let (at, width, height) = pack(&sizes, max_side).ok_or_else(|| {
        Error::invalid(
            "atlas",
            format!("its charts ({sizes:?} texels) do not fit in {max_side}×{max_side}"),
        )
    })?;
    let mut image = Image::new(width, height, channels);
    let mut placed = Vec::with_capacity(charts.len());
    for ((chart, values), (x, y)) in charts.iter().zip(at) {
        let mut chart = *chart;
        chart.rect.x = x;
        chart.rect.y = y;
        for j in 0..chart.rect.height {
            for i in 0..chart.rect.width {
                let k = (j * chart.rect.width + i) * channels;
                image
                    .texel_mut(x + i, y + j)
                    .copy_from_slice(&values[k..k + channels]);
            }
        }
        placed.push(chart);
    }
    let atlas = Atlas {
        width,
        height,
        thickness_nm,
        charts: placed,
    };
    Ok((atlas, image))
}

/// Error figures of an atlas at points against the solver. `*_abs` per
/// channel (R.r, R.g, R.b, T.r, T.g, T.b for a colour film; see
/// [`Film::channels`]); `*_de` per colour (R, T; zero for spectra).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Measurement {
    /// Points measured.
    pub points: usize,
    /// Largest error per channel: absolute, relative above 1
    /// ([`scaled_error`]).
    pub max_abs: Vec<f64>,
    /// 99th percentile per channel.
    pub p99_abs: Vec<f64>,
    /// Mean per channel.
    pub mean_abs: Vec<f64>,
    /// Largest CIEDE2000, reflected and transmitted.
    pub max_de: [f64; 2],
    /// Mean CIEDE2000.
    pub mean_de: [f64; 2],
    /// (thickness nm, cos θ) of the largest absolute error.
    pub worst_point: [f64; 2],
}

impl Measurement {
    /// The largest of `max_abs`.
    pub fn max_all(&self) -> f64 {
        self.max_abs.iter().fold(0.0, |a, &b| a.max(b))
    }

    /// Figures of (got, exact) colour pairs at `points`.
    pub fn of(points: &[[f32; 2]], got: &[[f64; 6]], exact: &[[f64; 6]]) -> Measurement {
        Measurement::of_flat(points, &got.concat(), &exact.concat(), 6, true)
    }

    /// Figures of (got, exact) at `points`, `channels` values per point
    /// (with CIEDE2000 when `colour`: six colour channels).
    pub fn of_flat(
        points: &[[f32; 2]],
        got: &[f64],
        exact: &[f64],
        channels: usize,
        colour: bool,
    ) -> Measurement {
        let n = points.len();
        if n == 0 {
            return Measurement {
                max_abs: vec![0.0; channels],
                p99_abs: vec![0.0; channels],
                mean_abs: vec![0.0; channels],
                ..Measurement::default()
            };
        }
        let errors: Vec<(Vec<f64>, [f64; 2])> = got
            .par_chunks_exact(channels)
            .zip(exact.par_chunks_exact(channels))
            .map(|(g, e)| {
                let abs = (0..channels).map(|k| scaled_error(g[k], e[k])).collect();
                let de = |o: usize| {
                    if !colour {
                        return 0.0;
                    }
                    let d = delta_e2000_rgb([g[o], g[o + 1], g[o + 2]], [e[o], e[o + 1], e[o + 2]]);
                    if d.is_nan() {
                        f64::INFINITY
                    } else {
                        d
                    }
                };
                (abs, [de(0), de(3)])
            })
            .collect();
        let mut m = Measurement {
            points: n,
            max_abs: vec![0.0; channels],
            p99_abs: vec![0.0; channels],
            mean_abs: vec![0.0; channels],
            ..Measurement::default()
        };
        for k in 0..channels {
            let mut e: Vec<f64> = errors.iter().map(|x| x.0[k]).collect();
            e.sort_by(f64::total_cmp);
            m.max_abs[k] = e[n - 1];
            m.p99_abs[k] = e[((n as f64 * 0.99).ceil() as usize).clamp(1, n) - 1];
            m.mean_abs[k] = e.iter().sum::<f64>() / n as f64;
        }
        for k in 0..2 {
            m.max_de[k] = errors.iter().map(|x| x.1[k]).fold(0.0, f64::max);
            m.mean_de[k] = errors.iter().map(|x| x.1[k]).sum::<f64>() / n as f64;
        }
        let worst = errors
            .iter()
            .map(|x| x.0.iter().fold(0.0f64, |a, &b| a.max(b)))
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(0, |(k, _)| k);
        m.worst_point = points[worst].map(f64::from);
        m
    }
}

/// What one side's random points say about an atlas: over the points the
/// target applies to, and over those in the aliased strip.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SideMeasurement {
    /// The side.
    pub side: Side,
    /// Every point of the side.
    pub all: Measurement,
    /// The points the target applies to: at or above the aliased strip's
    /// edge and outside a dispersive critical band.
    pub resolved: Measurement,
    /// The points in the aliased strip (none when there is no strip).
    pub aliased: Measurement,
    /// [`CRITICAL_BAND_POINTS`] points of its own in the dispersive
    /// critical band where the target is not sought
    /// ([`SideReport::unsought_band`]); none when there is no such band.
    pub critical: Measurement,
}

/// The solver's exact values at one side's measurement points (and at a
/// critical band's own points when the target is not sought there),
/// [`Film::channels`] per point: solved once, as the film does not change
/// between rounds of growing the atlas.
pub struct SideExact {
    points: Vec<[f32; 2]>,
    exact: Vec<f64>,
    band: Option<(Vec<[f32; 2]>, Vec<f64>)>,
}

/// Solves each side's `points`, and [`CRITICAL_BAND_POINTS`] of its own in
/// a band its report does not seek the target in (see [`measure`]).
pub fn solve_points(
    sides: &[SideRequest],
    reports: &[SideReport],
    points: &[Vec<[f32; 2]>],
    thickness_nm: (f64, f64),
) -> Result<Vec<SideExact>> {
    sides
        .iter()
        .zip(reports)
        .zip(points)
        .map(|((req, report), pts)| {
            let band = match report.unsought_band {
                None => None,
                Some(band) => {
                    let own =
                        random_points(thickness_nm, band, CRITICAL_BAND_POINTS, CRITICAL_BAND_SEED);
                    let exact = solve(req, &own)?;
                    Some((own, exact))
                }
            };
            Ok(SideExact {
                points: pts.clone(),
                exact: solve(req, pts)?,
                band,
            })
        })
        .collect()
}

/// Measures `image` read through `atlas` (bilinear, f32, as a GPU, from a
/// normalized texture coordinate) at each side's points against the
/// solver's values there (`exact`, from [`solve_points`]).
pub fn measure(
    atlas: &Atlas,
    image: &Image,
    sides: &[SideRequest],
    reports: &[SideReport],
    exact: &[SideExact],
) -> Vec<SideMeasurement> {
    let uniform = atlas.uniform_f32();
    sides
        .iter()
        .zip(reports)
        .zip(exact)
        .map(|((req, report), solved)| {
            let ch = req.film.channels();
            let colour = !req.film.is_spectral();
            let pts = &solved.points;
            let got = read(&uniform, image, req, pts);
            let pick = |idx: &[usize], v: &[f64]| -> Vec<f64> {
                idx.iter()
                    .flat_map(|&k| v[k * ch..(k + 1) * ch].iter().copied())
                    .collect()
            };
            let split = |keep: &dyn Fn(f32) -> bool| {
                let idx: Vec<usize> = (0..pts.len()).filter(|&k| keep(pts[k][1])).collect();
                let p: Vec<[f32; 2]> = idx.iter().map(|&k| pts[k]).collect();
                Measurement::of_flat(
                    &p,
                    &pick(&idx, &got),
                    &pick(&idx, &solved.exact),
                    ch,
                    colour,
                )
            };
            let band = report.unsought_band;
            let in_band =
                |c: f32| band.is_some_and(|(a, b)| f64::from(c) >= a && f64::from(c) <= b);
            let floor = report.aliased_below as f32;
            // The band is narrow (a hundredth of cos θ): its figures take
            // points of their own.
            let critical = match &solved.band {
                None => split(&|_| false),
                Some((own, exact)) => {
                    let got = read(&uniform, image, req, own);
                    Measurement::of_flat(own, &got, exact, ch, colour)
                }
            };
            SideMeasurement {
                side: req.side,
                all: Measurement::of_flat(pts, &got, &solved.exact, ch, colour),
                resolved: split(&|c| c >= floor && !in_band(c)),
                aliased: split(&|c| c < floor),
                critical,
            }
        })
        .collect()
}

/// Points of a dispersive critical band's own measurement, uniform over
/// the band.
pub const CRITICAL_BAND_POINTS: usize = 4000;
/// The seed of their PCG64 stream.
pub const CRITICAL_BAND_SEED: u64 = 16;

/// The solver's exact values at `pts`, [`Film::channels`] per point.
fn solve(req: &SideRequest, pts: &[[f32; 2]]) -> Result<Vec<f64>> {
    req.film.points_flat(
        &pts.iter()
            .map(|p| (f64::from(p[0]), f64::from(p[1])))
            .collect::<Vec<_>>(),
    )
}

/// What the atlas gives at `pts`, as a GPU reads it, [`Film::channels`]
/// per point.
fn read(uniform: &[f32], image: &Image, req: &SideRequest, pts: &[[f32; 2]]) -> Vec<f64> {
    let ch = req.film.channels();
    pts.par_iter()
        .flat_map_iter(|p| {
            let mut out = vec![0.0f32; ch];
            if let Some(t) = super::locate_f32(uniform, p[0], p[1], req.side) {
                image.bilinear(gpu_round_trip(t, image), &mut out);
            }
            out.into_iter().map(f64::from)
        })
        .collect()
}

/// A texel position as the filter of a GPU sees it: the shader divides it
/// by the texture's size (a texture coordinate in f32), and the filter
/// multiplies it back, off by an f32 rounding of each.
fn gpu_round_trip(t: [f32; 2], image: &Image) -> [f32; 2] {
    let size = [image.width as f32, image.height as f32];
    [0, 1].map(|k| (t[k] / size[k]) * size[k])
}

/// Whether a measurement meets the goal.
fn meets(m: &Measurement, goal: Goal) -> bool {
    goal.max_abs.is_none_or(|t| m.max_all() <= t)
        && goal
            .max_de
            .is_none_or(|t| m.max_de[0].max(m.max_de[1]) <= t)
}

/// Uniform random points over a side's domain, as f32 (what a shader gets),
/// from a PCG64 stream with `seed`.
pub fn random_points(
    thickness_nm: (f64, f64),
    cos: (f64, f64),
    n: usize,
    seed: u64,
) -> Vec<[f32; 2]> {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let mut draw = |(lo, hi): (f64, f64)| (lo + rng.random::<f64>() * (hi - lo)) as f32;
    (0..n).map(|_| [draw(thickness_nm), draw(cos)]).collect()
}

/// The cos θ in [c0, c1] below which `aliased` holds (aliasing only grows
/// towards grazing incidence): 0 when nowhere, c1 when everywhere. Scans
/// geometrically from grazing incidence up, then bisects the last step.
pub(super) fn aliased_edge(
    (c0, c1): (f64, f64),
    aliased: &dyn Fn(f64) -> Result<bool>,
) -> Result<f64> {
    let lowest = c0.max(1e-4);
    let ratio = (c1 / lowest).max(1.0);
    let (mut below, mut above) = (None, None);
    for k in 0..=40 {
        let c = lowest * ratio.powf(f64::from(k) / 40.0);
        if !aliased(c)? {
            above = Some(c);
            break;
        }
        below = Some(c);
    }
    let (Some(mut lo), Some(mut hi)) = (below, above) else {
        return Ok(below.map_or(0.0, |_| c1));
    };
    for _ in 0..12 {
        let mid = 0.5 * (lo + hi);
        if aliased(mid)? {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(hi)
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
