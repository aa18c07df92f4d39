//! The rough table of an export: the front side's pre-integrated rough
//! reflectance F_eff (docs/rough.md; light from the ambient) over
//! thickness × cos θ_v × roughness, as an atlas of roughness slices in one
//! RGBA16F texture, read by `irid_film_rough` (shaders/irid_film_rough.wgsl).
//!
//! Slice s holds F_eff at roughness (s / (S − 1))² (S slices, uniform in
//! √roughness, so the shader maps roughness to a slice in closed form) on
//! the nodes of the front chart's own [`Mapping`] (same thickness and cos θ
//! warps, grown only if the slices' own error asks for it), each slice a
//! rectangle inside a gutter of edge copies, the slices in rows of
//! `columns`. The shader does one bilinear fetch in each of the two slices
//! around the roughness and blends them linearly. Slice 0 (roughness 0) is
//! the smooth film's reflectance, computed by the same sweep as the front
//! chart. The slice count is chosen, like the smooth charts' sizes, so that
//! what the GPU computes meets an error target against `irid::rough` at
//! random points.

use rand::{Rng, SeedableRng};
use rayon::prelude::*;

use super::mapping::{chart_xy, AngleWarp, Mapping};
use super::texture::{to_f16, Texture};
use super::{critical_cos, ExportSpec, F16_MAX, MAX_SIZE};
use crate::color::{delta_e2000_rgb, SpectralIntegrator};
use crate::error::{Error, Result};
use crate::optics::Stack;
use crate::rough::{rough_reflectance, Quadrature, RoughTable};

/// vec4 in the rough uniform array (docs/gpu.md): the texture size, slice
/// count and columns; the slices' mapping (two vec4); the slice size and
/// pitch.
pub const ROUGH_VEC4: usize = 4;
/// Random values per axis of the rough error measurement: the points are
/// every combination of that many thicknesses, cosines and roughnesses.
pub const ROUGH_AXIS_POINTS: usize = 40;
/// The seed of the rough measurement's PCG64 stream.
pub const ROUGH_SEED: u64 = 29;
/// Slices of the first size tried.
const START_SLICES: usize = 5;
/// The most slices: beyond, a film's F_eff is no smooth function of
/// roughness a linear blend can follow.
const MAX_SLICES: usize = 257;
/// Rounds of the size search before it gives up.
const MAX_ROUNDS: usize = 8;
/// Texels of edge copies around every slice.
const GUTTER: usize = 1;
/// The slices' first grid: thickness × cos θ nodes.
const START_GRID: (usize, usize) = (257, 65);

/// The growth of both axes when the random points measure `measured`
/// above `target` though every midpoint met it: a feature between them.
fn growth_for_measured(measured: f64, target: f64) -> f64 {
    ((measured / target).sqrt() * 1.1).clamp(1.15, 2.0)
}

/// A new axis size: `n` grown by `factor` (by at least one texel when
/// growing), 1 for a flat axis.
fn grown(n: usize, factor: f64, flat: bool) -> usize {
    if flat {
        return 1;
    }
    if factor <= 1.0 {
        return n;
    }
    let intervals = ((n - 1) as f64 * factor).ceil() as usize;
    (intervals + 1).max(n + 1)
}

/// The slices' first mapping: thickness nodes crowding quadratically
/// towards the thinnest, cos θ nodes towards grazing incidence or a
/// critical angle.
fn start_mapping(spec: &ExportSpec) -> Mapping {
    let flat = |(a, b): (f64, f64), n: usize| if a == b { 1 } else { n };
    let angle = match critical_cos(&spec.stack) {
        Some(c) => AngleWarp::Critical(c),
        None => AngleWarp::Grazing,
    };
    Mapping::new(
        spec.thickness_nm,
        spec.cos_theta,
        2.0,
        angle,
        flat(spec.thickness_nm, START_GRID.0),
        flat(spec.cos_theta, START_GRID.1),
    )
}

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

/// Error of what the GPU computes from the rough table against
/// `irid::rough` (default quadrature), per RGB channel of F_eff.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughError {
    /// Largest absolute error per channel.
    pub max_abs: [f64; 3],
    /// 99th percentile of the absolute error per channel.
    pub p99_abs: [f64; 3],
    /// Mean absolute error per channel.
    pub mean_abs: [f64; 3],
    /// Largest and mean CIEDE2000 of the colour.
    pub max_delta_e00: f64,
    /// See `max_delta_e00`.
    pub mean_delta_e00: f64,
    /// How many points were measured.
    pub points: usize,
    /// The PCG64 seed of the points.
    pub seed: u64,
    /// (thickness nm, cos θ, roughness) of the largest error.
    pub worst_point: [f64; 3],
}

impl RoughError {
    /// The largest of `max_abs`.
    pub fn max_all(&self) -> f64 {
        self.max_abs.iter().fold(0.0, |a, &b| a.max(b))
    }
}

/// A finished rough table.
#[derive(Clone, Debug)]
pub struct RoughExport {
    /// Every slice's thickness × cos θ nodes and their closed-form map.
    pub mapping: Mapping,
    /// Slices, at roughness (s / (slices − 1))².
    pub slices: usize,
    /// Slices per row of the texture.
    pub columns: usize,
    /// F_eff as f16 values (held in f32), RGBA with A = 1.
    pub texture: Texture,
    /// The error target it was sized for.
    pub target: f64,
    /// What the GPU computes against `irid::rough`.
    pub error: RoughError,
    /// The quadrature F_eff was computed with.
    pub quadrature: Quadrature,
    uniform: Vec<f32>,
}

impl RoughExport {
    /// The roughness of every slice.
    pub fn roughness_nodes(&self) -> Vec<f64> {
        roughness_nodes(self.slices)
    }

    /// `[x0, y0, width, height]` of slice `s` in texels, gutter excluded.
    pub fn slice_rect(&self, s: usize) -> [usize; 4] {
        let [pitch_x, pitch_y] = pitch(&self.mapping);
        [
            GUTTER + (s % self.columns) * pitch_x,
            GUTTER + (s / self.columns) * pitch_y,
            self.mapping.size_u,
            self.mapping.size_v,
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
        let params: &[f32; 8] = v[4..12].try_into().expect("eight mapping parameters");
        let [x, y] = chart_xy(params, thickness_nm, cos_theta);
        let n = v[2];
        let s = roughness.clamp(0.0, 1.0).sqrt() * (n - 1.0);
        let s0 = s.floor().min(n - 2.0);
        let w = s - s0;
        let uv = |slice: f32| {
            let row = ((slice + 0.5) / v[3]).floor();
            let column = slice - row * v[3];
            let origin = [column * v[14] + v[11], row * v[15] + v[11]];
            [
                ((origin[0] + 0.5) + x * (v[12] - 1.0)) / v[0],
                ((origin[1] + 0.5) + y * (v[13] - 1.0)) / v[1],
            ]
        };
        let a = self.texture.sample_bilinear(uv(s0));
        let b = self.texture.sample_bilinear(uv(s0 + 1.0));
        std::array::from_fn(|k| a[k] * (1.0 - w) + b[k] * w)
    }
}

/// Roughness 0 to 1 at `slices` nodes uniform in √roughness: slice s
/// holds roughness (s / (slices − 1))². F_eff changes fastest with
/// roughness where the lobe starts to wash the film's fringes out (a few
/// hundredths for thick films) and ever more slowly above; the square puts
/// the nodes where the linear blend needs them (on the soap film 0–1000 nm
/// it needs about half the slices of uniform steps).
fn roughness_nodes(slices: usize) -> Vec<f64> {
    (0..slices)
        .map(|s| (s as f64 / (slices - 1) as f64).powi(2))
        .collect()
}

/// Texels from one slice's first node to the next one's, along x and y.
fn pitch(mapping: &Mapping) -> [usize; 2] {
    [mapping.size_u + 2 * GUTTER, mapping.size_v + 2 * GUTTER]
}

/// The front side's film as the rough engine takes it.
struct RoughFilm {
    stack: Stack,
    layer: usize,
    integrator: SpectralIntegrator,
}

impl RoughFilm {
    fn table(&self, thickness: &[f64], cos: &[f64], roughness: &[f64]) -> Result<RoughTable> {
        rough_reflectance(
            &self.stack,
            self.layer,
            &self.integrator,
            thickness,
            cos,
            roughness,
            &Quadrature::default(),
        )
    }
}

/// The random points of the rough measurement: every combination of
/// [`ROUGH_AXIS_POINTS`] thicknesses, cosines and roughnesses, each drawn
/// uniform over its range (roughness [0, 1]) from a PCG64 stream seeded
/// with [`ROUGH_SEED`], as f32 (what a shader gets); thicknesses ascending
/// and distinct.
pub fn rough_measurement_axes(spec: &ExportSpec) -> [Vec<f32>; 3] {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(ROUGH_SEED);
    let mut axis = |(lo, hi): (f64, f64)| -> Vec<f32> {
        (0..ROUGH_AXIS_POINTS)
            .map(|_| (lo + rng.random::<f64>() * (hi - lo)) as f32)
            .collect()
    };
    let mut thickness = axis(spec.thickness_nm);
    let cos = axis(spec.cos_theta);
    let roughness = axis((0.0, 1.0));
    thickness.sort_by(f32::total_cmp);
    thickness.dedup();
    [thickness, cos, roughness]
}

/// F_eff from `irid::rough` at every combination of `axes` (as
/// [`rough_measurement_axes`] gives them): what the rough table is
/// measured against.
pub fn rough_exact_at(spec: &ExportSpec, axes: &[Vec<f32>; 3]) -> Result<RoughTable> {
    spec.validate()?;
    let film = rough_film(spec);
    let [t, c, r] = axes
        .each_ref()
        .map(|a| a.iter().map(|&v| f64::from(v)).collect::<Vec<_>>());
    film.table(&t, &c, &r)
}

fn rough_film(spec: &ExportSpec) -> RoughFilm {
    let (stack, layer) = crate::lut::with_varying_layer(&spec.stack, spec.layer);
    RoughFilm {
        stack,
        layer,
        integrator: SpectralIntegrator::with_white(spec.sampling, spec.white),
    }
}

/// The random points and F_eff at each.
struct Reference {
    axes: [Vec<f32>; 3],
    exact: RoughTable,
}

impl Reference {
    fn measure(&self, rough: &RoughExport) -> RoughError {
        let [t, c, r] = &self.axes;
        let errors: Vec<([f64; 3], f64, [f64; 3])> = (0..r.len())
            .into_par_iter()
            .flat_map_iter(|k| (0..c.len()).flat_map(move |j| (0..t.len()).map(move |i| (i, j, k))))
            .map(|(i, j, k)| {
                let got = rough.sample(t[i], c[j], r[k]).map(f64::from);
                let exact = self.exact.at(i, j, k);
                let abs = std::array::from_fn(|n| (got[n] - exact[n]).abs());
                let point = [t[i], c[j], r[k]].map(f64::from);
                (abs, delta_e2000_rgb(got, exact), point)
            })
            .collect();
        summarize(&errors)
    }
}

fn summarize(errors: &[([f64; 3], f64, [f64; 3])]) -> RoughError {
    let n = errors.len();
    let mut out = RoughError {
        max_abs: [0.0; 3],
        p99_abs: [0.0; 3],
        mean_abs: [0.0; 3],
        max_delta_e00: 0.0,
        mean_delta_e00: 0.0,
        points: n,
        seed: ROUGH_SEED,
        worst_point: [0.0; 3],
    };
    for k in 0..3 {
        let mut e: Vec<f64> = errors.iter().map(|x| x.0[k]).collect();
        e.sort_by(f64::total_cmp);
        out.max_abs[k] = e[n - 1];
        out.p99_abs[k] = e[((n as f64 * 0.99).ceil() as usize).clamp(1, n) - 1];
        out.mean_abs[k] = e.iter().sum::<f64>() / n as f64;
    }
    // NaN (a colour the Lab conversion cannot take) counts as worst.
    out.max_delta_e00 = errors.iter().fold(0.0f64, |a, x| {
        if x.1.is_nan() {
            f64::INFINITY
        } else {
            a.max(x.1)
        }
    });
    out.mean_delta_e00 = errors.iter().map(|x| x.1).sum::<f64>() / n as f64;
    let worst = |x: &[f64; 3]| x.iter().fold(0.0f64, |a, &b| a.max(b));
    if let Some(w) = errors
        .iter()
        .max_by(|a, b| worst(&a.0).total_cmp(&worst(&b.0)))
    {
        out.worst_point = w.2;
    }
    out
}

/// Packs F_eff at the slices' nodes (`table`, one roughness node per
/// slice) into the texture and the uniform array.
fn pack(mapping: Mapping, table: &RoughTable, target: f64) -> Result<RoughExport> {
    let slices = table.roughness.len();
    let [pitch_x, pitch_y] = pitch(&mapping);
    let columns = (MAX_SIZE / pitch_x).clamp(1, slices);
    let rows = slices.div_ceil(columns);
    let (width, height) = (columns * pitch_x, rows * pitch_y);
    if width > MAX_SIZE || height > MAX_SIZE {
        return Err(Error::invalid(
            "rough-max-error",
            format!(
                "{slices} slices of {}×{} texels do not fit a {MAX_SIZE}×{MAX_SIZE} texture; loosen the target or narrow --thickness or --angles",
                mapping.size_u, mapping.size_v
            ),
        ));
    }
    let mut rough = RoughExport {
        mapping,
        slices,
        columns,
        texture: Texture {
            width,
            height,
            texels: vec![[0.0, 0.0, 0.0, 1.0]; width * height],
        },
        target,
        error: summarize(&[([0.0; 3], 0.0, [0.0; 3])]),
        quadrature: Quadrature::default(),
        uniform: Vec::new(),
    };
    let (w, h) = (mapping.size_u, mapping.size_v);
    for s in 0..slices {
        let [x0, y0, _, _] = rough.slice_rect(s);
        for y in y0 - GUTTER..y0 + h + GUTTER {
            for x in x0 - GUTTER..x0 + w + GUTTER {
                let i = (x.max(x0) - x0).min(w - 1);
                let j = (y.max(y0) - y0).min(h - 1);
                let v = table.at(i, j, s);
                rough.texture.texels[y * width + x] =
                    [to_f16(v[0]), to_f16(v[1]), to_f16(v[2]), 1.0];
            }
        }
    }
    let p = mapping.params_f32();
    rough.uniform = vec![
        width as f32,
        height as f32,
        slices as f32,
        columns as f32,
        p[0],
        p[1],
        p[2],
        p[3],
        p[4],
        p[5],
        p[6],
        GUTTER as f32,
        w as f32,
        h as f32,
        pitch_x as f32,
        pitch_y as f32,
    ];
    Ok(rough)
}

/// The largest error of a linear blend between every other slice of
/// `table` (its odd roughness nodes against the mean of their neighbours).
fn midpoint_error(table: &RoughTable) -> f64 {
    let n_r = table.roughness.len();
    let per_slice = table.thickness_nm.len() * table.cos_theta.len();
    (1..n_r)
        .step_by(2)
        .flat_map(|k| (0..per_slice).map(move |i| (k, i)))
        .map(|(k, i)| {
            let at = |r: usize| table.reflectance[r * per_slice + i];
            let (a, m, b) = (at(k - 1), at(k), at(k + 1));
            (0..3).fold(0.0f64, |e, n| e.max((m[n] - 0.5 * (a[n] + b[n])).abs()))
        })
        .fold(0.0, f64::max)
}

/// Fails when F_eff is not finite or beyond f16 somewhere.
fn check_representable(table: &RoughTable) -> Result<()> {
    match table
        .reflectance
        .iter()
        .position(|v| v.iter().any(|x| !x.is_finite() || x.abs() > F16_MAX))
    {
        None => Ok(()),
        Some(_) => Err(Error::invalid(
            "rough",
            format!("F_eff is not finite or exceeds the f16 range ({F16_MAX}) somewhere"),
        )),
    }
}

/// Sizes, bakes and measures the rough table of `spec`'s front side
/// against `target`. `progress` receives one line per size tried.
pub(super) fn rough_export(
    spec: &ExportSpec,
    target: f64,
    progress: &dyn Fn(&str),
) -> Result<RoughExport> {
    let mapping = start_mapping(spec);
    let film = rough_film(spec);
    let axes = rough_measurement_axes(spec);
    let exact = rough_exact_at(spec, &axes)?;
    let reference = Reference { axes, exact };
    let flat = (
        spec.thickness_nm.0 == spec.thickness_nm.1,
        spec.cos_theta.0 == spec.cos_theta.1,
    );
    let (mut mapping, mut slices) = (mapping, START_SLICES);
    for _round in 0..MAX_ROUNDS {
        // Every other node of a table with twice the roughness intervals
        // tells how far the linear blend is from F_eff between slices.
        // On every other thickness and cos θ node, which is enough to see
        // how F_eff bends between slices at a quarter of the cost.
        let fine = roughness_nodes(2 * slices - 1);
        let every_other = |nodes: Vec<f64>| nodes.into_iter().step_by(2).collect::<Vec<_>>();
        let probe = film.table(
            &every_other(mapping.thickness_nodes()),
            &every_other(mapping.cos_nodes()),
            &fine,
        )?;
        check_representable(&probe)?;
        let e_r = midpoint_error(&probe);
        drop(probe);
        progress(&format!(
            "rough: {slices} slices of {}×{}: roughness midpoint error {e_r:.2e}",
            mapping.size_u, mapping.size_v
        ));
        // The random points decide; the midpoints only keep hopeless sizes
        // from being measured.
        if e_r > 0.75 * target {
            let grow = ((e_r / (0.75 * target)).sqrt() * 1.1).clamp(1.15, 4.0);
            slices = grown_slices(slices, grow)?;
            continue;
        }
        let nodes = roughness_nodes(slices);
        let table = film.table(&mapping.thickness_nodes(), &mapping.cos_nodes(), &nodes)?;
        check_representable(&table)?;
        let mut rough = pack(mapping, &table, target)?;
        rough.error = reference.measure(&rough);
        let measured = rough.error.max_all();
        progress(&format!(
            "rough: {slices} slices: {} random points, max error {measured:.2e}",
            rough.error.points
        ));
        if measured <= target {
            return Ok(rough);
        }
        let grow = growth_for_measured(measured, target);
        if e_r <= 0.25 * target {
            // The blend between slices is good: the slices' own grid is not.
            mapping = mapping.resized(
                grown(mapping.size_u, grow, flat.0),
                grown(mapping.size_v, grow, flat.1),
            );
        } else {
            slices = grown_slices(slices, grow)?;
        }
    }
    Err(Error::invalid(
        "rough-max-error",
        format!(
            "{target} is not reached within {MAX_ROUNDS} rounds of the rough table's size search"
        ),
    ))
}

fn grown_slices(slices: usize, factor: f64) -> Result<usize> {
    let intervals = ((slices - 1) as f64 * factor).ceil() as usize;
    if intervals + 1 > MAX_SLICES {
        return Err(Error::invalid(
            "rough-max-error",
            format!("the target needs more than {MAX_SLICES} roughness slices"),
        ));
    }
    Ok(intervals + 1)
}

/// The rough texture's file in the export folder.
pub const ROUGH_FILE: &str = "rough.exr";

/// Writes the rough texture and its shaders into the export's temporary
/// folder.
pub(super) fn fill(rough: &RoughExport, tmp: &std::path::Path) -> Result<()> {
    super::files::write_exr(&rough.texture, &tmp.join(ROUGH_FILE))?;
    super::files::write_texts(tmp, &ROUGH_SHADERS)
}

/// film.json's `rough`: the texture, its slice layout (named and as the
/// uniform array), the nodes, and the error against `irid::rough`.
pub(super) fn rough_json(rough: &RoughExport) -> serde_json::Value {
    let m = &rough.mapping;
    let e = &rough.error;
    let q = &rough.quadrature;
    serde_json::json!({
        "texture": {
            "file": ROUGH_FILE,
            "width": rough.texture.width,
            "height": rough.texture.height,
            "format": "rgba16f",
        },
        "light_from": "ambient",
        "quantity": "F_eff: reflectance pre-integrated over a GGX lobe (docs/rough.md), linear RGB in the export's white",
        "layout": {
            "slices": rough.slices,
            "columns": rough.columns,
            "roughness": "slice s holds roughness (s / (slices - 1))^2; irid_film_rough finds the slice position sqrt(roughness) * (slices - 1) and blends the two slices around it linearly",
            "slice_size": [m.size_u, m.size_v],
            "pitch": [m.size_u + 2 * GUTTER, m.size_v + 2 * GUTTER],
            "gutter": GUTTER,
            "slice_rects": (0..rough.slices).map(|s| rough.slice_rect(s)).collect::<Vec<_>>(),
            "params": {
                "thickness_min_nm": m.thickness_min_nm,
                "thickness_max_nm": m.thickness_max_nm,
                "cos_min": m.cos_min,
                "cos_max": m.cos_max,
                "cos_crit": m.cos_crit,
                "y_crit": m.y_crit,
                "thickness_power": m.thickness_power,
            },
        },
        "nodes": {
            "thickness_nm": m.thickness_nodes(),
            "cos_theta": m.cos_nodes(),
            "roughness": rough.roughness_nodes(),
        },
        "quadrature": {
            "mu_intervals": q.mu_intervals,
            "outer_points_per_panel": q.outer,
            "azimuth_points": q.inner,
        },
        "uniform_f32": rough.uniform_f32(),
        "uniform_vec4": ROUGH_VEC4,
        "error": {
            "channels": ["F_eff.r", "F_eff.g", "F_eff.b"],
            "metric": "absolute difference between irid_film_rough as the GPU computes it (bilinear with f32 weights, clamp to edge, f16 texels, linear blend of two slices) and irid::rough's F_eff (default quadrature) at every combination of random thicknesses, cosines and roughnesses, each uniform over its range",
            "target_max_abs": rough.target,
            "max_abs": e.max_abs,
            "p99_abs": e.p99_abs,
            "mean_abs": e.mean_abs,
            "max_delta_e00": e.max_delta_e00,
            "mean_delta_e00": e.mean_delta_e00,
            "points": e.points,
            "axis_points": ROUGH_AXIS_POINTS,
            "seed": e.seed,
            "worst_point": e.worst_point,
        },
        "shaders": ROUGH_SHADERS.iter().map(|(name, _)| *name).collect::<Vec<_>>(),
    })
}
