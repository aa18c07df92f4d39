//! Full small renders: the tracer with each film mode, one frame each, timed
//! end to end and compared pixel by pixel (CIEDE2000) with the frame shaded by
//! direct exact evaluation. Renders run on the caller's rayon pool (the
//! tracer's tiles run in parallel); preparing the films (baking a table) is
//! timed apart.

// Not every public item here is documented yet: the crate-wide
// missing_docs lint (Cargo.toml) is waived for this file until it is.
#![allow(missing_docs)]

use std::path::Path;
use std::time::Instant;

use crate::color::Sampling;
use crate::error::Result;
use crate::render::{prepare_films, render_with, FilmMode, RenderOptions, Scene};

#[derive(Clone, Debug)]
pub struct RenderRow {
    pub scene: String,
    pub mode: String,
    pub width: u32,
    pub height: u32,
    /// Baking or loading tables (zero for direct modes).
    pub prepare_s: f64,
    pub render_s: f64,
    pub mean_de2000: f64,
    pub p99_de2000: f64,
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
