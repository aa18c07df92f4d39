//! Film shading from baked tables: one RGB table per side the scene uses,
//! covering only the film's thickness range, cached on disk under the
//! table's cache key so a changed stack, range or resolution rebakes.

use std::path::{Path, PathBuf};

use super::film::{FilmShading, Side};
use super::scene::Film;
use crate::error::{Error, Result};
use crate::lut::FilmRgb;
use crate::lut::{BakeSpec, Lut, Resolution};

const THICKNESS_STEP_NM: f64 = 4.0;
const MAX_THICKNESS_NODES: usize = 8193;
const ANGLE_NODES: usize = 65;

/// A film shaded from baked rgb tables: one for the front side and, when
/// the film has a back side, one for the reversed stack (without it, back
/// hits use the front table). Each covers the film's thickness range and
/// every incidence angle; see [`LutFilm::spec`].
pub struct LutFilm {
    front: Lut,
    back: Option<Lut>,
}

impl LutFilm {
    /// The table spec for one side of a film: the stack as seen from that
    /// side, the film's thickness range, every incidence angle, RGB under D65
    /// with exact (1 nm) integration. The grid is fixed rather than searched
    /// for an error target: a node every 4 nm of thickness (a visible fringe
    /// spans ≥ λ/2n ≈ 80 nm even at n = 2.3) and 65 angle nodes, which the
    /// baker places itself (crowded at a critical angle). That keeps LUT
    /// renders within a fraction of a CIEDE2000 unit of the direct exact
    /// render (tests/render.rs) while a table stays a few hundred kB, small
    /// enough to stay in cache while the tracer samples it at random: the
    /// table's memory traffic, not its arithmetic, is what film shading costs.
    pub fn spec(film: &Film, side: Side) -> BakeSpec {
        let (stack, layer) = match side {
            Side::Front => (film.stack.clone(), film.layer + 1),
            Side::Back => (film.stack.reversed(), film.stack.layers.len() - film.layer),
        };
        let mut spec = BakeSpec::new(stack);
        spec.layer = layer;
        spec.thickness_nm = (
            f64::from(film.thickness_range_nm.0),
            f64::from(film.thickness_range_nm.1),
        );
        spec.cos_theta = (0.0, 1.0);
        let span_nm = spec.thickness_nm.1 - spec.thickness_nm.0;
        spec.resolution = Resolution::Nodes {
            thickness: ((span_nm / THICKNESS_STEP_NM).ceil() as usize + 1).min(MAX_THICKNESS_NODES),
            angle: ANGLE_NODES,
            wavelength: 1,
        };
        spec
    }

    /// Where the table for `spec` is cached.
    pub fn cache_path(film: &Film, side: Side, spec: &BakeSpec, cache_dir: &Path) -> PathBuf {
        let side = match side {
            Side::Front => "front",
            Side::Back => "back",
        };
        let name: String = film
            .name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        cache_dir.join(format!("{name}-{side}-{}.exr", spec.cache_key()))
    }

    /// Loads the tables from `cache_dir`, baking (and caching) any that are
    /// missing or unreadable. Returns the shader and how many tables were
    /// baked and how many came from the cache.
    pub fn prepare(film: &Film, cache_dir: &Path) -> Result<(LutFilm, usize, usize)> {
        std::fs::create_dir_all(cache_dir).map_err(|e| Error::io(cache_dir, e))?;
        let (mut baked, mut cached) = (0, 0);
        let mut table = |side: Side| -> Result<Lut> {
            let spec = Self::spec(film, side);
            let path = Self::cache_path(film, side, &spec, cache_dir);
            let (lut, was_baked) = crate::lut::cached_at(&spec, &path).map_err(|e| match e {
                Error::Io { .. } => e,
                e => Error::invalid(format!("film '{}'", film.name), e.to_string()),
            })?;
            if was_baked {
                baked += 1;
            } else {
                cached += 1;
            }
            Ok(lut)
        };
        let front = table(Side::Front)?;
        let back = if film.back_side {
            Some(table(Side::Back)?)
        } else {
            None
        };
        Ok((LutFilm { front, back }, baked, cached))
    }
}

impl FilmShading for LutFilm {
    /// Always inlined: the tracer calls it from the smooth and the rough
    /// film paths, and with two callers the compiler stopped inlining the
    /// lookup into the hit, which cost a smooth LUT render about 4 % more
    /// instructions (callgrind, two-layer-noise).
    #[inline(always)]
    fn shade(&self, thickness_nm: f32, cos_theta: f32, side: Side) -> FilmRgb {
        let lut = match side {
            Side::Back => self.back.as_ref().unwrap_or(&self.front),
            Side::Front => &self.front,
        };
        lut.sample_rgb(thickness_nm, cos_theta)
    }
}
