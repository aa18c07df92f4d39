//! GPU-ready tables: a stack's reflectance and transmittance in an atlas
//! of charts ([`crate::atlas`]) that hardware bilinear filtering reads,
//! sized so that what the GPU computes (f32 texture coordinates, f16
//! texels, bilinear filter) meets an error target, with the shaders that
//! read them. `irid export` writes the result; the file set and the shader
//! interface are specified in `docs/gpu.md`.
//!
//! The charts cover each side of the film light can arrive from: side 0
//! the stack as written, cos θ in the ambient; side 1, whenever the
//! substrate is lossless over the spectrum and the stack reads differently
//! from there, the reversed stack, cos θ in the substrate (with total
//! internal reflection beyond a dense substrate's critical angle). Both
//! sides' charts share one atlas; [`crate::atlas::search`] chooses them and
//! their sizes, and measures the packed, f16-rounded atlas against the
//! solver as the shader reads it.

mod files;
mod measure;
mod rough;
mod texture;

pub use crate::atlas::{Atlas, Chart, HEADER_VEC4, MAX_CHARTS, PARAMS_PER_CHART, UNIFORM_VEC4};
pub use files::{declare_dir, fill_dir, film_json, write_dir, FILM_FORMAT, FILM_VERSION};
pub use measure::{measurement_points, DEFAULT_POINTS, POINTS_SEED};
pub use rough::{
    rough_exact_at, RoughExport, RoughPoints, GRAZING_COS, ROUGH_AXIS_POINTS, ROUGH_GRAZING_POINTS,
    ROUGH_SEED, ROUGH_SHADERS, ROUGH_VEC4, TILING_VEC4,
};
pub use texture::{RowCheck, Texture};

use crate::atlas::search::{build, Goal, SideMeasurement, SideRequest};
use crate::atlas::Film;
use crate::color::{Sampling, SpectralIntegrator, White};
use crate::error::{Error, Result};
use crate::optics::Stack;
use crate::stats::{AtlasFigures, ColourFigures};
pub use crate::sweep::Side;

/// The largest texture side an atlas uses: WebGPU's default limit for 2D
/// textures, which desktop GPUs exceed.
pub const MAX_SIZE: usize = 8192;
/// The largest finite f16 value: a table holding more is not representable.
pub const F16_MAX: f64 = 65504.0;
pub use crate::atlas::LASING_BOUND;

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
    /// The defaults of `irid export`: layer 1 over its own thickness, every
    /// angle (cos θ 0 to 1), exact integration, D65, 1e-3 on both sides,
    /// 20 000 points.
    pub fn new(stack: Stack) -> ExportSpec {
        let t = stack.layers.first().map_or(0.0, |l| l.thickness_nm);
        ExportSpec {
            stack,
            layer: 1,
            thickness_nm: (t, t),
            cos_theta: (0.0, 1.0),
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
        crate::sweep::check_film_domain(
            &self.stack,
            self.layer,
            self.thickness_nm,
            self.cos_theta,
        )?;
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

/// One side of a finished export: the charts that serve it and its error.
#[derive(Clone, Debug)]
pub struct SideExport {
    /// Which side.
    pub side: Side,
    /// The charts its lookups read (indices into the atlas's charts).
    pub charts: Vec<usize>,
    /// cos θ below which the colour integration itself is aliased (the
    /// film's fringes are narrower than its wavelength steps): the target
    /// is not sought there, and its error is stated apart; 0 when nowhere.
    pub aliased_below: f64,
    /// What the GPU computes (f32 texture coordinates, bilinear with f32
    /// weights on f16 texels) against the exact solver on the stack seen
    /// from this side, over every measured point.
    pub error: ColourFigures,
    /// The same over the points below `aliased_below` (none when 0).
    pub aliased_error: Option<ColourFigures>,
    /// The cos θ band over which a dispersive ambient's critical angle
    /// moves (light from the denser side), where the target is not sought
    /// and its charts take a fixed budget of texels
    /// ([`crate::atlas::search::CRITICAL_BAND_TEXELS`]); none when the side
    /// has no such band.
    pub critical_band: Option<(f64, f64)>,
    /// The error over the measured points where the target is sought
    /// (above the aliased strip, outside the critical band), when the side
    /// has either.
    pub sought_error: Option<ColourFigures>,
    /// The error over points of the band's own
    /// ([`crate::atlas::search::CRITICAL_BAND_POINTS`], seed
    /// [`crate::atlas::search::CRITICAL_BAND_SEED`]), when it has one.
    pub critical_error: Option<ColourFigures>,
    /// The most a filter with 1/256 weight steps adds to `error.max_abs`:
    /// the largest neighbouring-texel step of its charts / 256.
    pub weights_8bit_extra: f64,
    /// The error through the 16-bit PNGs, when asked for.
    pub png_error: Option<ColourFigures>,
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
    uniform: Vec<f32>,
}

impl Export {
    /// `irid_film` as a GPU computes it from the f16 textures: R and T for
    /// light arriving from `side`.
    pub fn sample(&self, thickness_nm: f32, cos_theta: f32, side: Side) -> ([f32; 3], [f32; 3]) {
        match crate::atlas::locate_f32(&self.uniform, thickness_nm, cos_theta, side) {
            Some(t) => {
                let uv = [
                    t[0] / self.atlas.width as f32,
                    t[1] / self.atlas.height as f32,
                ];
                let r = self.reflectance.sample_bilinear(uv);
                let t = self.transmittance.sample_bilinear(uv);
                ([r[0], r[1], r[2]], [t[0], t[1], t[2]])
            }
            None => ([0.0; 3], [0.0; 3]),
        }
    }

    /// The uniform array the shaders read: [`Atlas::uniform_f32`].
    pub fn uniform_f32(&self) -> &[f32] {
        &self.uniform
    }

    /// The export's record of `side`, if it has that side.
    pub fn side(&self, side: Side) -> Option<&SideExport> {
        self.sides.iter().find(|s| s.side == side)
    }
}

/// The film seen from `spec`'s side (its stack and varying layer), with
/// everything fixed for evaluating it.
fn film_of(spec: &ExportSpec) -> Result<Film> {
    let integrator = SpectralIntegrator::with_white(spec.sampling, spec.white);
    Film::new(&spec.stack, spec.layer, integrator)
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
    let film = film_of(&spec.seen_from(side))?;
    film.points(
        &points
            .iter()
            .map(|p| (f64::from(p[0]), f64::from(p[1])))
            .collect::<Vec<_>>(),
    )
}

/// The sides that get charts of their own: the front, and the back unless
/// no light arrives from the substrate, `front_only` was asked, or the
/// stack reads the same from both sides (its back lookups read the front's
/// charts). Also whether the substrate absorbs.
fn charted_sides(spec: &ExportSpec) -> Result<(Vec<Side>, bool)> {
    let absorbs = spec.substrate_absorbs()?;
    let mut sides = vec![Side::Front];
    if !absorbs && !spec.front_only {
        let seen = spec.seen_from(Side::Back);
        if !(seen.stack == spec.stack && seen.layer == spec.layer) {
            sides.push(Side::Back);
        }
    }
    Ok((sides, absorbs))
}

/// Builds the atlas of every side that meets its target as the GPU
/// computes it (see the module docs), and measures each side through it.
/// `progress` receives one line per stage.
pub fn export(spec: &ExportSpec, progress: &dyn Fn(&str)) -> Result<Export> {
    spec.validate()?;
    let (charted, absorbs) = charted_sides(spec)?;
    let films = charted
        .iter()
        .map(|&side| film_of(&spec.seen_from(side)))
        .collect::<Result<Vec<_>>>()?;
    for film in &films {
        film.check_lasing(spec.thickness_nm, spec.cos_theta)?;
    }
    let requests = side_requests(spec, &charted, &films);
    let points = measurement_points(spec);
    let all_points = vec![points; requests.len()];
    let built = build(
        &requests,
        spec.thickness_nm,
        MAX_SIZE,
        &all_points,
        progress,
    )
    .map_err(|e| match charted.get(1) {
        // The back side's failure names how to do without it.
        Some(&Side::Back) if e.to_string().contains("side 1") => on_back_side(e),
        _ => e,
    })?;
    check_representable(spec, &built.image)?;
    // The rough table reads the front side's charts and texels.
    let rough = match spec.rough_max_error {
        Some(target) => {
            crate::rough::refuse_unsought_band(built.sides[0].unsought_band)?;
            let source = rough::RoughSource {
                film: &films[0],
                atlas: &built.atlas,
                image: &built.image,
            };
            Some(rough::rough_export(spec, &source, target, progress)?)
        }
        None => None,
    };
    let [reflectance, transmittance] = [0, 3].map(|at| Texture {
        width: built.image.width,
        height: built.image.height,
        texels: built
            .image
            .data
            .chunks_exact(6)
            .map(|v| [v[at], v[at + 1], v[at + 2], 1.0])
            .collect(),
    });
    let mut listed = vec![Side::Front];
    if !absorbs && !spec.front_only {
        listed.push(Side::Back);
    }
    let sides = listed
        .into_iter()
        .map(|side| side_export(side, &charted, &built, [&reflectance, &transmittance]))
        .collect();
    let opaque = absorbs
        || transmittance
            .texels
            .iter()
            .all(|t| t[..3].iter().all(|&x| x == 0.0));
    let atlas = built.atlas;
    let uniform = atlas.uniform_f32();
    let mut export = Export {
        spec: spec.clone(),
        atlas,
        reflectance,
        transmittance,
        sides,
        png_scale: None,
        opaque,
        rough,
        uniform,
    };
    if spec.png {
        png_errors(&mut export)?;
    }
    Ok(export)
}

/// What the atlas search is asked for each charted side.
fn side_requests<'a>(
    spec: &ExportSpec,
    charted: &[Side],
    films: &'a [Film],
) -> Vec<SideRequest<'a>> {
    charted
        .iter()
        .zip(films)
        .map(|(&side, film)| SideRequest {
            film,
            side,
            cos: spec.cos_theta,
            goal: Goal {
                max_abs: Some(spec.target(side)),
                max_de: None,
                half: true,
            },
        })
        .collect()
}

/// The record of `side` in the built atlas: its charts (a side without
/// charts of its own reads the front's, measured on its own stack: the
/// same stack, read from the other side), its errors and the 8-bit filter
/// bound over both `textures`.
fn side_export(
    side: Side,
    charted: &[Side],
    built: &crate::atlas::search::Built,
    textures: [&Texture; 2],
) -> SideExport {
    let own = charted.iter().position(|&s| s == side).unwrap_or(0);
    let m = &built.measured[own];
    let atlas = &built.atlas;
    let chart_side = charted[own];
    let charts: Vec<usize> = (0..atlas.charts.len())
        .filter(|&k| atlas.charts[k].side == chart_side)
        .collect();
    let step = charts
        .iter()
        .map(|&k| {
            let r = atlas.charts[k].rect;
            let rect = [r.x, r.y, r.width, r.height];
            textures
                .iter()
                .map(|t| t.max_neighbour_step(rect))
                .fold(0.0f32, f32::max)
        })
        .fold(0.0f32, f32::max);
    SideExport {
        side,
        charts,
        aliased_below: built.sides[own].aliased_below,
        error: export_error(&m.all),
        aliased_error: aliased_error(m),
        sought_error: (m.aliased.points > 0 || m.critical.points > 0)
            .then(|| export_error(&m.resolved)),
        critical_band: built.sides[own].unsought_band,
        critical_error: built.sides[own].unsought_band.map(|_| ColourFigures {
            seed: Some(crate::atlas::search::CRITICAL_BAND_SEED),
            ..export_error(&m.critical)
        }),
        weights_8bit_extra: f64::from(step) / 256.0,
        png_error: None,
    }
}

/// An export side's figures from the atlas search's measurement.
fn export_error(m: &AtlasFigures) -> ColourFigures {
    // An export's atlas holds R and T in RGB: six channels.
    let six = |v: &[f64]| -> [f64; 6] { std::array::from_fn(|k| v.get(k).copied().unwrap_or(0.0)) };
    ColourFigures {
        points: m.points,
        max_abs: six(&m.max_abs),
        p99_abs: six(&m.p99_abs),
        mean_abs: six(&m.mean_abs),
        max_delta_e00: m.max_delta_e00,
        mean_delta_e00: m.mean_delta_e00,
        seed: Some(POINTS_SEED),
        worst_point: m.worst_point,
    }
}

fn aliased_error(m: &SideMeasurement) -> Option<ColourFigures> {
    (m.aliased.points > 0).then(|| export_error(&m.aliased))
}

/// Fails when a texel is not finite or beyond f16, or, for a gain film,
/// beyond [`LASING_BOUND`] (its range reaches or crosses a lasing pole).
fn check_representable(spec: &ExportSpec, image: &crate::atlas::Image) -> Result<()> {
    let stack = &spec.stack;
    let gain = stack.layers.iter().any(|l| l.material.has_gain()) || stack.substrate.has_gain();
    let bound = if gain { LASING_BOUND } else { F16_MAX } as f32;
    if image.data.iter().all(|x| x.abs() <= bound) {
        return Ok(());
    }
    Err(if gain {
        Error::invalid(
            "gain film",
            format!("R or T exceeds {LASING_BOUND} or is not finite: the range reaches a lasing pole; narrow --thickness or --angles"),
        )
    } else {
        Error::invalid("export", "R or T is not finite or exceeds the f16 range")
    })
}

/// A back side's failure says which side failed and how to do without it.
fn on_back_side(e: Error) -> Error {
    Error::invalid(
        "back side (light from the substrate)",
        format!("{e}; --back-max-error sets this side's own target, --front-only leaves it out"),
    )
}

/// The 16-bit PNGs' scale and each side's error through them.
fn png_errors(export: &mut Export) -> Result<()> {
    let scale = files::png_scale(export);
    let (r, t) = files::png_textures(export, scale);
    let points = measurement_points(&export.spec);
    let through_png = Export {
        reflectance: r,
        transmittance: t,
        sides: Vec::new(),
        rough: None,
        ..export.clone()
    };
    for k in 0..export.sides.len() {
        let side = export.sides[k].side;
        let exact = exact_at(&export.spec, side, &points)?;
        let got: Vec<[f64; 6]> = points
            .iter()
            .map(|p| {
                let (r, t) = through_png.sample(p[0], p[1], side);
                [r[0], r[1], r[2], t[0], t[1], t[2]].map(f64::from)
            })
            .collect();
        let m = crate::atlas::search::figures(&points, &got.concat(), &exact.concat(), 6, true);
        export.sides[k].png_error = Some(export_error(&m));
    }
    export.png_scale = Some(scale);
    Ok(())
}
