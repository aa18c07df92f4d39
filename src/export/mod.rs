//! GPU-ready tables: a stack's reflectance and transmittance on texel grids
//! that hardware bilinear filtering reads correctly, chosen so that what the
//! GPU computes (bilinear, f16 texels) meets an error target, with the
//! shaders that read them. `irid export` writes the result; the file set and
//! the shader interface are specified in `docs/gpu.md`.
//!
//! An export is an atlas ([`Atlas`]): one chart per side of the film that
//! light can arrive from. The front chart holds the stack as written, cos θ
//! in the ambient; the back chart, present whenever the substrate is
//! lossless over the spectrum, the reversed stack, cos θ in the substrate
//! (with total internal reflection beyond a dense substrate's critical
//! angle). A stack that reads the same from both sides has one chart for
//! both. Each chart's axes are uniform in its chart coordinates: thickness
//! linearly or quadratically, cos θ through a closed-form warp
//! ([`Mapping`]) that puts a node exactly on a dense side's critical angle
//! and crowds nodes quadratically towards it, so the square-root kink of R
//! there becomes a corner on a node.

mod atlas;
mod files;
mod mapping;
mod measure;
mod rough;
mod search;

pub use atlas::{
    side_index, Atlas, Chart, RowCheck, Texture, CHART_PARAM_NAMES, CHART_VEC4, GUTTER, MAX_CHARTS,
    MAX_SIZE, UNIFORM_VEC4,
};
pub use files::{declare_dir, fill_dir, film_json, write_dir, FILM_FORMAT, FILM_VERSION};
pub use mapping::{AngleWarp, Mapping};
pub use measure::{measurement_points, ExportError, DEFAULT_POINTS, POINTS_SEED};
pub use rough::{
    rough_exact_at, rough_measurement_axes, RoughError, RoughExport, ROUGH_AXIS_POINTS, ROUGH_SEED,
    ROUGH_SHADERS, ROUGH_VEC4,
};
pub use search::{F16_MAX, LASING_BOUND};

use rayon::prelude::*;

use crate::color::refine::Refinement;
use crate::color::{Sampling, SpectralIntegrator, White};
use crate::error::{Error, Result};
use crate::optics::{Stack, StackGrid};
pub use crate::render::Side;
use search::{SideSearch, SizedChart};

/// The shaders, as committed in `shaders/` (the GLSL and HLSL forms are
/// generated from the WGSL by `cargo run -p irid-gpu --bin gen-shaders`).
pub const SHADERS: [(&str, &str); 4] = [
    (
        "irid_film.wgsl",
        include_str!("../../shaders/irid_film.wgsl"),
    ),
    (
        "irid_film.glsl",
        include_str!("../../shaders/irid_film.glsl"),
    ),
    (
        "irid_film_es.glsl",
        include_str!("../../shaders/irid_film_es.glsl"),
    ),
    (
        "irid_film.hlsl",
        include_str!("../../shaders/irid_film.hlsl"),
    ),
];

/// What to export.
#[derive(Clone, Debug, PartialEq)]
pub struct ExportSpec {
    /// The stack to export, as seen from its ambient.
    pub stack: Stack,
    /// The layer whose thickness is the u axis, from 1 at the ambient side
    /// (ignored for a stack without layers).
    pub layer: usize,
    /// The thickness range (nm) of the u axis.
    pub thickness_nm: (f64, f64),
    /// cos θ in the medium light arrives from (the ambient for the front
    /// side, the substrate for the back side).
    pub cos_theta: (f64, f64),
    /// Spectral integration.
    pub sampling: Sampling,
    /// What (1, 1, 1) is (docs/color.md).
    pub white: White,
    /// The largest absolute error allowed in any channel of what the GPU
    /// computes (bilinear filtering of f16 texels), at every measured point.
    pub max_error: f64,
    /// The back side's own target, when it is to differ (`None`: `max_error`).
    pub back_max_error: Option<f64>,
    /// Export the front side only, even when light can arrive from the
    /// substrate.
    pub front_only: bool,
    /// Random points at which that error is measured against the solver.
    pub points: usize,
    /// Also write 16-bit PNGs (and measure their quantization).
    pub png: bool,
    /// Also export the front side's rough reflectance (docs/gpu.md), with
    /// this error target; `None`: no rough table.
    pub rough_max_error: Option<f64>,
}

impl ExportSpec {
    /// The defaults of `irid export`: layer 1 over its own thickness, cos θ
    /// from cos 89° to 1, exact integration, D65, 1e-3 on both sides,
    /// 20 000 points.
    pub fn new(stack: Stack) -> ExportSpec {
        let t = stack.layers.first().map_or(0.0, |l| l.thickness_nm);
        ExportSpec {
            stack,
            layer: 1,
            thickness_nm: (t, t),
            cos_theta: (crate::lut::DEFAULT_COS_MIN, 1.0),
            sampling: Sampling::Exact,
            white: White::D65,
            max_error: 1e-3,
            back_max_error: None,
            front_only: false,
            points: DEFAULT_POINTS,
            png: false,
            rough_max_error: None,
        }
    }

    /// Checks ranges and the stack; errors name the offending option.
    pub fn validate(&self) -> Result<()> {
        crate::lut::check_film_domain(&self.stack, self.layer, self.thickness_nm, self.cos_theta)?;
        check_target("max-error", self.max_error)?;
        if let Some(e) = self.back_max_error {
            check_target("back-max-error", e)?;
        }
        if let Some(e) = self.rough_max_error {
            check_target("rough-max-error", e)?;
        }
        if !(1..=crate::lut::MAX_VALIDATION_POINTS).contains(&self.points) {
            return Err(Error::invalid(
                "points",
                format!(
                    "must be between 1 and {}, got {}",
                    crate::lut::MAX_VALIDATION_POINTS,
                    self.points
                ),
            ));
        }
        Ok(())
    }

    /// The spec of the film seen from `side`: for the back, the reversed
    /// stack, whose varying layer counts from the substrate.
    pub fn seen_from(&self, side: Side) -> ExportSpec {
        match side {
            Side::Front => self.clone(),
            Side::Back => {
                let n = self.stack.layers.len();
                ExportSpec {
                    stack: self.stack.reversed(),
                    layer: if n == 0 {
                        self.layer
                    } else {
                        n + 1 - self.layer
                    },
                    ..self.clone()
                }
            }
        }
    }

    /// The error target of `side`.
    pub fn target(&self, side: Side) -> f64 {
        match side {
            Side::Front => self.max_error,
            Side::Back => self.back_max_error.unwrap_or(self.max_error),
        }
    }

    /// Whether the substrate absorbs at some wavelength of the spectral
    /// sampling: light transmitted into it is absorbed, none arrives from
    /// it, and the film is opaque.
    pub fn substrate_absorbs(&self) -> Result<bool> {
        let integrator = SpectralIntegrator::with_white(self.sampling, self.white);
        for &nm in integrator.wavelengths_nm() {
            if self.stack.substrate.index_at(nm)?.im != 0.0 {
                return Ok(true);
            }
        }
        Ok(false)
    }
}

/// Half a unit in the last place of f16 just below 1.
const F16_HALF_ULP_AT_ONE: f64 = 1.0 / 4096.0;

/// An error target: positive, finite, and one f16 texels can meet.
fn check_target(option: &str, target: f64) -> Result<()> {
    if !(target > 0.0 && target.is_finite()) {
        return Err(Error::invalid(
            option,
            format!("must be a positive number, got {target}"),
        ));
    }
    // f16 rounds a value near 1 by up to 2^-12: below twice that no grid
    // of f16 texels can promise the target for a film that reflects or
    // transmits nearly everything somewhere.
    if target < 2.0 * F16_HALF_ULP_AT_ONE {
        return Err(Error::invalid(
            option,
            format!(
                "{target} cannot be met with f16 texels, which round values near 1 by up to {F16_HALF_ULP_AT_ONE:.2e}; use at least 5e-4"
            ),
        ));
    }
    Ok(())
}

/// One side of a finished export: which chart serves it and its error.
#[derive(Clone, Debug)]
pub struct SideExport {
    /// Which side.
    pub side: Side,
    /// The chart its lookups read.
    pub chart: usize,
    /// What the GPU computes (bilinear with f32 weights on f16 texels)
    /// against the exact solver on the stack seen from this side.
    pub error: ExportError,
    /// The most a filter with 1/256 weight steps adds to `error.max_abs`:
    /// the largest neighbouring-texel step of its chart / 256.
    pub weights_8bit_extra: f64,
    /// The error through the 16-bit PNGs, when asked for.
    pub png_error: Option<ExportError>,
}

/// A finished export: the atlas, its two textures, and each side's error.
#[derive(Clone, Debug)]
pub struct Export {
    /// What was exported.
    pub spec: ExportSpec,
    /// The charts and where (thickness, cos θ) lands in them.
    pub atlas: Atlas,
    /// The reflectance texture: f16 values (held in f32), RGBA with A = 1.
    pub reflectance: Texture,
    /// The transmittance texture, likewise.
    pub transmittance: Texture,
    /// The front side, then the back side when light can arrive from the
    /// substrate (and `front_only` was not asked).
    pub sides: Vec<SideExport>,
    /// The 16-bit PNGs' scale (texel = PNG value / 65535 × scale), when
    /// asked for.
    pub png_scale: Option<f64>,
    /// True when no light leaves through the substrate: the substrate
    /// absorbs somewhere in the spectrum (the transmittance texture then
    /// holds the power absorbed in it), or the transmittance is zero
    /// everywhere.
    pub opaque: bool,
    /// The front side's rough reflectance over roughness slices, when
    /// `spec.rough_max_error` asks for it.
    pub rough: Option<RoughExport>,
}

impl Export {
    /// `irid_film` as a GPU computes it from the f16 textures: R and T for
    /// light arriving from `side`.
    pub fn sample(&self, thickness_nm: f32, cos_theta: f32, side: Side) -> ([f32; 3], [f32; 3]) {
        let chart = self.atlas.chart_of(side);
        let uv = self.atlas.uv(chart, thickness_nm, cos_theta);
        let r = self.reflectance.sample_bilinear(uv);
        let t = self.transmittance.sample_bilinear(uv);
        ([r[0], r[1], r[2]], [t[0], t[1], t[2]])
    }

    /// The export's record of `side`, if it has that side.
    pub fn side(&self, side: Side) -> Option<&SideExport> {
        self.sides.iter().find(|s| s.side == side)
    }
}

/// The stack with everything fixed for the whole export, seen from one side.
struct Film {
    /// A layerless stack gets a zero-thickness layer of the ambient, which
    /// changes nothing optically.
    stack: Stack,
    layer: usize,
    grid: StackGrid,
    integrator: SpectralIntegrator,
    /// More points per nanometre where the film's fringes are narrower
    /// than the integration's step.
    refinement: Refinement,
}

impl Film {
    fn new(spec: &ExportSpec) -> Result<Film> {
        let (stack, layer) = crate::lut::with_varying_layer(&spec.stack, spec.layer);
        let integrator = SpectralIntegrator::with_white(spec.sampling, spec.white);
        let grid = StackGrid::new(&stack, integrator.wavelengths_nm())?;
        let refinement = Refinement::new(&stack, Some(layer), &integrator)?;
        Ok(Film {
            refinement,
            stack,
            layer,
            grid,
            integrator,
        })
    }

    /// Exact RGB of R and T at every node of `mapping`, row-major (row =
    /// cos θ node), six values per node: the baker's sweep on the
    /// mapping's nodes.
    fn eval(&self, mapping: &Mapping) -> Result<Vec<[f64; 6]>> {
        crate::lut::rgb_at_nodes(
            &self.stack,
            self.layer,
            self.integrator.clone(),
            &mapping.thickness_nodes(),
            &mapping.cos_nodes(),
        )
    }

    /// Exact RGB of R and T at each (thickness, cos θ) point: its whole
    /// spectrum through the batched solver, integrated as it is solved
    /// (with more points per nanometre where the film's fringes need them).
    fn exact_at(&self, points: &[[f32; 2]]) -> Result<Vec<[f64; 6]>> {
        let weights = self.integrator.rgb_lane_weights();
        points
            .par_iter()
            .map_init(
                || self.grid.thicknesses_nm().to_vec(),
                |thick, p| {
                    thick[self.layer - 1] = f64::from(p[0]);
                    let sums = self.refinement.weighted_spectrum(
                        &self.grid,
                        &weights,
                        thick,
                        f64::from(p[1]),
                    )?;
                    let (r, t) = (sums.reflectance, sums.transmittance);
                    Ok([r[0], r[1], r[2], t[0], t[1], t[2]])
                },
            )
            .collect()
    }
}

/// The substrate's critical cos θ at 550 nm, when the stack is seen from
/// its dense side (a lossless substrate optically thinner than the
/// ambient): R has a square-root kink there.
pub fn critical_cos(stack: &Stack) -> Option<f64> {
    match (
        stack.ambient.index_at(550.0),
        stack.substrate.index_at(550.0),
    ) {
        (Ok(n0), Ok(ns)) if ns.im == 0.0 && ns.re < n0.re => {
            Some((1.0 - (ns.re / n0.re).powi(2)).sqrt())
        }
        _ => None,
    }
}

/// The exact RGB reflectance and transmittance (R.r, R.g, R.b, T.r, T.g,
/// T.b, in the spec's white and sampling) of light arriving from `side` at
/// each point, from irid's solver: what an export is measured against.
pub fn exact_at(spec: &ExportSpec, side: Side, points: &[[f32; 2]]) -> Result<Vec<[f64; 6]>> {
    spec.validate()?;
    Film::new(&spec.seen_from(side))?.exact_at(points)
}

/// One chart being sized: the sides it serves, the stack as seen from the
/// first of them, and its grid.
struct ChartWork {
    sides: Vec<Side>,
    spec: ExportSpec,
    film: Film,
    sized: SizedChart,
}

impl ChartWork {
    /// The search of the chart's first side, against `target`.
    fn search(&self, target: f64) -> SideSearch<'_> {
        SideSearch {
            film: &self.film,
            spec: &self.spec,
            side: self.sides[0],
            target,
        }
    }
}

/// Chooses for each side the chart size that meets its target as the GPU
/// computes it, packs the charts into one atlas, bakes it and measures each
/// side through it (see the module docs). `progress` receives one line per
/// size tried.
pub fn export(spec: &ExportSpec, progress: &dyn Fn(&str)) -> Result<Export> {
    spec.validate()?;
    let absorbs = spec.substrate_absorbs()?;
    let mut plan: Vec<(Vec<Side>, ExportSpec)> = vec![(vec![Side::Front], spec.clone())];
    if !absorbs && !spec.front_only {
        let seen = spec.seen_from(Side::Back);
        if seen.stack == spec.stack && seen.layer == spec.layer {
            // The stack reads the same from both sides: one chart serves both.
            plan[0].0.push(Side::Back);
        } else {
            plan.push((vec![Side::Back], seen));
        }
    }
    let mut charts: Vec<ChartWork> = Vec::new();
    for (sides, seen) in plan {
        let film = Film::new(&seen)?;
        let sized = SideSearch {
            film: &film,
            spec: &seen,
            side: sides[0],
            target: chart_target(spec, &sides),
        }
        .size(None, progress)
        .map_err(|e| on_side(sides[0], e))?;
        charts.push(ChartWork {
            sides,
            spec: seen,
            film,
            sized,
        });
    }
    for _round in 0..search::MAX_ROUNDS {
        let atlas = Atlas::pack(
            charts
                .iter()
                .map(|c| (c.sides.clone(), c.sized.mapping))
                .collect(),
        )?;
        let nodes: Vec<&[[f64; 6]]> = charts.iter().map(|c| c.sized.nodes.as_slice()).collect();
        let (reflectance, transmittance) = atlas.textures(&nodes);
        let mut sides = Vec::new();
        let mut regrow = None;
        for (k, chart) in charts.iter().enumerate() {
            let error = chart
                .sized
                .reference
                .measure(|t, c| search::sample(&atlas, &reflectance, &transmittance, k, t, c));
            let rect = atlas.charts[k].rect();
            let step = reflectance
                .max_neighbour_step(rect)
                .max(transmittance.max_neighbour_step(rect));
            for &side in &chart.sides {
                if error.max_all() > spec.target(side) {
                    regrow = Some((k, error.max_all() / spec.target(side)));
                }
                sides.push(SideExport {
                    side,
                    chart: k,
                    error: error.clone(),
                    weights_8bit_extra: f64::from(step) / 256.0,
                    png_error: None,
                });
            }
        }
        if let Some((k, excess)) = regrow {
            // Packing moved the chart's texel coordinates by a rounding:
            // grow it a little and search on from there.
            regrow_chart(&mut charts[k], spec, excess, progress)?;
            continue;
        }
        sides.sort_by_key(|s| side_index(s.side));
        let opaque = absorbs
            || charts[0]
                .sized
                .nodes
                .iter()
                .all(|v| v[3..].iter().all(|&x| atlas::to_f16(x) == 0.0));
        let mut export = Export {
            spec: spec.clone(),
            atlas,
            reflectance,
            transmittance,
            sides,
            png_scale: None,
            opaque,
            rough: None,
        };
        if spec.png {
            png_errors(&mut export, &charts);
        }
        if let Some(target) = spec.rough_max_error {
            let front = export.atlas.charts[export.atlas.chart_of(Side::Front)].mapping;
            export.rough = Some(rough::rough_export(spec, front, target, progress)?);
        }
        return Ok(export);
    }
    Err(Error::invalid(
        "max-error",
        "the charts' errors through the atlas do not settle below the target",
    ))
}

/// Grows a chart whose error through the atlas exceeds its target by the
/// ratio `excess`, and sizes it again from there.
fn regrow_chart(
    chart: &mut ChartWork,
    spec: &ExportSpec,
    excess: f64,
    progress: &dyn Fn(&str),
) -> Result<()> {
    let m = chart.sized.mapping;
    let g = search::growth_for_measured(excess, 1.0);
    let flat = (
        spec.thickness_nm.0 == spec.thickness_nm.1,
        spec.cos_theta.0 == spec.cos_theta.1,
    );
    let start = m.resized(
        search::grown(m.size_u, g, flat.0),
        search::grown(m.size_v, g, flat.1),
    );
    chart.sized = chart
        .search(chart_target(spec, &chart.sides))
        .size(Some(start), progress)
        .map_err(|e| on_side(chart.sides[0], e))?;
    Ok(())
}

/// The target of a chart: the strictest of its sides'.
fn chart_target(spec: &ExportSpec, sides: &[Side]) -> f64 {
    sides
        .iter()
        .map(|&s| spec.target(s))
        .fold(f64::INFINITY, f64::min)
}

/// A back side's failure says which side failed and how to do without it.
fn on_side(side: Side, e: Error) -> Error {
    match side {
        Side::Front => e,
        Side::Back => Error::invalid(
            "back side (light from the substrate)",
            format!(
                "{e}; --back-max-error sets this side's own target, --front-only leaves it out"
            ),
        ),
    }
}

/// The 16-bit PNGs' scale and each side's error through them.
fn png_errors(export: &mut Export, charts: &[ChartWork]) {
    let scale = files::png_scale(export);
    let (r, t) = files::png_textures(export, scale);
    for side in &mut export.sides {
        let reference = &charts[side.chart].sized.reference;
        side.png_error = Some(
            reference.measure(|th, c| search::sample(&export.atlas, &r, &t, side.chart, th, c)),
        );
    }
    export.png_scale = Some(scale);
}
