//! Full small renders: the tracer with each film mode, one frame each, timed
//! end to end and compared pixel by pixel (CIEDE2000) with the frame shaded by
//! direct exact evaluation. Renders run on the caller's rayon pool (the
//! tracer's tiles run in parallel); preparing the films (baking a table) is
//! timed apart.

use std::path::Path;
use std::time::Instant;

use crate::color::Sampling;
use crate::error::Result;
use crate::render::{prepare_films, render_with, FilmMode, RenderOptions, Scene};

/// One timed frame of one scene in one film mode, with its colour error
/// against the direct exact frame.
#[derive(Clone, Debug)]
pub struct RenderRow {
    /// The built-in scene's name.
    pub scene: String,
    /// The film mode in words, e.g. `direct exact`, `direct uniform:9` or
    /// the LUT mode with thickness grids.
    pub mode: String,
    /// Frame width in pixels.
    pub width: u32,
    /// Frame height in pixels.
    pub height: u32,
    /// Seconds spent baking or loading tables (zero for direct modes).
    pub prepare_s: f64,
    /// Wall time of the render itself in seconds (one sample per pixel),
    /// films already prepared.
    pub render_s: f64,
    /// Mean per-pixel CIEDE2000 against the direct exact frame (0 for that
    /// frame itself), on colours clamped to [0, 1].
    pub mean_de2000: f64,
    /// 99th-percentile per-pixel CIEDE2000 against the direct exact frame.
    pub p99_de2000: f64,
    /// Largest per-pixel CIEDE2000 against the direct exact frame.
    pub max_de2000: f64,
}

/// Renders each built-in scene of `scenes` at `width` × `height`, one sample
/// per pixel, in each mode; tables are baked into `cache_dir`.
pub fn run(scenes: &[&str], width: u32, height: u32, cache_dir: &Path) -> Result<Vec<RenderRow>> {
    let mut rows = Vec::new();
    for &name in scenes {
        let scene = Scene::load_named(name)?;
        let frame = |mode: FilmMode| -> Result<(f64, f64, crate::render::Image)> {
            let start = Instant::now();
            let films = prepare_films(&scene, &mode)?;
            let prepare_s = start.elapsed().as_secs_f64();
            let mut opts = RenderOptions::new(mode);
            opts.width = Some(width);
            opts.height = Some(height);
            opts.spp = Some(1);
            let start = Instant::now();
            let image = render_with(&scene, &films, &opts);
            Ok((prepare_s, start.elapsed().as_secs_f64(), image))
        };
        let (_, exact_s, reference) = frame(FilmMode::Direct {
            sampling: Sampling::Exact,
        })?;
        let mut push =
            |mode: String, prepare_s: f64, render_s: f64, image: &crate::render::Image| {
                let de = image.delta_e2000(&reference)?;
                rows.push(RenderRow {
                    scene: name.to_string(),
                    mode,
                    width,
                    height,
                    prepare_s,
                    render_s,
                    mean_de2000: de.mean,
                    p99_de2000: de.p99,
                    max_de2000: de.max,
                });
                Result::Ok(())
            };
        push("direct exact".into(), 0.0, exact_s, &reference)?;
        for sampling in [Sampling::Rgb3, Sampling::Uniform(9), Sampling::Uniform(41)] {
            let (p, r, image) = frame(FilmMode::Direct { sampling })?;
            push(format!("direct {sampling}"), p, r, &image)?;
        }
        let (p, r, image) = frame(FilmMode::lut(cache_dir))?;
        push(
            "LUT + thickness grid (baked on demand)".into(),
            p,
            r,
            &image,
        )?;
    }
    Ok(rows)
}
