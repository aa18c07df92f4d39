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

use rand::{Rng, SeedableRng};
use rayon::prelude::*;

use super::kernel::{Kernel, Rules};
use super::{rough_reflectance, MuGrid, Quadrature, RoughTable};
use crate::atlas::{pack, Atlas, Chart, Coords, Film, Image};
use crate::color::{delta_e2000_rgb, SpectralIntegrator};
use crate::error::{Error, Result};
use crate::optics::Stack;
use crate::simd::simd_dispatch;
use crate::sweep::rgb_at_nodes;
use crate::sweep::Side;

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

/// What the slices give against [`rough_reflectance`] at random points,
/// per RGB channel of F_eff.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SliceError {
    /// Points measured.
    pub points: usize,
    /// Largest absolute error per channel.
    pub max_abs: [f64; 3],
    /// 99th percentile of the absolute error per channel.
    pub p99_abs: [f64; 3],
    /// Mean absolute error per channel.
    pub mean_abs: [f64; 3],
    /// Largest and mean CIEDE2000 of the colour.
    pub max_delta_e00: f64,
    /// Mean CIEDE2000.
    pub mean_delta_e00: f64,
    /// (thickness nm, cos θ, roughness) of the largest absolute error.
    pub worst_point: [f64; 3],
}

impl SliceError {
    /// The largest of `max_abs`.
    pub fn max_all(&self) -> f64 {
        self.max_abs.iter().fold(0.0, |a, &b| a.max(b))
    }
}

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
    pub measured: SliceError,
    /// The same at random points with cos θ < [`GRAZING_COS`].
    pub grazing: SliceError,
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

/// The film's smooth colour on the dense thickness grid × the μ nodes, and
/// the cubic interpolation in thickness.
struct Dense {
    /// Thickness nodes, uniform in w = ln(1 + (d − d_lo) / d₀).
    lo_nm: f64,
    step: f64,
    count: usize,
    /// R, G, B at (μ node m, thickness t): `values[(m * count + t) * 3 + ch]`
    /// (one row of `3 * count` values per μ node, what the weighing sums).
    values: Vec<f64>,
}

impl Dense {
    fn position(&self, d: f64) -> f64 {
        if self.count < 2 {
            return 0.0;
        }
        ((d - self.lo_nm).max(0.0) / THICKNESS_SCALE_NM).ln_1p() / self.step
    }

    /// The four dense nodes around `d` and their Catmull–Rom weights
    /// (indices clamped at the ends).
    fn stencil(&self, d: f64) -> ([usize; 4], [f64; 4]) {
        let last = self.count.saturating_sub(1);
        let pos = self.position(d).clamp(0.0, last as f64);
        let k = (pos.floor() as usize).min(last.saturating_sub(1));
        let t = pos - k as f64;
        let (t2, t3) = (t * t, t * t * t);
        let w = [
            -0.5 * t3 + t2 - 0.5 * t,
            1.5 * t3 - 2.5 * t2 + 1.0,
            -1.5 * t3 + 2.0 * t2 + 0.5 * t,
            0.5 * t3 - 0.5 * t2,
        ];
        let idx = |o: i64| (k as i64 + o).clamp(0, last as i64) as usize;
        ([idx(-1), idx(0), idx(1), idx(2)], w)
    }

    /// `out` (R, G, B at every dense thickness) = F_eff for `kernel`: the
    /// kernel's weighted sum of the μ rows, a row of the matrix product
    /// kernels × values, summed a cache-sized block of the row at a time.
    fn weigh(&self, kernel: &Kernel, out: &mut [f64]) {
        const BLOCK: usize = 1024;
        let (first, weights) = kernel.weights();
        let len = 3 * self.count;
        out.fill(0.0);
        for start in (0..len).step_by(BLOCK) {
            let end = (start + BLOCK).min(len);
            for (j, &w) in weights.iter().enumerate() {
                let row = (first + j) * len;
                add_scaled(
                    w,
                    &self.values[row + start..row + end],
                    &mut out[start..end],
                );
            }
        }
    }
}

simd_dispatch! {
    /// `y += w x`, element by element (unfused: every copy rounds alike).
    fn add_scaled(w: f64, x: &[f64], y: &mut [f64]) {
        for (y, x) in y.iter_mut().zip(x) {
            *y += w * *x;
        }
    }
}

/// F_eff at one roughness on the dense tensor grid:
/// `[(c * n_t + t) * 3 + ch]` for cos θ node c of the tables' grid, dense
/// thickness t and channel ch.
type Table = Vec<f64>;

/// Where a point (thickness, cos θ) lies in the tables: the four dense
/// thicknesses and four cos θ nodes around it and their weights, found once
/// and applied to every slice's table.
#[derive(Clone, Copy)]
struct Stencil {
    thickness: [usize; 4],
    thickness_weights: [f64; 4],
    first_cos: usize,
    cos_weights: [f64; 4],
}

/// What computes F_eff: the dense grid, the μ grid (its nodes are the μ of
/// the film's colour and the tables' cos θ), and the quadrature's rules.
struct Filler<'a> {
    dense: &'a Dense,
    grid: &'a MuGrid,
    rules: &'a Rules,
}

impl Filler<'_> {
    /// F_eff at every roughness of `roughness` on the dense tensor grid:
    /// one kernel per (roughness, cos θ node), each weighing the μ rows.
    fn tables(&self, roughness: &[f64]) -> Vec<Table> {
        let len = 3 * self.dense.count;
        let cos = self.grid.nodes();
        roughness
            .iter()
            .map(|&r| {
                let mut table = vec![0.0; cos.len() * len];
                table
                    .par_chunks_mut(len)
                    .zip(cos.par_iter())
                    .for_each(|(out, &c)| {
                        let kernel = Kernel::with_rules(self.grid, c, r, self.rules);
                        self.dense.weigh(&kernel, out);
                    });
                table
            })
            .collect()
    }

    /// The stencil of (`d` nm, cos θ `c`): cubic in both.
    fn stencil(&self, d: f64, c: f64) -> Stencil {
        let (thickness, thickness_weights) = self.dense.stencil(d);
        let (first_cos, cos_weights) = self.grid.interpolation(c);
        Stencil {
            thickness,
            thickness_weights,
            first_cos,
            cos_weights,
        }
    }

    /// F_eff from `table` at the point of `at`.
    fn at(&self, table: &Table, at: &Stencil) -> [f64; 3] {
        let n_t = self.dense.count;
        let mut v = [0.0; 3];
        for (j, wc) in at.cos_weights.iter().enumerate() {
            let row = &table[(at.first_cos + j) * n_t * 3..];
            for (&i, wd) in at.thickness.iter().zip(at.thickness_weights) {
                let w = wc * wd;
                let texel = &row[i * 3..i * 3 + 3];
                for (o, x) in v.iter_mut().zip(texel) {
                    *o += w * x;
                }
            }
        }
        v
    }

    /// F_eff from `table` at each point of `at`.
    fn values(&self, table: &Table, at: &[Stencil]) -> Vec<[f64; 3]> {
        at.iter().map(|s| self.at(table, s)).collect()
    }

    /// The stencils of every node of `chart` (its rectangle's size),
    /// row-major.
    fn chart_stencils(&self, chart: &Chart) -> Vec<Stencil> {
        chart_nodes(chart)
            .into_iter()
            .map(|(d, c)| self.stencil(d, c))
            .collect()
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
    let smooth_charts: Vec<Chart> = req
        .atlas
        .charts
        .iter()
        .filter(|c| c.side == Side::Front)
        .copied()
        .collect();
    if smooth_charts.is_empty() {
        return Err(Error::invalid(
            "rough table",
            "the atlas has no chart of light from the ambient",
        ));
    }
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
            measured: SliceError::default(),
            grazing: SliceError::default(),
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
            return Err(Error::invalid(
                "rough table",
                format!(
                    "{count} roughness slices of {}x{} texels are off by {:.2e} at thickness \
                     {:.1} nm, cos θ {:.4}, roughness {:.3}, above the target {:.1e}",
                    built.atlas.width,
                    built.atlas.height,
                    built.measured.max_all(),
                    built.measured.worst_point[0],
                    built.measured.worst_point[1],
                    built.measured.worst_point[2],
                    req.max_error
                ),
            ));
        }
        doublings += 1;
        grow_tables(&mut tables, 2 * count - 1, &filler);
        say(format!("{} slices", tables.len() + 1));
        blend_error = second_difference_error(&filler, &tables, req.atlas, &smooth0);
    }
}

/// The smooth atlas's reflectance at every node of each of `charts` (its
/// side-0 charts), row-major per chart.
fn smooth_values(req: &SliceRequest, charts: &[Chart]) -> Vec<Vec<[f64; 3]>> {
    charts
        .iter()
        .map(|chart| {
            let r = chart.rect;
            (0..r.height)
                .flat_map(|j| (0..r.width).map(move |i| (i, j)))
                .map(|(i, j)| {
                    let v = req.image.texel(r.x + i, r.y + j);
                    [f64::from(v[0]), f64::from(v[1]), f64::from(v[2])]
                })
                .collect()
        })
        .collect()
}

/// Makes `tables` (slices 1.. of S, uniform in √roughness; slice 0 is the
/// smooth film's) those of `count` slices, (count − 1) a multiple of
/// (S − 1): the old ones keep their places, the new ones are computed.
fn grow_tables(tables: &mut Vec<Table>, count: usize, filler: &Filler) {
    let old_count = tables.len() + 1;
    let stride = if old_count > 1 {
        (count - 1) / (old_count - 1)
    } else {
        1
    };
    let kept = |s: usize| old_count > 1 && s.is_multiple_of(stride);
    let new: Vec<usize> = (1..count).filter(|&s| !kept(s)).collect();
    let roughness: Vec<f64> = new.iter().map(|&s| slice_roughness(s, count)).collect();
    let mut computed = filler.tables(&roughness).into_iter();
    let mut old = std::mem::take(tables).into_iter();
    for s in 1..count {
        let next = if kept(s) { old.next() } else { computed.next() };
        tables.push(next.expect("a table for every slice"));
    }
}

/// The first tables: [`START_SLICES`] slices, then twice and four times as
/// many intervals until the blend meets `target`; from the blend errors of
/// the last two the count whose blend meets it (the error falling as a
/// power of the spacing, the power measured), a multiple of the last one's
/// intervals so that its slices are kept.
fn predicted_tables(
    filler: &Filler,
    req: &SliceRequest,
    smooth0: &[Vec<[f64; 3]>],
    target: f64,
    say: &dyn Fn(String),
) -> (Vec<Table>, f64) {
    let mut tables = Vec::new();
    let mut finer = START_SLICES;
    grow_tables(&mut tables, finer, filler);
    let mut errors = vec![second_difference_error(filler, &tables, req.atlas, smooth0)];
    for _ in 0..DOUBLINGS_BEFORE_PREDICTION {
        if errors[errors.len() - 1] <= target {
            break;
        }
        finer = 2 * finer - 1;
        grow_tables(&mut tables, finer, filler);
        errors.push(second_difference_error(filler, &tables, req.atlas, smooth0));
    }
    let fine = errors[errors.len() - 1];
    if fine <= target || errors.len() < 2 {
        return (tables, fine);
    }
    let coarse = errors[errors.len() - 2];
    let predicted = predicted_count(finer, coarse, fine, target);
    say(format!(
        "{} and {finer} slices blend to {coarse:.2e} and {fine:.2e}; {predicted} predicted",
        finer / 2 + 1
    ));
    if predicted == finer {
        return (tables, fine);
    }
    grow_tables(&mut tables, predicted, filler);
    let blend = second_difference_error(filler, &tables, req.atlas, smooth0);
    (tables, blend)
}

/// The linear blend's largest error halfway between slices, estimated as
/// |F(s−1) − 2 F(s) + F(s+1)| / 8 at every node of `charts` with cos θ ≥
/// [`GRAZING_COS`] (`smooth` is slice 0 at those nodes).
fn second_difference_error(
    filler: &Filler,
    tables: &[Table],
    atlas: &Atlas,
    smooth: &[Vec<[f64; 3]>],
) -> f64 {
    let fronts: Vec<(usize, &Chart)> = atlas
        .charts
        .iter()
        .enumerate()
        .filter(|(_, c)| c.side == Side::Front)
        .collect();
    fronts
        .par_iter()
        .zip(smooth)
        .map(|(&(owner, chart), slice0)| {
            let nodes = chart_nodes(chart);
            let stencils = filler.chart_stencils(chart);
            let mut values: Vec<Vec<[f64; 3]>> = vec![slice0.clone()];
            values.extend(tables.iter().map(|t| filler.values(t, &stencils)));
            let mut worst = 0.0f64;
            for (k, &(d, c)) in nodes.iter().enumerate() {
                if c < GRAZING_COS || atlas.chart_for(d, c, Side::Front) != Some(owner) {
                    continue;
                }
                for w in values.windows(3) {
                    let (a, b, c) = (w[0][k], w[1][k], w[2][k]);
                    for ((a, b), c) in a.iter().zip(b).zip(c) {
                        worst = worst.max((a - 2.0 * b + c).abs() / 8.0);
                    }
                }
            }
            worst
        })
        .reduce(|| 0.0, f64::max)
}

/// The slice count whose blend error meets `target`, from its errors
/// `coarse` and `fine` at (`count` − 1) / 2 and `count` − 1 intervals: the
/// error taken to fall as the spacing to the power the two show (between 1
/// and 2, the linear blend's own order), the count rounded up to a
/// multiple of `count` − 1 intervals, at most [`MAX_SLICES`].
fn predicted_count(count: usize, coarse: f64, fine: f64, target: f64) -> usize {
    if fine <= target {
        return count;
    }
    let order = (coarse / fine).log2().clamp(1.0, 2.0);
    let factor = (fine / target).powf(1.0 / order);
    let step = count - 1;
    let multiple = (factor.ceil() as usize).max(1);
    (step * multiple + 1).min((MAX_SLICES - 1) / step * step + 1)
}

/// Rounds of growing the charts.
const CHART_ROUNDS: usize = 3;

/// `charts` with their node counts grown until bilinear interpolation of
/// every slice's F_eff meets `target` halfway between nodes along each axis
/// (cos θ ≥ [`GRAZING_COS`]); never fewer nodes than the smooth film's.
fn grown_charts(
    filler: &Filler,
    tables: &[Table],
    atlas: &Atlas,
    target: f64,
    max_side: usize,
) -> Vec<Chart> {
    atlas
        .charts
        .par_iter()
        .enumerate()
        .filter(|(_, c)| c.side == Side::Front)
        .map(|(k, chart)| {
            let serves = |d: f64, c: f64| atlas.chart_for(d, c, Side::Front) == Some(k);
            let mut chart = *chart;
            for _ in 0..CHART_ROUNDS {
                let (eu, ev) = midpoint_errors(filler, tables, &chart, &serves);

                let grow = |n: usize, e: f64| -> usize {
                    if e <= target || n < 2 {
                        return n;
                    }
                    let factor = (e / target).sqrt() * 1.1;
                    (1 + ((n - 1) as f64 * factor).ceil() as usize).min(max_side)
                };
                let (w, h) = (grow(chart.rect.width, eu), grow(chart.rect.height, ev));
                if (w, h) == (chart.rect.width, chart.rect.height) {
                    break;
                }
                chart.rect.width = w;
                chart.rect.height = h;
            }
            chart
        })
        .collect()
}

/// The largest error of linear interpolation halfway between neighbouring
/// nodes along u and along v of `chart`, over every slice's F_eff, where
/// `serves` says the chart is the one a reader picks (a band's nodes
/// inside a corner chart's radius are never read).
fn midpoint_errors(
    filler: &Filler,
    tables: &[Table],
    chart: &Chart,
    serves: &dyn Fn(f64, f64) -> bool,
) -> (f64, f64) {
    let (w, h) = (chart.rect.width, chart.rect.height);
    let frac = |k: f64, n: usize| if n > 1 { k / (n - 1) as f64 } else { 0.0 };
    let point = |x: f64, y: f64| {
        let (d, c) = chart.point(x, y);
        (d.max(0.0), c.clamp(0.0, 1.0))
    };
    let nodes: Vec<Stencil> = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .map(|(i, j)| {
            let (d, c) = point(frac(i as f64, w), frac(j as f64, h));
            filler.stencil(d, c)
        })
        .collect();
    // (node, its neighbour, the midpoint's stencil, along u) for every
    // midpoint a reader may fetch.
    let mut checks: Vec<(usize, usize, Stencil, bool)> = Vec::new();
    for j in 0..h {
        for i in 0..w {
            if point(frac(i as f64, w), frac(j as f64, h)).1 < GRAZING_COS {
                continue;
            }
            let k = j * w + i;
            let mut check = |(d, c): (f64, f64), next: usize, along_u: bool| {
                if serves(d, c) {
                    checks.push((k, next, filler.stencil(d, c), along_u));
                }
            };
            if i + 1 < w {
                check(
                    point(frac(i as f64 + 0.5, w), frac(j as f64, h)),
                    k + 1,
                    true,
                );
            }
            if j + 1 < h {
                check(
                    point(frac(i as f64, w), frac(j as f64 + 0.5, h)),
                    k + w,
                    false,
                );
            }
        }
    }
    let off = |mid: [f64; 3], a: [f64; 3], b: [f64; 3]| {
        (0..3)
            .map(|ch| (mid[ch] - 0.5 * (a[ch] + b[ch])).abs())
            .fold(0.0, f64::max)
    };
    let (mut eu, mut ev) = (0.0f64, 0.0f64);
    for table in tables {
        let values = filler.values(table, &nodes);
        for (a, b, mid, along_u) in &checks {
            let e = off(filler.at(table, mid), values[*a], values[*b]);
            if *along_u {
                eu = eu.max(e);
            } else {
                ev = ev.max(e);
            }
        }
    }
    (eu, ev)
}

/// `charts` packed in one atlas over `thickness_nm`.
fn packed(thickness_nm: (f64, f64), charts: Vec<Chart>, max_side: usize) -> Result<Atlas> {
    let sizes: Vec<(usize, usize)> = charts
        .iter()
        .map(|c| (c.rect.width, c.rect.height))
        .collect();
    let (places, width, height) = pack(&sizes, max_side).ok_or_else(|| {
        Error::invalid(
            "rough table",
            format!("the slices' charts do not fit in {max_side}x{max_side} texels"),
        )
    })?;
    let charts = charts
        .into_iter()
        .zip(places)
        .map(|(mut c, (x, y))| {
            c.rect.x = x;
            c.rect.y = y;
            c
        })
        .collect();
    Ok(Atlas {
        width,
        height,
        thickness_nm,
        charts,
    })
}

/// The slices' images on `atlas`: slice 0 the smooth film (the smooth
/// atlas's texels where a chart kept its size, else evaluated exactly), the
/// others from `tables`.
fn images(
    req: &SliceRequest,
    filler: &Filler,
    tables: &[Table],
    smooth_charts: &[Chart],
    atlas: &Atlas,
) -> Result<Vec<Image>> {
    let mut slices = vec![Image::new(atlas.width, atlas.height, 3); tables.len() + 1];
    for (chart, smooth) in atlas.charts.iter().zip(smooth_charts) {
        let r = chart.rect;
        let zero: Vec<[f64; 3]> = if (r.width, r.height) == (smooth.rect.width, smooth.rect.height)
        {
            smooth_values(req, std::slice::from_ref(smooth)).remove(0)
        } else {
            req.film
                .chart(chart, r.width, r.height)?
                .into_iter()
                .map(|v| [v[0], v[1], v[2]])
                .collect()
        };
        let put = |img: &mut Image, values: &[[f64; 3]]| {
            for (k, v) in values.iter().enumerate() {
                let t = img.texel_mut(r.x + k % r.width, r.y + k / r.width);
                for ch in 0..3 {
                    t[ch] = v[ch] as f32;
                }
            }
        };
        put(&mut slices[0], &zero);
        let stencils = filler.chart_stencils(chart);
        let rest: Vec<Vec<[f64; 3]>> = tables
            .par_iter()
            .map(|t| filler.values(t, &stencils))
            .collect();
        for (img, values) in slices[1..].iter_mut().zip(rest) {
            put(img, &values);
        }
    }
    Ok(slices)
}

/// The dense thickness grid over every node's thickness and the film's
/// smooth colour on it × the quadrature's μ nodes.
fn dense_grid(
    stack: &Stack,
    layer: usize,
    integrator: &SpectralIntegrator,
    nodes: &[(f64, f64)],
    grid: &MuGrid,
) -> Result<Dense> {
    let (lo, hi) = nodes
        .iter()
        .map(|n| n.0)
        .fold((f64::INFINITY, 0.0f64), |(a, b), d| (a.min(d), b.max(d)));
    let index = stack
        .layers
        .get(layer.wrapping_sub(1))
        .and_then(|l| l.material.index_at(550.0).ok())
        .map_or(1.0, |n| n.re.max(1.0));
    let period = SHORTEST_WAVELENGTH_NM / (2.0 * index);
    let span = hi - lo;
    let step = (FINEST_SPACING_NM / THICKNESS_SCALE_NM)
        .min(period / INTERVALS_PER_FRINGE / (span + THICKNESS_SCALE_NM));
    let (count, step) = if span > 1e-9 {
        let w = (span / THICKNESS_SCALE_NM).ln_1p();
        let n = (w / step).ceil() as usize;
        (n + 1, w / n as f64)
    } else {
        (1, 1.0)
    };
    let thickness: Vec<f64> = (0..count)
        .map(|k| lo + THICKNESS_SCALE_NM * (k as f64 * step).exp_m1())
        .collect();
    let mus = grid.nodes().len();
    crate::limits::check_allocation(
        &format!("F_eff over {count} thicknesses x {mus} μ nodes"),
        crate::limits::product(&[count as u64, mus as u64], 72),
    )?;
    // μ-major rows of thickness × RGB, as the weighing reads them.
    let values = rgb_at_nodes(stack, layer, integrator.clone(), &thickness, grid.nodes())?
        .into_iter()
        .flat_map(|v| [v[0], v[1], v[2]])
        .collect();
    Ok(Dense {
        lo_nm: lo,
        step,
        count,
        values,
    })
}

/// Random cosines of the measurement below [`GRAZING_COS`].
const GRAZING_AXIS_POINTS: usize = 6;

/// The slices against [`rough_reflectance`] (see [`measure_sampler`]).
fn measure(
    stack: &Stack,
    layer: usize,
    integrator: &SpectralIntegrator,
    slices: &RoughSlices,
) -> Result<(SliceError, SliceError)> {
    measure_sampler(
        stack,
        layer,
        integrator,
        (slices.atlas.thickness_nm, cos_span(&slices.atlas)),
        MEASURE_SEED,
        &|d, c, r| slices.sample(d, c, r),
    )
}

/// The cos θ range the side-0 charts of `atlas` serve (a corner from 0).
pub fn cos_span(atlas: &Atlas) -> (f64, f64) {
    atlas
        .charts
        .iter()
        .filter(|c| c.side == Side::Front)
        .map(|c| match c.coords {
            Coords::Band { c, .. } => (c.lo, c.hi),
            Coords::Corner { radius, .. } => (0.0, radius.min(1.0)),
        })
        .fold((1.0f64, 0.0f64), |(lo, hi), (a, b)| (lo.min(a), hi.max(b)))
}

/// `sample` (F_eff at thickness nm, cos θ, roughness) against
/// [`rough_reflectance`] of the film `stack` (layer `layer` varying) at
/// every combination of [`MEASURE_THICKNESSES`] random thicknesses and
/// [`MEASURE_AXIS_POINTS`] random cosines (≥ [`GRAZING_COS`]) and
/// roughnesses, over `domain` (the thickness and the cos θ range), drawn
/// from the PCG64 stream of `seed`; then with [`GRAZING_AXIS_POINTS`]
/// cosines below [`GRAZING_COS`] where the range reaches there.
pub fn measure_sampler(
    stack: &Stack,
    layer: usize,
    integrator: &SpectralIntegrator,
    domain: ((f64, f64), (f64, f64)),
    seed: u64,
    sample: &(dyn Fn(f64, f64, f64) -> [f64; 3] + Sync),
) -> Result<(SliceError, SliceError)> {
    let points = MeasurePoints::draw(
        domain,
        seed,
        [
            MEASURE_THICKNESSES,
            MEASURE_AXIS_POINTS,
            GRAZING_AXIS_POINTS,
        ],
    );
    if points.all_cos().is_empty() {
        return Ok((SliceError::default(), SliceError::default()));
    }
    let reference = Reference::new(stack, layer, integrator, &points)?;
    Ok(reference.errors(sample))
}

/// Random points of a rough measurement: every combination of the
/// thicknesses, the cosines (at or above [`GRAZING_COS`], then below) and
/// the roughnesses; as f64, or as f32 where they are what a shader gets.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasurePoints<T = f64> {
    /// Thicknesses (nm), ascending, distinct.
    pub thickness: Vec<T>,
    /// cos θ at or above [`GRAZING_COS`], ascending.
    pub cos: Vec<T>,
    /// cos θ below [`GRAZING_COS`], ascending.
    pub grazing_cos: Vec<T>,
    /// Roughnesses, ascending.
    pub roughness: Vec<T>,
}

impl<T: Copy> MeasurePoints<T> {
    /// Every cosine: `cos`, then `grazing_cos`.
    pub fn all_cos(&self) -> Vec<T> {
        self.cos.iter().chain(&self.grazing_cos).copied().collect()
    }
}

impl MeasurePoints {
    /// `[thicknesses, cosines and roughnesses, grazing cosines]` values
    /// uniform over `domain` (thickness nm, cos θ), roughness over [0, 1],
    /// from the PCG64 stream of `seed`, drawn in the order thicknesses,
    /// cosines, roughnesses, grazing cosines; no cosines at or above [`GRAZING_COS`] when the range
    /// stays below it, none below when it stays above.
    pub fn draw(domain: ((f64, f64), (f64, f64)), seed: u64, counts: [usize; 3]) -> MeasurePoints {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let ((t0, t1), (c0, c1)) = domain;
        let [n_thickness, n_axis, n_grazing] = counts;
        let mut draw = |lo: f64, hi: f64, n: usize| -> Vec<f64> {
            let mut v: Vec<f64> = (0..n)
                .map(|_| lo + rng.random::<f64>() * (hi - lo))
                .collect();
            v.sort_by(f64::total_cmp);
            v.dedup();
            v
        };
        let thickness = draw(t0, t1, n_thickness);
        let cos = if c1 > GRAZING_COS {
            draw(c0.max(GRAZING_COS), c1, n_axis)
        } else {
            Vec::new()
        };
        let roughness = draw(0.0, 1.0, n_axis);
        let grazing_cos = if c0 < GRAZING_COS {
            draw(c0, c1.min(GRAZING_COS), n_grazing)
        } else {
            Vec::new()
        };
        MeasurePoints {
            thickness,
            cos,
            grazing_cos,
            roughness,
        }
    }
}

/// F_eff from [`rough_reflectance`] (default quadrature) at every point of
/// a [`MeasurePoints`]: what slices and the textures made of them are
/// measured against, computed once.
#[derive(Clone, Debug)]
pub struct Reference {
    /// The points' axes and F_eff at each (`cos_theta`: the points'
    /// [`MeasurePoints::all_cos`]).
    pub exact: RoughTable,
    /// How many of `exact.cos_theta` are at or above [`GRAZING_COS`].
    pub main_cos: usize,
}

impl Reference {
    /// F_eff of the film `stack` (layer `layer` varying) at `points`.
    pub fn new(
        stack: &Stack,
        layer: usize,
        integrator: &SpectralIntegrator,
        points: &MeasurePoints,
    ) -> Result<Reference> {
        let exact = rough_reflectance(
            stack,
            layer,
            integrator,
            &points.thickness,
            &points.all_cos(),
            &points.roughness,
            &Quadrature::default(),
        )?;
        Ok(Reference {
            exact,
            main_cos: points.cos.len(),
        })
    }

    /// `sample` (F_eff at thickness nm, cos θ, roughness) against the
    /// reference: over the cosines at or above [`GRAZING_COS`], and over
    /// those below (no points when there are none).
    pub fn errors(
        &self,
        sample: &(dyn Fn(f64, f64, f64) -> [f64; 3] + Sync),
    ) -> (SliceError, SliceError) {
        let e = &self.exact;
        let errors_over = |cs: std::ops::Range<usize>| -> SliceError {
            let errors: Vec<([f64; 3], f64, [f64; 3])> = e
                .roughness
                .par_iter()
                .enumerate()
                .flat_map_iter(|(r, &rv)| {
                    cs.clone().flat_map(move |c| {
                        e.thickness_nm.iter().enumerate().map(move |(t, &tv)| {
                            let cv = e.cos_theta[c];
                            let want = e.at(t, c, r);
                            let got = sample(tv, cv, rv);
                            let abs = std::array::from_fn(|k| (got[k] - want[k]).abs());
                            (abs, delta_e2000_rgb(got, want), [tv, cv, rv])
                        })
                    })
                })
                .collect();
            summarize(&errors)
        };
        (
            errors_over(0..self.main_cos),
            errors_over(self.main_cos..e.cos_theta.len()),
        )
    }
}

/// The figures of per-point errors (absolute error per channel, ΔE00,
/// the point): a NaN (a lookup gone wrong) counts as the worst.
pub(crate) fn summarize(errors: &[([f64; 3], f64, [f64; 3])]) -> SliceError {
    let n = errors.len();
    if n == 0 {
        return SliceError::default();
    }
    let mut out = SliceError {
        points: n,
        ..SliceError::default()
    };
    let finite = |x: f64| if x.is_nan() { f64::INFINITY } else { x };
    for k in 0..3 {
        let mut e: Vec<f64> = errors.iter().map(|x| finite(x.0[k])).collect();
        e.sort_by(f64::total_cmp);
        out.max_abs[k] = e[n - 1];
        out.p99_abs[k] = e[((n as f64 * 0.99).ceil() as usize).clamp(1, n) - 1];
        out.mean_abs[k] = e.iter().sum::<f64>() / n as f64;
    }
    out.max_delta_e00 = errors.iter().fold(0.0f64, |a, x| a.max(finite(x.1)));
    out.mean_delta_e00 = errors.iter().map(|x| finite(x.1)).sum::<f64>() / n as f64;
    let worst = |x: &[f64; 3]| x.iter().fold(0.0f64, |a, &b| a.max(finite(b)));
    out.worst_point = errors
        .iter()
        .max_by(|a, b| worst(&a.0).total_cmp(&worst(&b.0)))
        .map_or([0.0; 3], |x| x.2);
    out
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
