//! The atlas against the solver at random points, as a GPU reads it: the
//! figures of each side, over the points the target applies to and apart
//! over the aliased strip and a dispersive critical band.

use super::*;

/// Error figures of an atlas at `points` against the solver: `got` and
/// `exact` hold `channels` values per point (R.r, R.g, R.b, T.r, T.g, T.b
/// for a colour film; see [`Film::channels`]), the error relative above 1
/// ([`scaled_error`]); with `colour`, the CIEDE2000 of the reflected and
/// the transmitted colour (zero for spectra; a NaN counts as infinite).
pub fn figures(
    points: &[[f32; 2]],
    got: &[f64],
    exact: &[f64],
    channels: usize,
    colour: bool,
) -> AtlasFigures {
    if points.is_empty() {
        return AtlasFigures {
            max_abs: vec![0.0; channels],
            p99_abs: vec![0.0; channels],
            mean_abs: vec![0.0; channels],
            ..AtlasFigures::default()
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
    let abs: Vec<f64> = errors.iter().flat_map(|x| x.0.iter().copied()).collect();
    let de: Vec<f64> = errors.iter().flat_map(|x| x.1).collect();
    let s = summarize(&abs, channels, &de, 2);
    AtlasFigures {
        points: s.points,
        max_abs: s.max_abs,
        p99_abs: s.p99_abs,
        mean_abs: s.mean_abs,
        max_delta_e00: [s.max_de[0], s.max_de[1]],
        mean_delta_e00: [s.mean_de[0], s.mean_de[1]],
        seed: None,
        worst_point: points[s.worst.unwrap_or(0)].map(f64::from),
    }
}

/// What one side's random points say about an atlas: over the points the
/// target applies to, and over those in the aliased strip.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SideMeasurement {
    /// The side.
    pub side: Side,
    /// Every point of the side.
    pub all: AtlasFigures,
    /// The points the target applies to: at or above the aliased strip's
    /// edge and outside a dispersive critical band.
    pub resolved: AtlasFigures,
    /// The points in the aliased strip (none when there is no strip).
    pub aliased: AtlasFigures,
    /// [`CRITICAL_BAND_POINTS`] points of its own in the dispersive
    /// critical band where the target is not sought
    /// ([`SideReport::unsought_band`]); none when there is no such band.
    pub critical: AtlasFigures,
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
                figures(
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
                    figures(own, &got, exact, ch, colour)
                }
            };
            SideMeasurement {
                side: req.side,
                all: figures(pts, &got, &solved.exact, ch, colour),
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
pub(super) fn solve(req: &SideRequest, pts: &[[f32; 2]]) -> Result<Vec<f64>> {
    req.film.points_flat(
        &pts.iter()
            .map(|p| (f64::from(p[0]), f64::from(p[1])))
            .collect::<Vec<_>>(),
    )
}

/// What the atlas gives at `pts`, as a GPU reads it, [`Film::channels`]
/// per point.
pub(super) fn read(
    uniform: &[f32],
    image: &Image,
    req: &SideRequest,
    pts: &[[f32; 2]],
) -> Vec<f64> {
    let ch = req.film.channels();
    pts.par_iter()
        .flat_map_iter(|p| {
            let mut out = vec![0.0f32; ch];
            if let Some(t) = crate::atlas::locate_f32(uniform, p[0], p[1], req.side) {
                image.bilinear(gpu_round_trip(t, image), &mut out);
            }
            out.into_iter().map(f64::from)
        })
        .collect()
}

/// A texel position as the filter of a GPU sees it: the shader divides it
/// by the texture's size (a texture coordinate in f32), and the filter
/// multiplies it back, off by an f32 rounding of each.
pub(super) fn gpu_round_trip(t: [f32; 2], image: &Image) -> [f32; 2] {
    let size = [image.width as f32, image.height as f32];
    [0, 1].map(|k| (t[k] / size[k]) * size[k])
}

/// Whether a measurement meets the goal.
pub(super) fn meets(m: &AtlasFigures, goal: Goal) -> bool {
    goal.max_abs.is_none_or(|t| m.max_all() <= t)
        && goal
            .max_de
            .is_none_or(|t| m.max_delta_e00[0].max(m.max_delta_e00[1]) <= t)
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
