//! The JSON header stored in a table's `irid` attribute.

use serde::{Deserialize, Serialize};

use super::axis::Axis;
use super::validate::Validation;
use super::Kind;
use crate::color::White;
use crate::optics::Stack;

/// The header's `format` value that identifies an irid table.
pub const FORMAT_NAME: &str = "irid-lut";
/// Bumped on any change a reader of an older version would misread.
/// Version 2: `error.bake_check` may be null (a table baked without the
/// check, `irid bake --no-check`).
pub const FORMAT_VERSION: u32 = 2;
/// Version 3: `color.white` is `"e"` (see docs/color.md). Only such tables
/// are written as version 3, so an older irid refuses them instead of
/// taking them for D65 tables; D65 tables stay version 2, unchanged.
pub const WHITE_E_VERSION: u32 = 3;
/// Version 4: the nodes are an atlas of charts (the header's `atlas`), not
/// a grid of thickness × cos θ nodes; `color.white` says the white. Grid
/// tables are still written as versions 2 and 3.
pub const ATLAS_VERSION: u32 = 4;
/// The oldest version this irid reads: every version-1 header is a valid
/// version-2 header (its bake check is always present).
pub const OLDEST_READABLE_VERSION: u32 = 1;
/// The newest version this irid reads.
pub const NEWEST_READABLE_VERSION: u32 = ATLAS_VERSION;

/// Whether this irid reads tables of format `version`.
pub fn readable_version(version: u64) -> bool {
    (u64::from(OLDEST_READABLE_VERSION)..=u64::from(NEWEST_READABLE_VERSION)).contains(&version)
}

/// The version a table of this white and layout is written in.
pub fn version_for(white: White, atlas: bool) -> u32 {
    match (atlas, white) {
        (true, _) => ATLAS_VERSION,
        (false, White::D65) => FORMAT_VERSION,
        (false, White::E) => WHITE_E_VERSION,
    }
}

/// The image axes' name in an atlas table: columns and rows of the atlas.
pub const ATLAS_AXIS: &str = "atlas";

/// Name of the thickness axis (nodes in nm), always the image's x axis.
pub const THICKNESS_AXIS: &str = "thickness_nm";
/// Name of the cos θ axis (cosine of the ambient incidence angle,
/// dimensionless), always the image's y axis.
pub const COS_AXIS: &str = "cos_theta";
/// Name of a spectral table's wavelength axis (nodes in nm), folded into y
/// as stacked blocks of cos θ rows.
pub const WAVELENGTH_AXIS: &str = "wavelength_nm";

/// Everything a reader needs besides the pixels.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// Always [`FORMAT_NAME`].
    pub format: String,
    /// The format version the file was written in: [`FORMAT_VERSION`], or
    /// [`WHITE_E_VERSION`] for an equal-energy-white table; readers accept
    /// [`OLDEST_READABLE_VERSION`] up to [`WHITE_E_VERSION`].
    pub version: u32,
    /// Whether the pixels hold rgb colours (six channels) or a spectral
    /// response (two channels and a wavelength axis).
    pub kind: Kind,
    /// The axis along image columns (x).
    pub x_axis: String,
    /// The axis along image rows (y). For the spectral kind the rows hold
    /// one block of cos θ rows per wavelength: row = w · n_cos + c.
    pub y_axis: String,
    /// Spectral kind only: the axis whose blocks are stacked along y.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub y_blocks: Option<String>,
    /// The axes in order thickness, cos θ, then (spectral kind only)
    /// wavelength; their node lists fix the image size.
    pub axes: Vec<Axis>,
    /// The image channels, in the order every per-channel error array
    /// (`max_abs` and the like) follows.
    pub channels: Vec<Channel>,
    /// "f32" or "f16": the sample type on disk.
    pub precision: String,
    /// The full stack, so the file alone can be re-validated.
    pub stack: Stack,
    /// Which layer's thickness the thickness axis sets (1-based; 0 when the
    /// stack has no layers).
    pub layer: usize,
    /// How rgb values were integrated from the spectrum (illuminant,
    /// observer, colour space, sampling, white).
    pub color: ColorInfo,
    /// The table's measured interpolation error figures.
    pub error: ErrorInfo,
    /// "irid <version>" that wrote the file.
    pub tool: String,
    /// [`super::BakeSpec::cache_key`] of the spec that baked it.
    pub cache_key: String,
    /// Version 4: where the nodes are (then `axes` hold only the domain's
    /// ends and the wavelength nodes, and both image axes are
    /// [`ATLAS_AXIS`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub atlas: Option<TableAtlas>,
}

/// An atlas table's layout.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TableAtlas {
    /// The charts and the image size (per wavelength block).
    #[serde(flatten)]
    pub atlas: crate::atlas::Atlas,
    /// cos θ below which the film's fringes are aliased (see
    /// docs/lut-format.md): the table's error target was not sought there.
    pub aliased_below_cos: f64,
    /// The cos θ band over which a dispersive ambient's critical angle
    /// moves (light from the denser side): the target was not sought there
    /// either (see docs/lut-format.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub critical_band_cos: Option<[f64; 2]>,
    /// A lossless film (R + T the same colour at every node): only the
    /// reflectance channels are stored and T = this colour − R.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lossless_white: Option<[f64; 3]>,
}

impl Header {
    /// The image channels this header's table stores, in order.
    pub fn channel_names(&self) -> &'static [&'static str] {
        let lossless = self
            .atlas
            .as_ref()
            .is_some_and(|a| a.lossless_white.is_some());
        match self.kind {
            Kind::Rgb if lossless => &super::sample::RGB_CHANNELS[..3],
            kind => super::sample::channel_names(kind),
        }
    }
}

/// One image channel of the table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Channel {
    /// The EXR channel name: `reflectance.R` … `transmittance.B` for the
    /// rgb kind, `reflectance` and `transmittance` for the spectral kind.
    /// EXR sorts channels by name, so readers look them up by name.
    pub name: String,
    /// Human-readable description of the value: unpolarized (mean of s and
    /// p) reflectance or transmittance (power into the substrate), and for
    /// rgb the colour space and white.
    pub meaning: String,
}

/// The colorimetry of an rgb table's values (also written for spectral
/// tables, whose CIEDE2000 figures use it).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ColorInfo {
    /// The illuminant the spectrum is integrated under, as named by
    /// [`White::illuminant`] (CIE D65, or equal-energy E).
    pub illuminant: String,
    /// The colour-matching functions: always "CIE 1931 2°".
    pub observer: String,
    /// The output colour space: linear sRGB (BT.709 primaries, D65 white),
    /// normalized so a perfect reflector is (1, 1, 1).
    pub space: String,
    /// The spectral sampling of the rgb integration (`exact`, `uniform:N`,
    /// `rgb3`).
    pub sampling: String,
    /// What (1, 1, 1) is (docs/color.md). Absent in D65 tables, which are
    /// written as before.
    #[serde(default, skip_serializing_if = "White::is_d65")]
    pub white: White,
}

/// Measured error of the table against the exact response.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorInfo {
    /// `--max-error` when the grid was chosen to meet it.
    pub target_max_abs: Option<f64>,
    /// `None` (null in the file) when the table was baked without the check.
    pub bake_check: Option<BakeCheck>,
    /// Random off-grid points against the direct solver (`irid validate`).
    pub validation: Option<Validation>,
}

/// The baker's own dense error measurement.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BakeCheck {
    /// Prose definition of the measured figure: always the text of the
    /// `BAKE_CHECK_METRIC` constant.
    pub metric: String,
    /// How many off-grid points were compared.
    pub points: usize,
    /// Largest absolute error per channel, in `channels` order.
    pub max_abs: Vec<f64>,
    /// The largest of `max_abs`.
    pub max_abs_all: f64,
}

/// The text of [`BakeCheck::metric`]: where the bake check compares the
/// table with the exact response and what it reports.
pub const BAKE_CHECK_METRIC: &str =
    "largest absolute difference, per channel, between the table's \
    multilinear interpolation and the exact response (fast baker, agrees with the solver to 1e-12) \
    at every edge midpoint and cell centre of the grid (midpoints in node index; the interpolation \
    is linear in the axis value)";
