//! GPU-ready tables: a stack's reflectance and transmittance on a texel grid
//! that hardware bilinear filtering reads correctly, chosen so that what the
//! GPU computes (bilinear, f16 texels) meets an error target, with the
//! shaders that read it. `irid export` writes the result; the file set and
//! the shader interface are specified in `docs/gpu.md`.
//!
//! The texture axes are uniform in the texture coordinates: thickness
//! linearly, cos θ through a closed-form warp ([`Mapping`]) that puts a node
//! exactly on a dense-side stack's critical angle and crowds nodes
//! quadratically towards it, so the square-root kink of R there becomes a
//! corner on a node.

mod files;
mod mapping;

pub use files::{declare_dir, fill_dir, write_dir, FILM_FORMAT, FILM_VERSION};
pub use mapping::{AngleWarp, Mapping, RowCheck, Texture, PARAM_NAMES};

use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::color::refine::Refinement;
use crate::color::{delta_e2000_rgb, Sampling, SpectralIntegrator, White};
use crate::error::{Error, Result};
use crate::optics::{Stack, StackGrid};

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

/// The largest texture side an export uses: WebGPU's default limit for 2D
/// textures, which desktop GPUs exceed.
pub const MAX_SIZE: usize = 8192;
/// The largest finite f16 value: a table holding more is not representable.
pub const F16_MAX: f64 = 65504.0;
/// The random points of the default error measurement.
pub const DEFAULT_POINTS: usize = 20_000;
/// The seed of the measurement's PCG64 stream.
pub const POINTS_SEED: u64 = 15;

/// What to export.
#[derive(Clone, Debug, PartialEq)]
pub struct ExportSpec {
    /// The stack to export.
    pub stack: Stack,
    /// The layer whose thickness is the u axis, from 1 at the ambient side
    /// (ignored for a stack without layers).
    pub layer: usize,
    /// The thickness range (nm) of the u axis.
    pub thickness_nm: (f64, f64),
    /// cos θ in the ambient.
    pub cos_theta: (f64, f64),
    /// Spectral integration.
    pub sampling: Sampling,
    /// What (1, 1, 1) is (docs/color.md).
    pub white: White,
    /// The largest absolute error allowed in any channel of what the GPU
    /// computes (bilinear filtering of f16 texels), at every measured point.
    pub max_error: f64,
    /// Random points at which that error is measured against the solver.
    pub points: usize,
    /// Also write 16-bit PNGs (and measure their quantization).
    pub png: bool,
}

impl ExportSpec {
    /// The defaults of `irid export`: layer 1 over its own thickness, cos θ
    /// from cos 89° to 1, exact integration, D65, 1e-3, 20 000 points.
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
            points: DEFAULT_POINTS,
            png: false,
        }
    }

    /// Checks ranges and the stack; errors name the offending option.
    pub fn validate(&self) -> Result<()> {
        crate::lut::check_film_domain(&self.stack, self.layer, self.thickness_nm, self.cos_theta)?;
        if !(self.max_error > 0.0 && self.max_error.is_finite()) {
            return Err(Error::invalid(
                "max-error",
                format!("must be a positive number, got {}", self.max_error),
            ));
        }
        // f16 rounds a value near 1 by up to 2^-12: below twice that no
        // grid of f16 texels can promise the target for a film that
        // reflects or transmits nearly everything somewhere.
        if self.max_error < 2.0 * F16_HALF_ULP_AT_ONE {
            return Err(Error::invalid(
                "max-error",
                format!(
                    "{} cannot be met with f16 texels, which round values near 1 by up to {:.2e}; use at least {:.0e}",
                    self.max_error,
                    F16_HALF_ULP_AT_ONE,
                    5e-4
                ),
            ));
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
}

/// Half a unit in the last place of f16 just below 1.
const F16_HALF_ULP_AT_ONE: f64 = 1.0 / 4096.0;

/// Error of what a GPU computes from the export against the exact solver,
/// at random points. `*_abs` arrays have six entries: R.r, R.g, R.b, T.r,
/// T.g, T.b; `*_delta_e00` two: reflectance and transmittance colour.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExportError {
    /// Largest absolute error per channel.
    pub max_abs: [f64; 6],
    /// 99th percentile of the absolute error per channel.
    pub p99_abs: [f64; 6],
    /// Mean absolute error per channel.
    pub mean_abs: [f64; 6],
    /// Largest CIEDE2000, reflected and transmitted colour.
    pub max_delta_e00: [f64; 2],
    /// Mean CIEDE2000, reflected and transmitted colour.
    pub mean_delta_e00: [f64; 2],
    /// How many points were measured.
    pub points: usize,
    /// The PCG64 seed of the points.
    pub seed: u64,
    /// (thickness nm, cos θ) of the largest error over channels.
    pub worst_point: [f64; 2],
}

impl ExportError {
    /// The largest of `max_abs`.
    pub fn max_all(&self) -> f64 {
        self.max_abs.iter().fold(0.0, |a, &b| a.max(b))
    }
}

/// A finished export: the two textures, their mapping and measured errors.
#[derive(Clone, Debug)]
pub struct Export {
    /// What was exported.
    pub spec: ExportSpec,
    /// Where (thickness, cos θ) lands in the textures.
    pub mapping: Mapping,
    /// The reflectance texture: f16 values (held in f32), RGBA with A = 1.
    pub reflectance: Texture,
    /// The transmittance texture, likewise.
    pub transmittance: Texture,
    /// What the GPU computes: bilinear with f32 weights on f16 texels.
    pub error: ExportError,
    /// The 16-bit PNGs' scale (texel = PNG value / 65535 × scale) and the
    /// error through them, when asked for.
    pub png: Option<(f64, ExportError)>,
    /// The most a filter with 1/256 weight steps adds to `error.max_abs`:
    /// the largest neighbouring-texel step / 256.
    pub weights_8bit_extra: f64,
    /// True when the transmittance is zero everywhere.
    pub opaque: bool,
}

impl Export {
    /// `irid_film` as a GPU computes it from the f16 textures.
    pub fn sample(&self, thickness_nm: f32, cos_theta: f32) -> ([f32; 3], [f32; 3]) {
        let uv = self.mapping.uv(thickness_nm, cos_theta);
        let r = self.reflectance.sample_bilinear(uv);
        let t = self.transmittance.sample_bilinear(uv);
        ([r[0], r[1], r[2]], [t[0], t[1], t[2]])
    }
}

/// The stack with everything fixed for the whole export.
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
    /// spectrum through the batched solver, integrated as it is solved.
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

/// Rounds to f16 (through f32, as the bake does, so every machine agrees).
fn to_f16(v: f64) -> f32 {
    half::f16::from_f32(v as f32).to_f32()
}

/// The two f16 textures of `values` (six per node).
fn textures(mapping: &Mapping, values: &[[f64; 6]]) -> (Texture, Texture) {
    let make = |offset: usize| Texture {
        width: mapping.size_u,
        height: mapping.size_v,
        texels: values
            .iter()
            .map(|v| {
                [
                    to_f16(v[offset]),
                    to_f16(v[offset + 1]),
                    to_f16(v[offset + 2]),
                    1.0,
                ]
            })
            .collect(),
    };
    (make(0), make(3))
}

/// |R| or |T| beyond which a gain film is taken to be at a lasing pole: a
/// hundredfold amplification is no film a renderer shows, and near a pole
/// the response is unbounded anyway.
pub const LASING_BOUND: f64 = 100.0;

/// Fails, naming where, when a value is not finite or beyond f16, or, for
/// a gain film, beyond [`LASING_BOUND`]: its range reaches (or crosses) a
/// lasing pole.
fn check_representable(mapping: &Mapping, values: &[[f64; 6]], gain: bool) -> Result<()> {
    let bound = if gain { LASING_BOUND } else { F16_MAX };
    let Some(k) = values
        .iter()
        .position(|v| v.iter().any(|x| x.is_nan() || x.abs() > bound))
    else {
        return Ok(());
    };
    let (i, j) = (k % mapping.size_u, k / mapping.size_u);
    let at = format!(
        "thickness {:.3} nm, cos θ {:.6}",
        mapping.thickness_at(i),
        mapping.cos_at(j)
    );
    Err(if gain {
        Error::invalid(
            "gain film",
            format!("R or T exceeds {LASING_BOUND} or is not finite at {at}: the range reaches a lasing pole; narrow --thickness or --angles"),
        )
    } else {
        Error::invalid("export", format!("R or T is not finite at {at}"))
    })
}

/// Interpolation error of the coarse nodes (even indices of `fine`, rounded
/// to f16) at the fine grid's midpoints: along u only, along v only, and at
/// cell centres.
fn midpoint_errors(coarse: &Mapping, fine: &[[f64; 6]]) -> [f64; 3] {
    let (nu, nv) = (2 * coarse.size_u - 1, 2 * coarse.size_v - 1);
    let at = |i: usize, j: usize| &fine[j * nu + i];
    let stored = |i: usize, j: usize| at(i, j).map(|x| f64::from(to_f16(x)));
    let mut worst = [0.0f64; 3];
    for j in 0..nv {
        for i in 0..nu {
            let kind = match (i % 2, j % 2) {
                (0, 0) => continue,
                (1, 0) => 0,
                (0, 1) => 1,
                _ => 2,
            };
            let (i0, i1) = (i - i % 2, i + i % 2);
            let (j0, j1) = (j - j % 2, j + j % 2);
            let (a, b, c, d) = (
                stored(i0, j0),
                stored(i1, j0),
                stored(i0, j1),
                stored(i1, j1),
            );
            let exact = at(i, j);
            for k in 0..6 {
                let interp = 0.25 * (a[k] + b[k] + c[k] + d[k]);
                worst[kind] = worst[kind].max((interp - exact[k]).abs());
            }
        }
    }
    worst
}

/// Random points over the domain, drawn as f32 (what a shader receives),
/// with the exact response at each.
struct Reference {
    points: Vec<[f32; 2]>,
    exact: Vec<[f64; 6]>,
}

impl Reference {
    fn new(film: &Film, spec: &ExportSpec) -> Result<Reference> {
        let points = measurement_points(spec);
        let exact = film.exact_at(&points)?;
        Ok(Reference { points, exact })
    }

    /// The error of `sample` (what the GPU computes at a point) against the
    /// exact values.
    fn measure(&self, sample: impl Fn(f32, f32) -> [f64; 6] + Sync) -> ExportError {
        let errors: Vec<([f64; 6], [f64; 2])> = self
            .points
            .par_iter()
            .zip(&self.exact)
            .map(|(p, exact)| {
                let got = sample(p[0], p[1]);
                let abs = std::array::from_fn(|k| (got[k] - exact[k]).abs());
                let de = [
                    delta_e2000_rgb([got[0], got[1], got[2]], [exact[0], exact[1], exact[2]]),
                    delta_e2000_rgb([got[3], got[4], got[5]], [exact[3], exact[4], exact[5]]),
                ];
                (abs, de)
            })
            .collect();
        let n = errors.len();
        let mut out = ExportError {
            max_abs: [0.0; 6],
            p99_abs: [0.0; 6],
            mean_abs: [0.0; 6],
            max_delta_e00: [0.0; 2],
            mean_delta_e00: [0.0; 2],
            points: n,
            seed: POINTS_SEED,
            worst_point: [0.0; 2],
        };
        for k in 0..6 {
            let mut e: Vec<f64> = errors.iter().map(|x| x.0[k]).collect();
            e.sort_by(f64::total_cmp);
            out.max_abs[k] = e[n - 1];
            out.p99_abs[k] = e[((n as f64 * 0.99).ceil() as usize).clamp(1, n) - 1];
            out.mean_abs[k] = e.iter().sum::<f64>() / n as f64;
        }
        for k in 0..2 {
            // NaN (a colour the Lab conversion cannot take) counts as worst.
            out.max_delta_e00[k] = errors.iter().map(|x| x.1[k]).fold(0.0, |a: f64, b| {
                if b.is_nan() {
                    f64::INFINITY
                } else {
                    a.max(b)
                }
            });
            out.mean_delta_e00[k] = errors.iter().map(|x| x.1[k]).sum::<f64>() / n as f64;
        }
        let worst = errors
            .iter()
            .map(|x| x.0.iter().fold(0.0f64, |a, &b| a.max(b)))
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(0, |(k, _)| k);
        out.worst_point = [
            f64::from(self.points[worst][0]),
            f64::from(self.points[worst][1]),
        ];
        out
    }
}

/// The random points (thickness nm, cos θ) at which [`export`] measures
/// the error: `spec.points` points uniform over the domain from a PCG64
/// stream seeded with [`POINTS_SEED`], drawn as f32 (what a shader gets).
pub fn measurement_points(spec: &ExportSpec) -> Vec<[f32; 2]> {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(POINTS_SEED);
    let mut draw = |(lo, hi): (f64, f64)| (lo + rng.random::<f64>() * (hi - lo)) as f32;
    (0..spec.points)
        .map(|_| [draw(spec.thickness_nm), draw(spec.cos_theta)])
        .collect()
}

/// The exact RGB reflectance and transmittance (R.r, R.g, R.b, T.r, T.g,
/// T.b, in the spec's white and sampling) at each point, from irid's
/// solver: what an export is measured against.
pub fn exact_at(spec: &ExportSpec, points: &[[f32; 2]]) -> Result<Vec<[f64; 6]>> {
    spec.validate()?;
    Film::new(spec)?.exact_at(points)
}

/// Rounds of the size search before it gives up.
const MAX_ROUNDS: usize = 16;
/// The most fine-grid nodes × wavelengths one round evaluates (about a
/// quarter of a minute of work on one core).
const MAX_WORK: usize = 1 << 31;

/// Chooses the texture size that meets `spec.max_error` as the GPU computes
/// it, bakes it and measures it (see the module docs). `progress` receives
/// one line per size tried.
pub fn export(spec: &ExportSpec, progress: &dyn Fn(&str)) -> Result<Export> {
    spec.validate()?;
    let film = Film::new(spec)?;
    let gain =
        film.stack.layers.iter().any(|l| l.material.has_gain()) || film.stack.substrate.has_gain();
    let (t_flat, c_flat) = (
        spec.thickness_nm.0 == spec.thickness_nm.1,
        spec.cos_theta.0 == spec.cos_theta.1,
    );
    let mut mapping = choose_warps(&film, spec, t_flat, c_flat, gain, progress)?;
    let reference = Reference::new(&film, spec)?;
    let waves = film.grid.wavelengths_nm().len();
    let target = spec.max_error;
    for _round in 0..MAX_ROUNDS {
        let (nu, nv) = (mapping.size_u, mapping.size_v);
        let fine_map = mapping.resized(2 * nu - 1, 2 * nv - 1);
        let work = fine_map.size_u * fine_map.size_v * waves;
        if nu > MAX_SIZE || nv > MAX_SIZE || work > MAX_WORK {
            break;
        }
        let fine = film.eval(&fine_map)?;
        check_representable(&fine_map, &fine, gain)?;
        let [e_u, e_v, e_c] = midpoint_errors(&mapping, &fine);
        let coarse: Vec<[f64; 6]> = (0..nv)
            .flat_map(|j| (0..nu).map(move |i| (i, j)))
            .map(|(i, j)| fine[2 * j * fine_map.size_u + 2 * i])
            .collect();
        let budget = budget_after_f16_rounding(&coarse, target)?;
        progress(&format!(
            "{nu}×{nv}: midpoint error {:.2e} (u) {:.2e} (v) {:.2e} (centre)",
            e_u, e_v, e_c
        ));
        let (gu, gv) = if e_u.max(e_v).max(e_c) <= target {
            let mut export = measured_export(spec, mapping, &coarse, &reference);
            progress(&format!(
                "{nu}×{nv}: {} random points, max error {:.2e}",
                spec.points,
                export.error.max_all()
            ));
            let measured = export.error.max_all();
            if measured <= target {
                if spec.png {
                    export.png = Some(png_error(&export, &reference));
                }
                return Ok(export);
            }
            // A feature between the midpoints: refine both axes.
            let grow = ((measured / target).sqrt() * 1.1).clamp(1.15, 2.0);
            (grow, grow)
        } else {
            growth_for_midpoint_errors([e_u, e_v, e_c], budget)
        };
        mapping = mapping.resized(grown(nu, gu, t_flat), grown(nv, gv, c_flat));
    }
    Err(Error::invalid(
        "max-error",
        format!(
            "{target} is not reached within {MAX_SIZE}×{MAX_SIZE} texels{}",
            if gain {
                " (a gain film near a lasing pole? narrow --thickness or --angles)"
            } else {
                " (narrow --thickness or --angles)"
            }
        ),
    ))
}

/// What remains of `target` for the bilinear error once f16 has rounded
/// the largest of `values`: f16 rounds each value by up to half its ulp, a
/// part of the budget no grid can buy back.
fn budget_after_f16_rounding(values: &[[f64; 6]], target: f64) -> Result<f64> {
    let largest = values
        .iter()
        .flat_map(|v| v.iter())
        .fold(0.0f64, |a, &b| a.max(b.abs()));
    let rounding = f16_half_ulp(largest);
    if rounding >= 0.9 * target {
        return Err(Error::invalid(
            "max-error",
            format!(
                "{target} cannot be met with f16 texels: values reach {largest:.3}, which f16 rounds by up to {rounding:.2e}"
            ),
        ));
    }
    Ok(target - rounding)
}

/// The growth of each axis (u, v) for midpoint errors (u, v, centre) over
/// `budget`. Bilinear error falls as h²: each axis grows by what its own
/// midpoint error asks, aiming at half the budget each.
fn growth_for_midpoint_errors([e_u, e_v, e_c]: [f64; 3], budget: f64) -> (f64, f64) {
    let share = 0.5 * budget;
    let factor = |e: f64| ((e / share).sqrt() * 1.1).clamp(1.0, 4.0);
    let (gu, gv) = (factor(e_u), factor(e_v));
    if gu == 1.0 && gv == 1.0 {
        // Only cell centres fail: both axes a little.
        let g = factor(e_c).max(1.15);
        return (g, g);
    }
    (gu, gv)
}

/// The export of the node values `coarse` on `mapping`, its error measured
/// at the reference points as the GPU samples it.
fn measured_export(
    spec: &ExportSpec,
    mapping: Mapping,
    coarse: &[[f64; 6]],
    reference: &Reference,
) -> Export {
    let (reflectance, transmittance) = textures(&mapping, coarse);
    let mut export = Export {
        spec: spec.clone(),
        mapping,
        weights_8bit_extra: f64::from(
            reflectance
                .max_neighbour_step()
                .max(transmittance.max_neighbour_step()),
        ) / 256.0,
        opaque: transmittance
            .texels
            .iter()
            .all(|t| t[..3].iter().all(|&x| x == 0.0)),
        reflectance,
        transmittance,
        error: reference.measure(|_, _| [0.0; 6]),
        png: None,
    };
    export.error = reference.measure(|t, c| {
        let (r, tr) = export.sample(t, c);
        [r[0], r[1], r[2], tr[0], tr[1], tr[2]].map(f64::from)
    });
    export
}

/// The 16-bit PNGs' scale and the error of sampling the textures through
/// them.
fn png_error(export: &Export, reference: &Reference) -> (f64, ExportError) {
    let scale = files::png_scale(export);
    let quantized = files::png_textures(export, scale);
    let error = reference.measure(|t, c| {
        let uv = export.mapping.uv(t, c);
        let r = quantized.0.sample_bilinear(uv);
        let tr = quantized.1.sample_bilinear(uv);
        [r[0], r[1], r[2], tr[0], tr[1], tr[2]].map(f64::from)
    });
    (scale, error)
}

/// The axis warps for `spec`: a dense-side stack's critical angle inside
/// the range always gets its node; otherwise each of uniform and crowded
/// (thickness towards its minimum, angle towards grazing) is tried on a
/// 129 × 129 grid, and the pair whose midpoint errors predict the fewest
/// texels (bilinear error falls as h²) wins.
fn choose_warps(
    film: &Film,
    spec: &ExportSpec,
    t_flat: bool,
    c_flat: bool,
    gain: bool,
    progress: &dyn Fn(&str),
) -> Result<Mapping> {
    const PROBE: usize = 129;
    let size = |flat: bool| if flat { 1 } else { PROBE };
    let critical =
        critical_cos(&film.stack).filter(|&cc| cc > spec.cos_theta.0 && cc < spec.cos_theta.1);
    let angles = match critical {
        Some(cc) => vec![AngleWarp::Critical(cc)],
        None if c_flat => vec![AngleWarp::Uniform],
        None => vec![AngleWarp::Uniform, AngleWarp::Grazing],
    };
    let powers: &[f64] = if t_flat { &[1.0] } else { &[1.0, 2.0] };
    let candidates: Vec<Mapping> = powers
        .iter()
        .flat_map(|&p| {
            angles.iter().map(move |&a| {
                Mapping::new(
                    spec.thickness_nm,
                    spec.cos_theta,
                    p,
                    a,
                    size(t_flat),
                    size(c_flat),
                )
            })
        })
        .collect();
    if candidates.len() == 1 {
        return Ok(candidates[0].resized(start_size(t_flat), start_size(c_flat)));
    }
    let share = 0.5 * spec.max_error;
    let predicted = |m: &Mapping| -> Result<f64> {
        let fine_map = m.resized(2 * m.size_u - 1, 2 * m.size_v - 1);
        let fine = film.eval(&fine_map)?;
        check_representable(&fine_map, &fine, gain)?;
        let [e_u, e_v, e_c] = midpoint_errors(m, &fine);
        let e_u = e_u.max(0.5 * e_c);
        let e_v = e_v.max(0.5 * e_c);
        let n = |e: f64, flat: bool| {
            if flat {
                1.0
            } else {
                (PROBE as f64 * (e / share).sqrt()).max(2.0)
            }
        };
        let texels = n(e_u, t_flat) * n(e_v, c_flat);
        progress(&format!(
            "warp: thickness power {}, angle {:?}: midpoint error {e_u:.2e} (u) {e_v:.2e} (v), predicts {texels:.0} texels",
            m.thickness_power,
            m.angle_warp()
        ));
        Ok(texels)
    };
    let mut best = (f64::INFINITY, candidates[0]);
    for m in &candidates {
        let texels = predicted(m)?;
        if texels < best.0 {
            best = (texels, *m);
        }
    }
    Ok(best.1.resized(start_size(t_flat), start_size(c_flat)))
}

/// The first size the search tries along an axis.
fn start_size(flat: bool) -> usize {
    if flat {
        1
    } else {
        17
    }
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

/// Half an f16 ulp at magnitude `v` (normal range).
fn f16_half_ulp(v: f64) -> f64 {
    if v < 6.2e-5 {
        return 2f64.powi(-25);
    }
    let exponent = v.log2().floor();
    2f64.powf(exponent - 11.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_ulp_matches_f16_rounding() {
        for v in [0.3f64, 0.9, 1.0, 1.7, 3.0, 100.0] {
            let bound = f16_half_ulp(v);
            let mut worst = 0.0f64;
            for k in 0..2000 {
                let x = v * (1.0 + k as f64 * 1e-6);
                if f16_half_ulp(x) == bound {
                    worst = worst.max((f64::from(to_f16(x)) - x).abs());
                }
            }
            // Through f32 first: that rounding (up to 6e-8 relative) adds on.
            assert!(
                worst <= bound + 1e-7 * v && worst > 0.5 * bound,
                "{v}: {worst} vs {bound}"
            );
        }
    }
}
