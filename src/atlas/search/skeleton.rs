//! Step 1, the skeleton: a side's cos θ range cut into pieces at a
//! dense-side critical angle, the corner chart of a free-standing film,
//! and the aliased strip's edge.

use super::*;

/// The pieces, corner and aliased strip of one side (see the module docs).
pub(super) fn skeleton<'a>(
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
pub(super) const EDGE: f64 = 1e-6;

/// The critical band `(a, b)` as it cuts the cos θ `range`: whole when it is
/// inside, else a dispersive band's part inside the range (a range that
/// starts or ends inside the band still has the band's charts, not a search
/// through it); `None` when it does not cut the range.
pub(super) fn within(range: (f64, f64), (a, b): (f64, f64)) -> Option<(f64, f64)> {
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
pub(super) fn critical_band(film: &Film) -> Result<Option<(f64, f64)>> {
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
pub(super) fn corner_chart(
    req: &SideRequest,
    thickness_nm: (f64, f64),
    goal: Goal,
) -> Result<Option<Chart>> {
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
pub(super) fn aliasing_floor(
    req: &SideRequest,
    thickness_nm: (f64, f64),
    goal: Goal,
) -> Result<f64> {
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

/// The cos θ in [c0, c1] below which `aliased` holds (aliasing only grows
/// towards grazing incidence): 0 when nowhere, c1 when everywhere. Scans
/// geometrically from grazing incidence up, then bisects the last step.
pub(in crate::atlas) fn aliased_edge(
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
