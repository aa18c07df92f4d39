//! The tracer: a Whitted-style renderer whose thin films are shaded through
//! one interface ([`FilmShading`]) with two implementations, baked tables
//! ([`LutFilm`]) and the direct transfer-matrix solution ([`DirectFilm`]), so
//! the two modes share every other line.
//!
//! ```no_run
//! use irid::render::{render, FilmMode, RenderOptions, Scene};
//! let scene = Scene::load_named("bubbles-noise")?;
//! let image = render(&scene, &RenderOptions::new(FilmMode::lut("luts/cache")))?;
//! image.write_png(std::path::Path::new("bubbles.png"))?;
//! # Ok::<(), irid::Error>(())
//! ```

pub mod camera;
pub mod compensation;
pub mod environment;
pub mod film;
pub mod geometry;
pub mod image;
pub mod lut_film;
pub mod material;
pub mod mesh;
pub mod microfacet;
pub mod output;
pub mod random;
pub mod scene;
pub mod scene_file;
pub mod thickness;
pub mod tracer;

use std::path::PathBuf;
use std::time::{Duration, Instant};

pub use self::image::Image;
pub use film::{DirectFilm, FilmShading, Side};
pub use lut_film::LutFilm;
pub use output::ColorDifference;
pub use scene::Scene;
pub use scene_file::builtin_names;

use crate::color::Sampling;
use crate::error::Result;
use material::Material;
use thickness::ThicknessGrid;

/// How films are shaded.
#[derive(Clone, Debug, PartialEq)]
pub enum FilmMode {
    /// Sample baked tables, baking any that are missing or stale into
    /// `cache_dir`; with `thickness_grids`, bake each noise film's thickness
    /// field to a grid too (see [`ThicknessGrid`]) rather than evaluate the
    /// noise at every hit.
    Lut {
        /// Directory of baked tables, one file per film side named after
        /// the film, the side and the table's cache key (see
        /// [`LutFilm::cache_path`]); created when missing.
        cache_dir: PathBuf,
        /// Bake each bounded noise film's thickness field to a grid (the
        /// default) instead of evaluating the noise at every hit.
        thickness_grids: bool,
    },
    /// Evaluate the transfer matrix at every hit with this wavelength sampling.
    Direct {
        /// The spectral integration that turns each hit's R and T spectra
        /// into linear sRGB.
        sampling: Sampling,
    },
}

impl FilmMode {
    /// Tables and thickness grids: the default, fast mode.
    pub fn lut(cache_dir: impl Into<PathBuf>) -> FilmMode {
        FilmMode::Lut {
            cache_dir: cache_dir.into(),
            thickness_grids: true,
        }
    }

    /// Tables, with the noise evaluated at every hit.
    pub fn lut_exact_noise(cache_dir: impl Into<PathBuf>) -> FilmMode {
        FilmMode::Lut {
            cache_dir: cache_dir.into(),
            thickness_grids: false,
        }
    }
}

/// Per-run settings; `None` keeps the scene file's value.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// How films are shaded: baked tables or the direct solver.
    pub film: FilmMode,
    /// Image width in pixels (values below 1 become 1).
    pub width: Option<u32>,
    /// Image height in pixels (values below 1 become 1).
    pub height: Option<u32>,
    /// Stratified samples per pixel (values below 1 become 1; 1 samples
    /// the pixel centre).
    pub spp: Option<u32>,
    /// Reflection and refraction bounces after the camera ray.
    pub max_depth: Option<u32>,
    /// Seeds the per-sample jitter; the image depends only on it (and the
    /// scene and options), not on thread count or scheduling.
    pub seed: u64,
}

impl RenderOptions {
    /// Options that shade films with `film` and keep every scene-file
    /// setting, with seed 0.
    pub fn new(film: FilmMode) -> RenderOptions {
        RenderOptions {
            film,
            width: None,
            height: None,
            spp: None,
            max_depth: None,
            seed: 0,
        }
    }
}

/// One shader per film of a scene, all of one mode.
pub enum FilmShaders {
    /// Table-backed shaders, indexed like the scene's `films`.
    Lut(Vec<LutFilm>),
    /// Direct transfer-matrix shaders, indexed like the scene's `films`.
    Direct(Vec<DirectFilm>),
}

/// The film shaders a scene needs, and what preparing them cost.
pub struct PreparedFilms {
    /// One shader per entry of the scene's `films`, in the same order.
    pub shaders: FilmShaders,
    /// Per object: in LUT mode with thickness grids, its film's noise
    /// thickness field baked to a grid (where the object is bounded and the
    /// grid small enough); otherwise empty, and the noise is evaluated at
    /// every hit.
    pub thickness_grids: Vec<Option<ThicknessGrid>>,
    /// Wall time spent baking or loading tables and baking thickness
    /// grids (zero in direct mode).
    pub bake_time: Duration,
    /// Tables baked by this call, and tables found in the cache.
    pub tables_baked: usize,
    /// Tables loaded from the cache directory instead of baked (zero in
    /// direct mode).
    pub tables_cached: usize,
}

/// Builds the film shaders a scene needs: in LUT mode, loads each table from
/// the cache or bakes it (only the thickness range and sides the scene uses).
pub fn prepare_films(scene: &Scene, mode: &FilmMode) -> Result<PreparedFilms> {
    let start = Instant::now();
    let (mut baked, mut cached) = (0, 0);
    let (shaders, thickness_grids, bake_time) = match mode {
        FilmMode::Direct { sampling } => (
            FilmShaders::Direct(
                scene
                    .films
                    .iter()
                    .map(|film| DirectFilm::new(film, *sampling))
                    .collect::<Result<_>>()?,
            ),
            Vec::new(),
            Duration::ZERO,
        ),
        FilmMode::Lut {
            cache_dir,
            thickness_grids,
        } => {
            let mut tables = Vec::with_capacity(scene.films.len());
            for film in &scene.films {
                let (lut, b, c) = LutFilm::prepare(film, cache_dir)?;
                baked += b;
                cached += c;
                tables.push(lut);
            }
            let grids = if *thickness_grids {
                bake_thickness_grids(scene)
            } else {
                Vec::new()
            };
            (FilmShaders::Lut(tables), grids, start.elapsed())
        }
    };
    Ok(PreparedFilms {
        shaders,
        thickness_grids,
        bake_time,
        tables_baked: baked,
        tables_cached: cached,
    })
}

/// Each film object's noise thickness field baked near its surface (see
/// [`ThicknessGrid`]); planes, and objects whose grid would be too large,
/// keep the exact field.
fn bake_thickness_grids(scene: &Scene) -> Vec<Option<ThicknessGrid>> {
    use rayon::prelude::*;
    scene
        .objects
        .par_iter()
        .map(|o| {
            let Material::Film(f) = &scene.materials[o.material] else {
                return None;
            };
            ThicknessGrid::bake(&f.thickness, &o.shape)
        })
        .collect()
}

/// Bytes a render holds per pixel at its peak: the tiles' pixels and the
/// image (12 bytes each), the PNG's bytes (3) and the EXR writer's copy (12).
pub const RENDER_BYTES_PER_PIXEL: u64 = 40;

/// Refuses a render whose image would not fit the memory budget (see
/// [`crate::limits`]), before any work is done.
pub fn check_image_size(scene: &Scene, opts: &RenderOptions) -> crate::Result<()> {
    let s = &scene.settings;
    let width = opts.width.unwrap_or(s.width).max(1);
    let height = opts.height.unwrap_or(s.height).max(1);
    crate::limits::check_allocation(
        &format!("a {width}x{height} image"),
        crate::limits::product(
            &[u64::from(width), u64::from(height)],
            RENDER_BYTES_PER_PIXEL,
        ),
    )
}

/// Renders with prepared film shaders (no progress output; see
/// [`render_with_progress`]).
pub fn render_with(scene: &Scene, films: &PreparedFilms, opts: &RenderOptions) -> Image {
    render_with_progress(scene, films, opts, &|_| {})
}

/// Renders with prepared film shaders, calling `progress` with the fraction
/// of the image done (0 to 1, from the rendering threads) as it goes: the
/// library draws nothing itself, the caller shows what it likes.
pub fn render_with_progress(
    scene: &Scene,
    films: &PreparedFilms,
    opts: &RenderOptions,
    progress: &(dyn Fn(f64) + Sync),
) -> Image {
    let s = &scene.settings;
    let width = opts.width.unwrap_or(s.width).max(1);
    let height = opts.height.unwrap_or(s.height).max(1);
    let c = &scene.camera;
    let camera = camera::Camera::new(
        c.position,
        c.look_at,
        c.up,
        c.vfov_deg,
        width as f32 / height as f32,
    );
    let max_depth = opts.max_depth.unwrap_or(s.max_depth);
    let sampler = image::Sampler {
        width,
        height,
        spp: opts.spp.unwrap_or(s.spp).max(1),
        seed: opts.seed,
        exposure: s.exposure,
    };
    // One tracer type per kind of shader, each compiled with its shader's
    // lookup inlined.
    match &films.shaders {
        FilmShaders::Lut(shaders) => render_tiles_with(
            scene, shaders, films, max_depth, &camera, &sampler, progress,
        ),
        FilmShaders::Direct(shaders) => render_tiles_with(
            scene, shaders, films, max_depth, &camera, &sampler, progress,
        ),
    }
}

fn render_tiles_with<F: FilmShading>(
    scene: &Scene,
    shaders: &[F],
    films: &PreparedFilms,
    max_depth: u32,
    camera: &camera::Camera,
    sampler: &image::Sampler,
    progress: &(dyn Fn(f64) + Sync),
) -> Image {
    // The rough-film path only where a film is rough: compiled in, it
    // slows the smooth path a little (see `Tracer`).
    let rough = scene
        .materials
        .iter()
        .any(|m| matches!(m, Material::Film(f) if f.alpha > 0.0));
    if rough {
        let tracer: tracer::Tracer<F, true> = tracer::Tracer {
            scene,
            films: shaders,
            thickness_grids: &films.thickness_grids,
            max_depth,
        };
        return image::render_tiles(&tracer, camera, sampler, progress);
    }
    let tracer: tracer::Tracer<F> = tracer::Tracer {
        scene,
        films: shaders,
        thickness_grids: &films.thickness_grids,
        max_depth,
    };
    image::render_tiles(&tracer, camera, sampler, progress)
}

/// Prepares the films and renders.
pub fn render(scene: &Scene, opts: &RenderOptions) -> Result<Image> {
    let films = prepare_films(scene, &opts.film)?;
    Ok(render_with(scene, &films, opts))
}
