//! The rough table of an export: the front side's pre-integrated rough
//! reflectance F_eff (docs/rough.md; light from the ambient) over
//! thickness × cos θ_v × roughness, read by `irid_film_rough`
//! (shaders/irid_film_rough.wgsl; docs/gpu.md).
//!
//! [`crate::rough::slices`] computes it: S roughness slices (slice s at
//! roughness (s / (S − 1))²), each an image of one atlas, the front side's
//! charts packed on their own (grown where F_eff needs more nodes than the
//! smooth film). The export tiles the S images into one RGBA16F texture,
//! slice s at its own rectangle inside a gutter of edge copies, and gives
//! the reader the rough atlas's uniform array behind two vec4 of tiling
//! numbers: the chart lookup is the smooth atlas's (the same generated
//! shader code), plus the slice's offset in the texture. What the GPU then
//! computes (f32 coordinates, f16 texels, bilinear filter, linear blend of
//! two slices) is measured against `irid::rough` at random points; cos θ
//! below [`GRAZING_COS`] is measured and stated apart.

use super::texture::{to_f16, Texture};
use super::{ExportSpec, F16_MAX, MAX_SIZE};
use crate::atlas::{locate_f32, Atlas, Film, Image};
use crate::color::SpectralIntegrator;
use crate::error::{Error, Result};
use crate::rough::slices::{self, MeasurePoints, Reference, RoughSlices, SliceRequest};
use crate::rough::{rough_reflectance, Quadrature, RoughTable};
use crate::stats::RoughFigures;
use crate::sweep::Side;

pub use crate::rough::slices::GRAZING_COS;

/// vec4 of tiling numbers before the rough atlas's own uniform array:
/// (texture width, height, slices, columns), (pitch x, pitch y, gutter, 0).
pub const TILING_VEC4: usize = 2;
/// The f32 of the rough uniform array before the rough atlas's own.
const ATLAS_OFFSET_F32: usize = 4 * TILING_VEC4;
/// The rough uniform array's length in vec4: the tiling numbers and the
/// rough atlas's [`crate::atlas::UNIFORM_VEC4`].
pub const ROUGH_VEC4: usize = TILING_VEC4 + crate::atlas::UNIFORM_VEC4;
/// Random values per axis of the rough error measurement: the points are
/// every combination of that many thicknesses, cosines (≥ [`GRAZING_COS`])
/// and roughnesses.
pub const ROUGH_AXIS_POINTS: usize = 40;
/// Random cosines below [`GRAZING_COS`] of the grazing strip's measurement.
pub const ROUGH_GRAZING_POINTS: usize = 10;
/// The seed of the rough measurement's PCG64 stream.
pub const ROUGH_SEED: u64 = 29;
/// Texels of edge copies around every slice.
const GUTTER: usize = 1;
/// Builds of the slices before the size search gives up: a build that meets
/// its target in f64 but not through the f16 texture is rebuilt once for a
/// tighter one.
const MAX_BUILDS: usize = 2;

/// The shader of the rough table, as committed in `shaders/` (the GLSL and
/// HLSL forms generated from the WGSL by `cargo run -p irid-gpu --bin
/// gen-shaders`).
pub const ROUGH_SHADERS: [(&str, &str); 4] = [
    (
        "irid_film_rough.wgsl",
        include_str!("../../shaders/irid_film_rough.wgsl"),
    ),
    (
        "irid_film_rough.glsl",
        include_str!("../../shaders/irid_film_rough.glsl"),
    ),
    (
        "irid_film_rough_es.glsl",
        include_str!("../../shaders/irid_film_rough_es.glsl"),
    ),
    (
        "irid_film_rough.hlsl",
        include_str!("../../shaders/irid_film_rough.hlsl"),
    ),
];

/// A finished rough table.
#[derive(Clone, Debug)]
pub struct RoughExport {
    /// The rough atlas: the front side's charts, packed on their own; every
    /// slice is an image of it.
    pub atlas: Atlas,
    /// Slices, at roughness (s / (slices − 1))².
    pub slices: usize,
    /// Slices per row of the texture.
    pub columns: usize,
    /// F_eff as f16 values (held in f32), RGBA with A = 1.
    pub texture: Texture,
    /// The error target it was sized for.
    pub target: f64,
    /// What the GPU computes against `irid::rough` at cos θ ≥
    /// [`GRAZING_COS`]: what the target is met over.
    pub error: RoughFigures,
    /// The same at cos θ below [`GRAZING_COS`] (none when the export's
    /// angles do not reach there).
    pub grazing_error: Option<RoughFigures>,
    /// The quadrature F_eff was computed with.
    pub quadrature: Quadrature,
    uniform: Vec<f32>,
}

impl RoughExport {
    /// The roughness of every slice.
    pub fn roughness_nodes(&self) -> Vec<f64> {
        (0..self.slices)
            .map(|s| slices::slice_roughness(s, self.slices))
            .collect()
    }

    /// `[x0, y0, width, height]` of slice `s` in texels, gutter excluded:
    /// the rough atlas's image, its texel (x, y) at (x0 + x, y0 + y).
    pub fn slice_rect(&self, s: usize) -> [usize; 4] {
        let [pitch_x, pitch_y] = pitch(&self.atlas);
        [
            GUTTER + (s % self.columns) * pitch_x,
            GUTTER + (s / self.columns) * pitch_y,
            self.atlas.width,
            self.atlas.height,
        ]
    }

    /// The uniform array `irid_film_rough` reads ([`ROUGH_VEC4`] vec4):
    /// film.json's `rough.uniform_f32`.
    pub fn uniform_f32(&self) -> &[f32] {
        &self.uniform
    }

    /// `irid_film_rough` as a GPU computes it from the f16 texture, operation
    /// for operation in f32: F_eff at (thickness, cos θ, roughness).
    pub fn sample(&self, thickness_nm: f32, cos_theta: f32, roughness: f32) -> [f32; 3] {
        let v = &self.uniform;
        let Some(texel) = locate_f32(&v[ATLAS_OFFSET_F32..], thickness_nm, cos_theta, Side::Front)
        else {
            return [0.0; 3];
        };
        let n = v[2];
        let s = roughness.clamp(0.0, 1.0).sqrt() * (n - 1.0);
        let s0 = s.floor().min(n - 2.0);
        let w = s - s0;
        let uv = |slice: f32| {
            let row = ((slice + 0.5) / v[3]).floor();
            let column = slice - row * v[3];
            let origin = [column * v[4] + v[6], row * v[5] + v[6]];
            [(origin[0] + texel[0]) / v[0], (origin[1] + texel[1]) / v[1]]
        };
        let a = self.texture.sample_bilinear(uv(s0));
        let b = self.texture.sample_bilinear(uv(s0 + 1.0));
        std::array::from_fn(|k| a[k] * (1.0 - w) + b[k] * w)
    }
}

/// Texels from one slice's first texel to the next one's, along x and y.
fn pitch(atlas: &Atlas) -> [usize; 2] {
    [atlas.width + 2 * GUTTER, atlas.height + 2 * GUTTER]
}

/// The random points of the rough measurement, as f32 (what a shader
/// gets), each uniform over its range from a PCG64 stream seeded with
/// [`ROUGH_SEED`]: [`ROUGH_AXIS_POINTS`] thicknesses (ascending, distinct),
/// cosines over the export's angles at or above [`GRAZING_COS`] and
/// roughnesses over [0, 1]; and [`ROUGH_GRAZING_POINTS`] cosines of the
/// export's angles below [`GRAZING_COS`] (none when they do not reach
/// there).
pub type RoughPoints = MeasurePoints<f32>;

impl MeasurePoints<f32> {
    /// The points of `spec`'s rough measurement.
    pub fn of(spec: &ExportSpec) -> RoughPoints {
        let drawn = MeasurePoints::draw(
            (spec.thickness_nm, spec.cos_theta),
            ROUGH_SEED,
            [ROUGH_AXIS_POINTS, ROUGH_AXIS_POINTS, ROUGH_GRAZING_POINTS],
        );
        let f32s = |v: &[f64]| v.iter().map(|&x| x as f32).collect::<Vec<f32>>();
        let mut thickness = f32s(&drawn.thickness);
        thickness.dedup();
        let mut grazing_cos = f32s(&drawn.grazing_cos);
        grazing_cos.retain(|&c| f64::from(c) < GRAZING_COS);
        MeasurePoints {
            thickness,
            cos: f32s(&drawn.cos),
            grazing_cos,
            roughness: f32s(&drawn.roughness),
        }
    }
}

/// F_eff from `irid::rough` at every combination of `points`' thicknesses,
/// cosines ([`RoughPoints::all_cos`]) and roughnesses: what the rough
/// table is measured against.
pub fn rough_exact_at(spec: &ExportSpec, points: &RoughPoints) -> Result<RoughTable> {
    spec.validate()?;
    let film = super::film_of(spec)?;
    let f64s = |a: &[f32]| a.iter().map(|&v| f64::from(v)).collect::<Vec<_>>();
    rough_reflectance(
        film.stack(),
        film.layer(),
        &SpectralIntegrator::with_white(spec.sampling, spec.white),
        &f64s(&points.thickness),
        &f64s(&points.all_cos()),
        &f64s(&points.roughness),
        &Quadrature::default(),
    )
}

/// What `rough` gives against `reference`: over the cosines at or above
/// [`GRAZING_COS`], and over those below (`None` when there are none).
fn measure(reference: &Reference, rough: &RoughExport) -> (RoughFigures, Option<RoughFigures>) {
    let (main, grazing) =
        reference.errors(&|t, c, r| rough.sample(t as f32, c as f32, r as f32).map(f64::from));
    let with_seed = |e: RoughFigures| RoughFigures {
        seed: Some(ROUGH_SEED),
        ..e
    };
    let grazing = (grazing.points > 0).then(|| with_seed(grazing));
    (with_seed(main), grazing)
}

/// The slices per row for `slices` slices of `pitch` texels: the fewest
/// texels in all (then the shorter longest side) among the tilings that fit
/// a [`MAX_SIZE`] square texture.
fn columns_for(slices: usize, [pitch_x, pitch_y]: [usize; 2]) -> Option<usize> {
    (1..=slices)
        .filter(|&c| c * pitch_x <= MAX_SIZE && slices.div_ceil(c) * pitch_y <= MAX_SIZE)
        .min_by_key(|&c| {
            let (w, h) = (c * pitch_x, slices.div_ceil(c) * pitch_y);
            (w * h, w.max(h))
        })
}

/// Tiles the slices' images into the texture (f16 values, A = 1, each
/// slice inside a gutter of its own edge texels) and fills the uniform
/// array.
fn pack(built: &RoughSlices, target: f64) -> Result<RoughExport> {
    let atlas = built.atlas.clone();
    let slices = built.slices.len();
    let [pitch_x, pitch_y] = pitch(&atlas);
    let columns = columns_for(slices, [pitch_x, pitch_y]).ok_or_else(|| {
        Error::invalid(
            "rough-max-error",
            format!(
                "{slices} slices of {}×{} texels do not fit a {MAX_SIZE}×{MAX_SIZE} texture; loosen the target or narrow --thickness or --angles",
                atlas.width, atlas.height
            ),
        )
    })?;
    let (width, height) = (columns * pitch_x, slices.div_ceil(columns) * pitch_y);
    let mut rough = RoughExport {
        atlas,
        slices,
        columns,
        texture: Texture {
            width,
            height,
            texels: vec![[0.0, 0.0, 0.0, 1.0]; width * height],
        },
        target,
        error: RoughFigures::default(),
        grazing_error: None,
        quadrature: Quadrature::default(),
        uniform: Vec::new(),
    };
    for (s, image) in built.slices.iter().enumerate() {
        let rect = rough.slice_rect(s);
        put_slice(&mut rough.texture, rect, image);
    }
    let mut uniform = vec![
        width as f32,
        height as f32,
        slices as f32,
        columns as f32,
        pitch_x as f32,
        pitch_y as f32,
        GUTTER as f32,
        0.0,
    ];
    uniform.extend(rough.atlas.uniform_f32());
    debug_assert_eq!(uniform.len(), 4 * ROUGH_VEC4);
    rough.uniform = uniform;
    Ok(rough)
}

/// Writes `image` at `[x0, y0, w, h]` of `texture`, f16-rounded, with a
/// [`GUTTER`] of copies of its edge texels around it.
fn put_slice(texture: &mut Texture, [x0, y0, w, h]: [usize; 4], image: &Image) {
    for y in y0 - GUTTER..y0 + h + GUTTER {
        let j = (y.max(y0) - y0).min(h - 1);
        for x in x0 - GUTTER..x0 + w + GUTTER {
            let i = (x.max(x0) - x0).min(w - 1);
            let v = image.texel(i, j);
            texture.texels[y * texture.width + x] = [
                to_f16(f64::from(v[0])),
                to_f16(f64::from(v[1])),
                to_f16(f64::from(v[2])),
                1.0,
            ];
        }
    }
}

/// Fails when F_eff is not finite or beyond f16 somewhere.
fn check_representable(built: &RoughSlices) -> Result<()> {
    let bad = |x: &f32| !x.is_finite() || f64::from(x.abs()) > F16_MAX;
    if built.slices.iter().any(|i| i.data.iter().any(bad)) {
        return Err(Error::invalid(
            "rough",
            format!("F_eff is not finite or exceeds the f16 range ({F16_MAX}) somewhere"),
        ));
    }
    Ok(())
}

/// What the rough table is built from: the front side's film and its
/// smooth atlas (charts and texels, R first).
pub(super) struct RoughSource<'a> {
    pub film: &'a Film,
    pub atlas: &'a Atlas,
    pub image: &'a Image,
}

/// Builds the rough table of `spec`'s front side for `target`, tiles it
/// and measures it through the f16 texture. `progress` receives one line
/// per stage.
pub(super) fn rough_export(
    spec: &ExportSpec,
    source: &RoughSource,
    target: f64,
    progress: &dyn Fn(&str),
) -> Result<RoughExport> {
    let start = std::time::Instant::now();
    let integrator = SpectralIntegrator::with_white(spec.sampling, spec.white);
    let points = RoughPoints::of(spec);
    let reference = Reference {
        exact: rough_exact_at(spec, &points)?,
        main_cos: points.cos.len(),
    };
    progress(&format!(
        "rough: F_eff at the measurement's points ({:.1} s)",
        start.elapsed().as_secs_f64()
    ));
    let mut asked = target;
    for build in 1..=MAX_BUILDS {
        let request = SliceRequest {
            film: source.film,
            atlas: source.atlas,
            image: source.image,
            max_error: asked,
            max_side: MAX_SIZE - 2 * GUTTER,
            reference: Some(&reference),
        };
        let built = slices::build(
            source.film.stack(),
            source.film.layer(),
            &integrator,
            &request,
            progress,
        )?;
        check_representable(&built)?;
        let mut rough = pack(&built, target)?;
        (rough.error, rough.grazing_error) = measure(&reference, &rough);
        let measured = rough.error.max_all();
        progress(&format!(
            "rough: {} slices tiled into {}×{} texels; through f16 at {} random points: max {measured:.2e} (target {target:.1e}) ({:.1} s)",
            rough.slices,
            rough.texture.width,
            rough.texture.height,
            rough.error.points,
            start.elapsed().as_secs_f64()
        ));
        if measured <= target {
            return Ok(rough);
        }
        if build == MAX_BUILDS {
            let w = rough.error.worst_point;
            return Err(Error::invalid(
                "rough-max-error",
                format!(
                    "the rough table is off by {measured:.2e} through its f16 texture at thickness {:.1} nm, cos θ {:.4}, roughness {:.3}, above the target {target:.1e}",
                    w[0], w[1], w[2]
                ),
            ));
        }
        // f16 rounding took the rest: ask the slices for the margin.
        asked *= (target / measured).min(0.9);
    }
    unreachable!("the loop returns on its last build")
}

/// The rough texture's file in the export folder.
pub const ROUGH_FILE: &str = "rough.exr";

/// Writes the rough texture and its shaders into the export's temporary
/// folder.
pub(super) fn fill(rough: &RoughExport, tmp: &std::path::Path) -> Result<()> {
    super::files::write_exr(&rough.texture, &tmp.join(ROUGH_FILE))?;
    super::files::write_texts(tmp, &ROUGH_SHADERS)
}

/// film.json's `rough`: the texture, its tiling, the rough atlas's charts
/// (as film.json's `charts`), the uniform array, the nodes, and the error
/// against `irid::rough`.
pub(super) fn rough_json(rough: &RoughExport) -> serde_json::Value {
    let q = &rough.quadrature;
    let [pitch_x, pitch_y] = pitch(&rough.atlas);
    let mut error = super::files::error_json(&rough.error);
    error["channels"] = serde_json::json!(["F_eff.r", "F_eff.g", "F_eff.b"]);
    error["metric"] = serde_json::json!(
        "absolute difference between irid_film_rough as the GPU computes it (f32 texture coordinates, bilinear with f32 weights, clamp to edge, f16 texels, linear blend of two slices) and irid::rough's F_eff (default quadrature) at every combination of random thicknesses, cosines at or above grazing_below_cos and roughnesses, each uniform over its range; grazing: the same with random cosines below grazing_below_cos, where the target is not sought (null when the export's angles do not reach there)"
    );
    error["target_max_abs"] = serde_json::json!(rough.target);
    error["axis_points"] = serde_json::json!(ROUGH_AXIS_POINTS);
    error["grazing_below_cos"] = serde_json::json!(GRAZING_COS);
    error["grazing"] = rough.grazing_error.as_ref().map_or(
        serde_json::Value::Null,
        super::files::error_json::<RoughFigures>,
    );
    serde_json::json!({
        "texture": {
            "file": ROUGH_FILE,
            "width": rough.texture.width,
            "height": rough.texture.height,
            "format": "rgba16f",
            "alpha": "1 everywhere: WebGPU has no 3-channel 16-bit float format (docs/gpu.md)",
            "row_check": super::files::row_check_json(&rough.texture),
        },
        "light_from": "ambient",
        "quantity": "F_eff: reflectance pre-integrated over a GGX lobe (docs/rough.md), linear RGB in the export's white",
        "slices": rough.slices,
        "roughness": "slice s holds roughness (s / (slices - 1))^2; irid_film_rough finds the slice position sqrt(roughness) * (slices - 1), clamped to [0, slices - 1], and blends the two slices around it linearly",
        "tiling": {
            "columns": rough.columns,
            "slice_size": [rough.atlas.width, rough.atlas.height],
            "pitch": [pitch_x, pitch_y],
            "gutter": GUTTER,
            "slice_rects": (0..rough.slices).map(|s| rough.slice_rect(s)).collect::<Vec<_>>(),
        },
        "atlas": {
            "width": rough.atlas.width,
            "height": rough.atlas.height,
            "thickness_nm": [rough.atlas.thickness_nm.0, rough.atlas.thickness_nm.1],
        },
        "charts": super::files::charts_json(&rough.atlas),
        "uniform_f32": rough.uniform_f32(),
        "uniform_vec4": ROUGH_VEC4,
        "atlas_uniform_offset_vec4": TILING_VEC4,
        "nodes": {
            "roughness": rough.roughness_nodes(),
        },
        "quadrature": {
            "mu_intervals": q.mu_intervals,
            "outer_points_per_panel": q.outer,
            "azimuth_points": q.inner,
        },
        "error": error,
        "shaders": ROUGH_SHADERS.iter().map(|(name, _)| *name).collect::<Vec<_>>(),
    })
}
