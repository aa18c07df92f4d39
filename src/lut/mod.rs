//! Lookup tables of a stack's response over one layer's thickness and the
//! incidence angle (and wavelength): baking, the OpenEXR file, sampling, and
//! validation against direct evaluation.
//!
//! The file layout is specified in `docs/lut-format.md`.

mod axis;
mod bake;
pub(crate) mod file;
mod header;
pub mod rough;
mod sample;
mod validate;

pub use axis::Axis;
pub use bake::{bake, bake_with_progress, VALIDATION_SEED};
pub use header::{
    BakeCheck, ColorInfo, ErrorInfo, Header, TableAtlas, ATLAS_VERSION, FORMAT_NAME,
    FORMAT_VERSION, NEWEST_READABLE_VERSION, OLDEST_READABLE_VERSION, WHITE_E_VERSION,
};
pub use rough::{RoughHeader, RoughLut};
pub use sample::{FilmRgb, Lut};
pub use validate::{validate, RegionFigures, Validation, MAX_POINTS as MAX_VALIDATION_POINTS};
#[allow(deprecated)]
pub use validate::{ErrorStats, RegionStats};
// The sweep's, named here too: a table is of a kind, and covers what the
// sweep can evaluate.
pub use crate::sweep::{check_film_domain, Kind};

use serde::{Deserialize, Serialize};

use crate::color::{Sampling, White};
use crate::error::{Error, Result};
use crate::optics::Stack;

/// Every medium of `stack` is defined over `range` (nm): a spectral table
/// spans no wavelength its materials' data does not.
fn check_wavelength_data(stack: &Stack, range: (f64, f64)) -> Result<()> {
    let media = std::iter::once(("ambient".to_string(), &stack.ambient))
        .chain(
            stack
                .layers
                .iter()
                .enumerate()
                .map(|(i, l)| (format!("layers[{}]", i + 1), &l.material)),
        )
        .chain(std::iter::once(("substrate".to_string(), &stack.substrate)));
    for (field, material) in media {
        let (lo, hi) = material.range_nm();
        if range.0 < lo || range.1 > hi {
            return Err(Error::invalid(
                "wavelengths",
                format!(
                    "{}:{} nm is outside the data of {field} ({}), defined over {lo}–{hi} nm",
                    range.0, range.1, material.name
                ),
            ));
        }
    }
    Ok(())
}

/// How a table places its nodes (docs/lut-format.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Layout {
    /// An atlas of charts in the varying layer's optical thickness (format
    /// version 4), sized for an error target.
    #[default]
    Atlas,
    /// A grid of thickness × cos θ nodes (versions 2 and 3): always for a
    /// fixed resolution, and for an error target when asked for.
    Grid,
}

impl Layout {
    fn is_atlas(&self) -> bool {
        *self == Layout::Atlas
    }
}

impl std::str::FromStr for Layout {
    type Err = Error;
    fn from_str(s: &str) -> Result<Layout> {
        match s {
            "atlas" => Ok(Layout::Atlas),
            "grid" => Ok(Layout::Grid),
            _ => Err(Error::invalid(
                format!("layout '{s}'"),
                "expected atlas or grid",
            )),
        }
    }
}

/// How dense the grid is.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Resolution {
    /// Node counts per axis (wavelength is ignored for the rgb kind).
    Nodes {
        /// Nodes on the thickness axis (≥ 1; 1 is a single thickness).
        thickness: usize,
        /// Nodes on the cos θ axis (≥ 1).
        angle: usize,
        /// Nodes on the wavelength axis of a spectral table (≥ 1); the rgb
        /// kind has no wavelength axis and treats it as 1.
        wavelength: usize,
    },
    /// The coarsest grid (found by refining) whose bake check error — the
    /// largest absolute error over all channels at every edge midpoint and
    /// cell centre of the grid — is at most this.
    MaxError(f64),
}

/// Everything that determines a table. Two specs with the same
/// [`BakeSpec::cache_key`] bake bit-identical tables.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BakeSpec {
    /// The film stack whose reflectance and transmittance the table holds.
    pub stack: Stack,
    /// The layer whose thickness is the table's thickness axis, counted from
    /// 1 at the ambient side. Ignored (the axis is a single node at 0) for a
    /// stack without layers.
    pub layer: usize,
    /// The (min, max) thickness of `layer` in nm spanned by the thickness
    /// axis; 0 ≤ min ≤ max ≤ [`MAX_THICKNESS_NM`]. Equal ends give a single
    /// thickness node.
    pub thickness_nm: (f64, f64),
    /// The (min, max) range of cos θ in the ambient, within [0, 1].
    pub cos_theta: (f64, f64),
    /// Whether the table holds rgb colours or a spectral response.
    pub kind: Kind,
    /// The rgb kind's spectral integration (also the colour used for the
    /// CIEDE2000 figures of a spectral table).
    pub sampling: Sampling,
    /// What (1, 1, 1) is in the rgb kind (docs/color.md). Not serialized
    /// when D65, so D65 specs keep the cache keys they always had.
    #[serde(default, skip_serializing_if = "White::is_d65")]
    pub white: White,
    /// The spectral kind's wavelength axis range.
    pub wavelength_nm: (f64, f64),
    /// The grid: fixed node counts, or an error target the bake refines
    /// the grid to meet.
    pub resolution: Resolution,
    /// Store f16 instead of f32 (the error figures include the rounding).
    pub half: bool,
    /// With an error target: random points at which the finished table is
    /// compared with the solver and must meet the target too (0: none). A
    /// fixed resolution ignores it.
    pub validation_points: usize,
    /// Measure the table's interpolation error (the header's
    /// `error.bake_check`) by evaluating the grid with every interval halved,
    /// about four times the table's nodes. Only a fixed resolution may skip
    /// it: an error target chooses its grid by this measurement.
    #[serde(default = "default_check")]
    pub check: bool,
    /// A CIEDE2000 target beside the absolute one of
    /// [`Resolution::MaxError`] (atlas layout only): the largest colour
    /// difference of the reflected or transmitted light. With it the
    /// absolute target may be infinite (no absolute target).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_de: Option<f64>,
    /// How the nodes are placed with an error target (a fixed resolution is
    /// always a grid): see [`BakeSpec::layout`]. Not serialized when it is
    /// the atlas, so grid specs keep the cache keys they always had.
    #[serde(default, skip_serializing_if = "Layout::is_atlas")]
    pub layout: Layout,
}

fn default_check() -> bool {
    true
}

impl BakeSpec {
    /// A spec with the defaults of `irid bake`: layer 1 at its own thickness
    /// (one thickness node), 0–89°, rgb with exact integration, error
    /// at most 1e-3, f32.
    pub fn new(stack: Stack) -> BakeSpec {
        let t = stack.layers.first().map_or(0.0, |l| l.thickness_nm);
        BakeSpec {
            stack,
            layer: 1,
            thickness_nm: (t, t),
            cos_theta: (DEFAULT_COS_MIN, 1.0),
            kind: Kind::Rgb,
            sampling: Sampling::Exact,
            white: White::D65,
            wavelength_nm: (380.0, 780.0),
            resolution: Resolution::MaxError(1e-3),
            half: false,
            validation_points: 20_000,
            check: true,
            max_de: None,
            layout: Layout::Atlas,
        }
    }

    /// The layout the table is baked in: a grid for a fixed resolution or
    /// when `layout` asks for one, else an atlas.
    pub fn layout(&self) -> Layout {
        match self.resolution {
            Resolution::Nodes { .. } => Layout::Grid,
            Resolution::MaxError(_) => self.layout,
        }
    }

    /// Checks ranges and the stack; errors name the offending field.
    pub fn validate(&self) -> Result<()> {
        check_film_domain(&self.stack, self.layer, self.thickness_nm, self.cos_theta)?;
        if self.kind == Kind::Spectral {
            let (w0, w1) = self.wavelength_nm;
            if !(w0.is_finite() && w1.is_finite() && w0 > 0.0 && w0 <= w1) {
                return Err(Error::invalid(
                    "wavelengths",
                    format!("need finite 0 < min ≤ max, got {w0}:{w1}"),
                ));
            }
            check_wavelength_data(&self.stack, (w0, w1))?;
        }
        if self.validation_points > MAX_VALIDATION_POINTS {
            return Err(Error::invalid(
                "validate-points",
                format!(
                    "must be at most {}, got {}",
                    MAX_VALIDATION_POINTS, self.validation_points
                ),
            ));
        }
        match self.resolution {
            Resolution::Nodes {
                thickness,
                angle,
                wavelength,
            } => {
                let spectral = self.kind == Kind::Spectral;
                let wavelength = if spectral { wavelength } else { 1 };
                if thickness == 0 || angle == 0 || wavelength == 0 {
                    return Err(Error::invalid("resolution", "node counts must be ≥ 1"));
                }
                let total = thickness
                    .checked_mul(angle)
                    .and_then(|n| n.checked_mul(wavelength));
                if thickness > MAX_AXIS_NODES
                    || angle > MAX_AXIS_NODES
                    || wavelength > MAX_AXIS_NODES
                    || total.is_none_or(|t| t > MAX_NODES)
                {
                    return Err(Error::invalid(
                        "resolution",
                        format!(
                            "{thickness},{angle}{}: at most {MAX_AXIS_NODES} nodes per axis and {MAX_NODES} in all",
                            if spectral { format!(",{wavelength}") } else { String::new() }
                        ),
                    ));
                }
                crate::limits::check_allocation(
                    "resolution",
                    self.fixed_bake_bytes([thickness, angle, wavelength]),
                )?;
            }
            Resolution::MaxError(e) => self.validate_target(e)?,
        }
        Ok(())
    }

    /// Checks an error target `e` (and the colour target beside it)
    /// against the kind, the layout and the storage.
    fn validate_target(&self, e: f64) -> Result<()> {
        // An infinite absolute target stands for none, beside a
        // colour target.
        let colour_only = e == f64::INFINITY && self.max_de.is_some();
        if !(e > 0.0 && (e.is_finite() || colour_only)) {
            return Err(Error::invalid(
                "max-error",
                format!("must be a positive number, got {e:e}"),
            ));
        }
        if let Some(de) = self.max_de {
            if self.kind == Kind::Spectral {
                return Err(Error::invalid(
                    "max-de",
                    "applies to rgb tables (a spectral table has no colour to target)",
                ));
            }
            if !(de > 0.0 && de.is_finite()) {
                return Err(Error::invalid(
                    "max-de",
                    format!("must be a positive number, got {de:e}"),
                ));
            }
            if self.layout() != Layout::Atlas {
                return Err(Error::invalid(
                    "max-de",
                    "needs the atlas layout (a grid refines for max-error only)",
                ));
            }
        }
        let floor = storage_error_floor(self.half);
        if e < floor {
            return Err(Error::invalid(
                "max-error",
                format!(
                    "{e:e} is below what {} storage resolves: its values near 1 are {floor:e} apart",
                    if self.half { "f16" } else { "f32" }
                ),
            ));
        }
        if !self.check {
            return Err(Error::invalid(
                "no-check",
                "needs a fixed resolution: with max-error the bake check is how the grid is chosen",
            ));
        }
        Ok(())
    }

    /// The peak memory of a fixed-resolution bake, estimated from its node
    /// counts: the exact values (f64) at every node of the check grid (every
    /// interval halved) or of the table itself without the check, the
    /// stored f32 table, and the sampler's layout of an rgb table. None
    /// when the figure overflows.
    fn fixed_bake_bytes(&self, counts: [usize; 3]) -> Option<u64> {
        let channels = match self.kind {
            Kind::Rgb => 6,
            Kind::Spectral => 2,
        };
        let table = crate::limits::product(&counts.map(|c| c as u64), 1)?;
        let evaluated = if self.check {
            crate::limits::product(&counts.map(|c| 2 * c as u64), 1)?
        } else {
            table
        };
        let values = crate::limits::product(&[evaluated, channels], 8)?;
        let stored = crate::limits::product(&[table, channels], 4)?;
        let simd = if self.kind == Kind::Rgb {
            table.checked_mul(32)?
        } else {
            0
        };
        values.checked_add(stored)?.checked_add(simd)
    }

    /// A stable hex digest of everything that determines the table (stack,
    /// layer, ranges, resolution or error target, kind, sampling, precision,
    /// format version): a renderer keys its cache of baked tables on it.
    pub fn cache_key(&self) -> String {
        // serde_json writes struct fields in declaration order and floats
        // exactly (shortest round-trip), so the text is a stable identity.
        let version = match self.layout() {
            Layout::Atlas => ATLAS_VERSION,
            Layout::Grid => FORMAT_VERSION,
        };
        // `layout` only decides an error-target table; elsewhere it is left
        // out (as for the atlas), so the same table has one key whichever
        // layout the caller's spec names.
        let mut identity = self.clone();
        let decides = matches!(self.resolution, Resolution::MaxError(_));
        if !decides {
            identity.layout = Layout::Atlas;
        }
        let text = serde_json::to_string(&(version, &identity)).unwrap_or_default();
        format!("{:016x}", fnv1a64(text.as_bytes()))
    }
}

/// The table for `spec` from a cache directory: `DIR/<cache key>.exr` when
/// it exists, loads, and was baked from the same spec; otherwise baked now
/// and written there (atomically, so concurrent renderers never read half a
/// table). A stale or unreadable cache file is replaced, never an error.
pub fn cached(spec: &BakeSpec, dir: &std::path::Path) -> Result<Lut> {
    let path = dir.join(format!("{}.exr", spec.cache_key()));
    cached_at(spec, &path).map(|(lut, _)| lut)
}

/// [`cached`] at a path of the caller's choosing; also says whether the
/// table had to be baked (true) or came from the file (false).
pub fn cached_at(spec: &BakeSpec, path: &std::path::Path) -> Result<(Lut, bool)> {
    let key = spec.cache_key();
    if let Ok(lut) = Lut::load(path) {
        if lut.header().cache_key == key {
            return Ok((lut, false));
        }
    }
    let lut = bake(spec)?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    lut.write(path)?;
    Ok((lut, true))
}

/// cos 89°, the default smallest cos θ. At exactly grazing incidence every
/// stack reflects fully, but a free-standing film (same medium on both
/// sides) of vanishing thickness reflects nothing: R jumps at the corner
/// (0 nm, 90°), which no grid can interpolate. Up to 89° it is steep but
/// smooth; beyond, the sampler clamps to the 89° row.
pub const DEFAULT_COS_MIN: f64 = 0.017_452_406_437_283_51;

/// The smallest `--max-error` a table's storage can meet: the spacing of
/// f32 (2⁻²⁴) or f16 (2⁻¹¹) values just below 1. Rounding a reflectance or
/// transmittance near 1 to the stored type errs by up to half of it, and a
/// target below the spacing leaves the interpolation no room at all: the
/// refinement would only grow the grid until it hit the size limits.
pub fn storage_error_floor(half: bool) -> f64 {
    if half {
        2f64.powi(-11)
    } else {
        2f64.powi(-24)
    }
}

/// Caps that keep a typo (`--resolution 1000000,…`) from exhausting memory:
/// at most this many nodes on any one axis.
pub const MAX_AXIS_NODES: usize = 1 << 16;
/// At most this many nodes in a whole table (the product of its axes' node
/// counts), enforced on fixed resolutions and on the grids an error target
/// refines to.
pub const MAX_NODES: usize = 1 << 26;

/// FNV-1a: tiny, dependency-free and fixed forever (unlike std's hasher).
fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}
