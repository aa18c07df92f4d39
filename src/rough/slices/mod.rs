//! F_eff on the nodes of an atlas: roughness *slices*, each an image of the
//! front side's charts (light from the ambient) holding the pre-integrated
//! rough reflectance at one roughness, read like the smooth atlas (chart
//! chosen in closed form, one bilinear filter) and blended linearly
//! between the two slices around the roughness.
//!
//! Slice s of S holds roughness (s / (S − 1))²: uniform in √roughness, so
//! a reader finds its slices in closed form, and dense at small roughness,
//! where F_eff changes fastest (the lobe starts to wash the fringes out).
//! Slice 0 is the smooth atlas's reflectance, texel for texel.
//!
//! The nodes of an atlas lie at scattered thicknesses and angles (a
//! chart's thickness axis is the layer's optical thickness, d = p / s(c)),
//! while F_eff is cheap only on a tensor grid: the film's smooth colour on
//! thickness nodes × the μ = v·h nodes of the quadrature ([`MuGrid`]),
//! weighted per (cos θ, roughness) by a [`Kernel`]. So each slice is
//! computed on a dense tensor grid, thickness (uniform in ln(1 + d / d₀): a
//! tenth of a nanometre near zero thickness, a twelfth of the shortest
//! fringe period at the top) × cos θ at the μ grid's own nodes (crowded
//! towards grazing incidence and split at a critical angle, built to
//! interpolate the film's colour cubically), and interpolated to each node
//! cubically in both.
//!
//! The slice count S is found from the second differences between slices
//! at every node: 5, 9 and 17 slices (each keeping the slices of the one
//! before), and from the blend errors of the last two (the error taken to
//! fall as a power of the spacing, the power they show) the count a linear
//! blend needs for its share of the target, rounded so that (S − 1) is a
//! multiple of 16 and those slices are kept too. The result is then measured
//! against [`rough_reflectance`] at random points, and the intervals doubled
//! while that misses the target.
//!
//! Each slice's table is a matrix product: one kernel per cos θ node (its
//! weights on the μ nodes) times the film's colour on μ nodes × dense
//! thicknesses; the kernels, deterministic quadratures of the GGX lobe, are
//! most of the cost. The slices' μ grid has half the intervals of the
//! reference ([`Quadrature::default`]'s), which the measurement shows to
//! cost nothing visible.
//!
//! Near grazing incidence (cos θ below [`GRAZING_COS`]) F_eff changes with
//! roughness on the scale of cos θ itself (the lobe's width α = roughness²
//! against the view angle's distance from the horizon), which no slice
//! count uniform in √roughness follows down to cos θ = 0: there the error
//! is measured and stated separately, as the smooth atlas states its
//! aliased strip.
//!
//! The steps are files: `dense.rs` (the dense grid and the cubic
//! interpolation from it), `count.rs` (the slice count, the charts' growth,
//! packing and filling), `measure.rs` (the random points and the figures);
//! [`build`] here runs them.

use rand::{Rng, SeedableRng};
use rayon::prelude::*;

use super::kernel::{Kernel, Rules};
use super::{rough_reflectance, MuGrid, Quadrature, RoughTable};
use crate::atlas::{pack, Atlas, Chart, Coords, Film, Image};
use crate::color::{delta_e2000_rgb, SpectralIntegrator};
use crate::error::{Error, Result};
use crate::optics::Stack;
use crate::simd::simd_dispatch;
use crate::stats::{self, RoughFigures};
use crate::sweep::rgb_at_nodes;
use crate::sweep::Side;

mod count;
mod dense;
mod measure;

use count::*;
use dense::*;
use measure::*;
pub use measure::{cos_span, measure_sampler, MeasurePoints, Reference};

/// Slices of the first count tried.
const START_SLICES: usize = 5;
/// The most slices.
pub const MAX_SLICES: usize = 129;
/// cos θ below which the slices' target is not sought (θ > 88.85°); see
/// the module docs.
pub const GRAZING_COS: f64 = 0.02;
/// The scale d₀ (nm) of the dense thickness grid's warp ln(1 + d / d₀).
const THICKNESS_SCALE_NM: f64 = 20.0;
/// The dense grid's spacing near zero thickness (nm).
const FINEST_SPACING_NM: f64 = 0.4;
/// Dense-grid intervals per shortest fringe period at the top of the range.
const INTERVALS_PER_FRINGE: f64 = 8.0;
/// The shortest wavelength of the colour integration (nm): it sets the
/// shortest fringe period.
const SHORTEST_WAVELENGTH_NM: f64 = 380.0;
/// Intervals of the slices' μ grid: half the reference's
/// ([`Quadrature::default`]), the film's colour interpolated cubically
/// between its nodes all the same; the measurement against the reference
/// shows what that costs (nothing visible for the soap film).
const SLICE_MU_INTERVALS: usize = 64;
/// Gauss–Legendre points along the azimuth of the slices' kernels: half
/// the reference's ([`Quadrature::default`]'s); the kernels are most of
/// the slices' cost, and the measurement against the reference shows what
/// the coarser rule costs.
const SLICE_INNER_POINTS: usize = 8;

/// The quadrature of the slices' kernels.
fn slice_quadrature() -> Quadrature {
    Quadrature {
        mu_intervals: SLICE_MU_INTERVALS,
        inner: SLICE_INNER_POINTS,
        ..Quadrature::default()
    }
}

/// Share of the target the slice blend may use (the charts' own
/// interpolation takes the rest).
const BLEND_SHARE: f64 = 0.5;
/// Times the first slice count is doubled (if its blend misses) before the
/// last two blend errors predict the count.
const DOUBLINGS_BEFORE_PREDICTION: usize = 2;
/// Rounds of doubling the slices after the first measurement.
const MAX_DOUBLINGS: usize = 2;
/// Random cosines and roughnesses of the measurement: it takes every
/// combination of them and [`MEASURE_THICKNESSES`] thicknesses (each cosine
/// and roughness costs a kernel, each thickness little).
pub const MEASURE_AXIS_POINTS: usize = 24;
/// Random thicknesses of the measurement.
pub const MEASURE_THICKNESSES: usize = 112;
/// The seed of the measurement's PCG64 stream.
pub const MEASURE_SEED: u64 = 29;

/// F_eff of a film's front side on an atlas, one image per roughness.
#[derive(Clone, Debug)]
pub struct RoughSlices {
    /// The front side's charts, packed on their own.
    pub atlas: Atlas,
    /// Roughness of each slice: (s / (S − 1))².
    pub roughness: Vec<f64>,
    /// One image (R, G, B of F_eff, as f32) per slice, the atlas's size.
    pub slices: Vec<Image>,
    /// The linear blend's error predicted from the slices' second
    /// differences (cos θ ≥ [`GRAZING_COS`]).
    pub blend_error: f64,
    /// Against [`rough_reflectance`] at random points with cos θ ≥
    /// [`GRAZING_COS`]: what the target is met over.
    pub measured: RoughFigures,
    /// The same at random points with cos θ < [`GRAZING_COS`].
    pub grazing: RoughFigures,
}

/// What [`build`] needs besides the film.
pub struct SliceRequest<'a> {
    /// The film, for the smooth reflectance at nodes of grown charts.
    pub film: &'a Film,
    /// The smooth atlas: its side-0 charts are the slices' charts.
    pub atlas: &'a Atlas,
    /// Its texels, R first (at least three channels): slice 0.
    pub image: &'a Image,
    /// The largest absolute error allowed in any channel.
    pub max_error: f64,
    /// The largest texture side the slices' atlas may take.
    pub max_side: usize,
    /// What to measure the slices against; `None`: points of their own
    /// ([`measure_sampler`]'s).
    pub reference: Option<&'a Reference>,
}

/// The roughness of slice `s` of `count`.
pub fn slice_roughness(s: usize, count: usize) -> f64 {
    if count < 2 {
        return 0.0;
    }
    let x = s as f64 / (count - 1) as f64;
    x * x
}

impl RoughSlices {
    /// F_eff at thickness `d` nm, cos θ `c` and roughness `r`, as a reader
    /// computes it: the chart by the atlas's rule, one bilinear fetch in each
    /// of the two slices around √r · (S − 1), blended linearly.
    pub fn sample(&self, d: f64, c: f64, r: f64) -> [f64; 3] {
        let Some(k) = self.atlas.chart_for(d, c, Side::Front) else {
            return [0.0; 3];
        };
        let chart = &self.atlas.charts[k];
        let d = d.clamp(self.atlas.thickness_nm.0, self.atlas.thickness_nm.1);
        let (x, y) = chart.xy(d, c.clamp(0.0, 1.0));
        let rect = chart.rect;
        let at = [
            (rect.x as f64 + 0.5 + x * (rect.width - 1) as f64) as f32,
            (rect.y as f64 + 0.5 + y * (rect.height - 1) as f64) as f32,
        ];
        let last = self.slices.len() - 1;
        let pos = r.clamp(0.0, 1.0).sqrt() * last as f64;
        let s = (pos.floor() as usize).min(last.saturating_sub(1));
        let f = (pos - s as f64).clamp(0.0, 1.0);
        let (mut a, mut b) = ([0.0f32; 3], [0.0f32; 3]);
        self.slices[s].bilinear(at, &mut a);
        self.slices[(s + 1).min(last)].bilinear(at, &mut b);
        std::array::from_fn(|k| f64::from(a[k]) + f * (f64::from(b[k]) - f64::from(a[k])))
    }
}

/// Every node (thickness nm, cos θ) of `chart`, row-major.
fn chart_nodes(chart: &Chart) -> Vec<(f64, f64)> {
    let (w, h) = (chart.rect.width, chart.rect.height);
    (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .map(|(i, j)| {
            let (d, c) = chart.node(i, j);
            (d.max(0.0), c.clamp(0.0, 1.0))
        })
        .collect()
}

/// F_eff on the side-0 charts of `req.atlas` (grown where F_eff needs more
/// nodes than the smooth film) for the film `stack` (layer `layer`
/// varying), slice count chosen for `req.max_error`, then measured.
pub fn build(
    stack: &Stack,
    layer: usize,
    integrator: &SpectralIntegrator,
    req: &SliceRequest,
    progress: &dyn Fn(&str),
) -> Result<RoughSlices> {
    if !(req.max_error > 0.0 && req.max_error.is_finite()) {
        return Err(Error::invalid(
            "rough error target",
            format!("{} is not a positive number", req.max_error),
        ));
    }
    let start = std::time::Instant::now();
    let say = |what: String| {
        progress(&format!(
            "rough: {what} ({:.1} s)",
            start.elapsed().as_secs_f64()
        ))
    };
    let smooth_charts = front_charts(req.atlas)?;
    let quadrature = slice_quadrature();
    let grid = MuGrid::for_stack(stack, quadrature.mu_intervals);
    let nodes: Vec<(f64, f64)> = smooth_charts.iter().flat_map(chart_nodes).collect();
    let dense = dense_grid(stack, layer, integrator, &nodes, &grid)?;
    say(format!(
        "F_eff from {} thicknesses x {} μ nodes",
        dense.count,
        grid.nodes().len(),
    ));
    let rules = Rules::new(&quadrature);
    let filler = Filler {
        dense: &dense,
        grid: &grid,
        rules: &rules,
    };
    let smooth0 = smooth_values(req, &smooth_charts);
    let (mut tables, mut blend_error) =
        predicted_tables(&filler, req, &smooth0, BLEND_SHARE * req.max_error, &say);
    let mut doublings = 0;
    loop {
        let count = tables.len() + 1;
        let charts = grown_charts(
            &filler,
            &tables,
            req.atlas,
            (1.0 - BLEND_SHARE) * req.max_error,
            req.max_side,
        );
        let atlas = packed(req.atlas.thickness_nm, charts, req.max_side)?;
        say(format!("charts grown to {}x{}", atlas.width, atlas.height));
        let slices = images(req, &filler, &tables, &smooth_charts, &atlas)?;
        say(format!("{count} images"));
        let mut built = RoughSlices {
            atlas,
            roughness: (0..count).map(|s| slice_roughness(s, count)).collect(),
            slices,
            blend_error,
            measured: RoughFigures::default(),
            grazing: RoughFigures::default(),
        };
        (built.measured, built.grazing) = match req.reference {
            Some(reference) => reference.errors(&|d, c, r| built.sample(d, c, r)),
            None => measure(stack, layer, integrator, &built)?,
        };
        say(format!(
            "{count} slices of {}x{}, measured {:.2e} (cos θ ≥ {GRAZING_COS}), {:.2e} below",
            built.atlas.width,
            built.atlas.height,
            built.measured.max_all(),
            built.grazing.max_all(),
        ));
        if built.measured.max_all() <= req.max_error {
            return Ok(built);
        }
        if doublings == MAX_DOUBLINGS || 2 * count - 1 > MAX_SLICES {
            return Err(off_target(&built, req.max_error));
        }
        doublings += 1;
        grow_tables(&mut tables, 2 * count - 1, &filler);
        say(format!("{} slices", tables.len() + 1));
        blend_error = second_difference_error(&filler, &tables, req.atlas, &smooth0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atlas::search::{self, Goal, SideRequest};
    use crate::color::White;

    fn slices_of(
        path: &str,
        thickness_nm: (f64, f64),
        cos: (f64, f64),
        max_error: f64,
    ) -> RoughSlices {
        let mut stack = Stack::load(std::path::Path::new(path)).expect("stack");
        stack.layers[0].thickness_nm = thickness_nm.0;
        let integrator = SpectralIntegrator::with_white(crate::color::Sampling::Exact, White::D65);
        let film = Film::new(&stack, 1, integrator.clone()).expect("film");
        let goal = Goal {
            max_abs: Some(1e-3),
            max_de: None,
            half: false,
        };
        let sides = [SideRequest {
            film: &film,
            side: Side::Front,
            cos,
            goal,
        }];
        let points = search::random_points(thickness_nm, cos, 2000, 7);
        let built =
            search::build(&sides, thickness_nm, 8192, &[points], &|_| {}).expect("smooth atlas");
        let req = SliceRequest {
            film: &film,
            atlas: &built.atlas,
            image: &built.image,
            max_error,
            max_side: 8192,
            reference: None,
        };
        let t = std::time::Instant::now();
        let s = build(film.stack(), film.layer(), &integrator, &req, &|l| {
            eprintln!("{l}")
        })
        .expect("slices");
        eprintln!(
            "{path}: {} slices of {}x{}, blend {:.2e}, measured {:?}, grazing {:?} in {:.2?}",
            s.slices.len(),
            s.atlas.width,
            s.atlas.height,
            s.blend_error,
            s.measured,
            s.grazing,
            t.elapsed()
        );
        s
    }

    #[test]
    fn soap_film_slices_meet_their_target() {
        let s = slices_of("luts/soap-film.toml", (0.0, 1000.0), (0.0, 1.0), 2e-3);
        assert!(s.measured.max_all() <= 2e-3, "{:?}", s.measured);
        assert!(s.blend_error <= 2e-3);
        // The grazing strip is measured and finite (its figure is stated,
        // not sought).
        assert!(s.grazing.points > 0 && s.grazing.max_all().is_finite());
        // Slice 0 is the smooth film, the last roughness 1, and every texel
        // finite.
        assert_eq!(s.roughness[0], 0.0);
        assert_eq!(*s.roughness.last().unwrap(), 1.0);
        assert!(s
            .slices
            .iter()
            .all(|i| i.data.iter().all(|v| v.is_finite())));
        // At a slice's own roughness the blend is that slice alone.
        let k = s.slices.len() / 2;
        let c = s.atlas.charts.last().unwrap();
        let (d, cos) = c.node(1, 1);
        let t = s.slices[k].texel(c.rect.x + 1, c.rect.y + 1);
        let got = s.sample(d, cos, s.roughness[k]);
        for ch in 0..3 {
            assert!((got[ch] - f64::from(t[ch])).abs() < 1e-5, "{got:?} {t:?}");
        }
    }

    /// Charts over part of the angles are measured over those angles only
    /// (cos θ 0.5–1: no grazing points at all).
    #[test]
    fn restricted_angles_are_measured_where_the_charts_serve() {
        let s = slices_of("luts/soap-film.toml", (300.0, 400.0), (0.5, 1.0), 2e-3);
        assert!(
            s.measured.points > 0 && s.measured.max_all() <= 2e-3,
            "{:?}",
            s.measured
        );
        assert_eq!(s.grazing.points, 0);
        let (lo, hi) = cos_span(&s.atlas);
        assert!(
            (lo - 0.5).abs() < 1e-9 && (hi - 1.0).abs() < 1e-9,
            "{lo} {hi}"
        );
    }
}
