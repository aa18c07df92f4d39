//! The CPU rough table on disk (`irid bake --rough`, docs/lut-format.md
//! "Rough tables"): the slices of a [`RoughSlices`] stacked in one
//! single-part scanline OpenEXR image, slice s in rows s · height to
//! (s + 1) · height − 1, three 32-bit float channels `reflectance.R`, `.G`,
//! `.B` of F_eff, and a JSON header in the text attribute `irid` with the
//! charts, the slice rule, the stack, the colour settings and the measured
//! error. [`RoughLut::load`] checks everything before sampling.

use std::path::Path;

use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Layer, LayerAttributes,
    SampleType, SmallVec, Text, Vec2,
};
use serde::{Deserialize, Serialize};

use crate::atlas::{Atlas, Coords, Image};
use crate::color::{Sampling, SpectralIntegrator, White};
use crate::error::{Error, Result};
use crate::optics::Stack;
use crate::rough::slices::{self, slice_roughness, RoughSlices, GRAZING_COS};
use crate::stats::RoughFigures;
use crate::sweep::Side;

use super::file::{ascii_json, attribute_text, first_header, read_planes, write_layer};
use super::{BakeSpec, ColorInfo, Kind, Layout};

/// The header's `format`.
pub const ROUGH_FORMAT: &str = "irid-rough";
/// The header's `version`; a reader refuses any other.
pub const ROUGH_VERSION: u32 = 1;
/// The slice rule, as the header states it.
pub const SLICE_RULE: &str = "roughness = (s / (slices - 1))^2";
/// The image channels, in order.
pub const ROUGH_CHANNELS: [&str; 3] = ["reflectance.R", "reflectance.G", "reflectance.B"];
/// The header attribute's name (as in every irid table).
const ATTRIBUTE: &str = "irid";

/// The measured error of a rough table against irid's rough reflectance.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RoughErrorInfo {
    /// The largest absolute error per channel the slices were built for.
    pub target_max_abs: f64,
    /// cos θ below which the target is not sought (the grazing strip).
    pub grazing_cos: f64,
    /// The linear blend's error predicted from the slices' second
    /// differences.
    pub blend_error: f64,
    /// At random points with cos θ ≥ `grazing_cos`.
    pub measured: RoughFigures,
    /// At random points with cos θ < `grazing_cos`.
    pub grazing: RoughFigures,
}

/// Everything a reader needs besides the pixels.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RoughHeader {
    /// Always [`ROUGH_FORMAT`].
    pub format: String,
    /// Always [`ROUGH_VERSION`].
    pub version: u32,
    /// The slice count S.
    pub slices: usize,
    /// Always [`SLICE_RULE`].
    pub slice_rule: String,
    /// The front side's charts and one slice's size (as an atlas table's).
    pub atlas: Atlas,
    /// The full stack.
    pub stack: Stack,
    /// The varying layer (from 1).
    pub layer: usize,
    /// The colour integration.
    pub color: ColorInfo,
    /// The measured error.
    pub error: RoughErrorInfo,
    /// "irid <version>" that wrote the file.
    pub tool: String,
}

/// A rough table: F_eff(d, cos θ, roughness) of a film's front side.
#[derive(Clone, Debug)]
pub struct RoughLut {
    header: RoughHeader,
    slices: RoughSlices,
}

impl RoughLut {
    /// The table of `slices`, baked for `target` from `stack` (layer
    /// `layer`) with colour by `sampling` under `white`.
    pub fn new(
        slices: RoughSlices,
        stack: &Stack,
        layer: usize,
        (sampling, white): (Sampling, White),
        target: f64,
    ) -> RoughLut {
        let header = RoughHeader {
            format: ROUGH_FORMAT.into(),
            version: ROUGH_VERSION,
            slices: slices.slices.len(),
            slice_rule: SLICE_RULE.into(),
            atlas: slices.atlas.clone(),
            stack: stack.clone(),
            layer,
            color: ColorInfo {
                white,
                illuminant: white.illuminant().into(),
                observer: "CIE 1931 2°".into(),
                space: "linear sRGB (ITU-R BT.709 primaries, D65 white)".into(),
                sampling: sampling.to_string(),
            },
            error: RoughErrorInfo {
                target_max_abs: target,
                grazing_cos: GRAZING_COS,
                blend_error: slices.blend_error,
                measured: slices.measured.clone(),
                grazing: slices.grazing.clone(),
            },
            tool: format!("irid {}", env!("CARGO_PKG_VERSION")),
        };
        RoughLut { header, slices }
    }

    /// The header.
    pub fn header(&self) -> &RoughHeader {
        &self.header
    }

    /// The slices (atlas, roughness per slice, images).
    pub fn slices(&self) -> &RoughSlices {
        &self.slices
    }

    /// The colour integration the table was baked with.
    pub fn integrator(&self) -> Result<SpectralIntegrator> {
        let sampling: Sampling = self.header.color.sampling.parse()?;
        Ok(SpectralIntegrator::with_white(
            sampling,
            self.header.color.white,
        ))
    }

    /// F_eff at thickness `d` nm, cos θ `c`, roughness `r` (each clamped
    /// to the table's range): the chart by the atlas rule, bilinear in each
    /// of the two slices around √r · (S − 1), blended linearly.
    pub fn sample(&self, d: f64, c: f64, r: f64) -> [f64; 3] {
        self.slices.sample(d, c, r)
    }

    /// The table against irid's rough reflectance at random points drawn
    /// from the PCG64 stream of `seed` (see
    /// [`slices::measure_sampler`]): (cos θ ≥ the grazing strip,
    /// below it).
    pub fn validate(&self, seed: u64) -> Result<(RoughFigures, RoughFigures)> {
        slices::measure_sampler(
            &self.header.stack,
            self.header.layer,
            &self.integrator()?,
            (
                self.header.atlas.thickness_nm,
                slices::cos_span(&self.header.atlas),
            ),
            seed,
            &|d, c, r| self.sample(d, c, r),
        )
    }

    /// Writes the table atomically (a temporary file renamed over `path`).
    pub fn write(&self, path: &Path) -> Result<()> {
        crate::atomic::write_with(path, |tmp| self.write_to(tmp, path))
    }

    /// Writes the table's file at `tmp`; errors name `path`.
    pub fn write_to(&self, tmp: &Path, path: &Path) -> Result<()> {
        let (w, h) = (self.header.atlas.width, self.header.atlas.height);
        let json = serde_json::to_string(&self.header)
            .map_err(|e| Error::invalid("rough table header", e.to_string()))?;
        let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
        for (k, name) in ROUGH_CHANNELS.iter().enumerate() {
            let plane: Vec<f32> = self
                .slices
                .slices
                .iter()
                .flat_map(|img| img.data.iter().skip(k).step_by(img.channels).copied())
                .collect();
            list.push(AnyChannel::new(*name, FlatSamples::F32(plane)));
        }
        let mut attributes = LayerAttributes::default();
        attributes.other.insert(
            Text::from(ATTRIBUTE),
            AttributeValue::Text(Text::from(ascii_json(&json).as_str())),
        );
        let layer = Layer::new(
            (w, h * self.header.slices),
            attributes,
            Encoding::UNCOMPRESSED,
            AnyChannels::sort(list),
        );
        write_layer(layer, tmp, path)
    }

    /// Reads and checks a rough table: the header (format, version, slice
    /// count and rule, charts inside the atlas, the stack's layer) and the
    /// image's size and channels from the file's headers before a pixel is
    /// read, then the pixels, which must be finite. Any mismatch is an
    /// error naming the file, never a panic.
    pub fn load(path: &Path) -> Result<RoughLut> {
        let bad = |why: String| Error::malformed(path, why);
        let exr_header = first_header(path)?;
        let json = attribute_text(&exr_header).map_err(bad)?;
        let header = parse_header(&json).map_err(bad)?;
        let (w, h, s) = (header.atlas.width, header.atlas.height, header.slices);
        let size = exr_header.layer_size;
        if exr_header.deep || (size.0, size.1) != (w, h * s) {
            return Err(bad(format!(
                "the image is {}x{} pixels but the header gives {s} slices of {w}x{h}",
                size.0, size.1
            )));
        }
        let stored = &exr_header.channels.list;
        if stored.len() != 3
            || ROUGH_CHANNELS.iter().any(|n| {
                !stored.iter().any(|c| {
                    c.name == **n && c.sample_type == SampleType::F32 && c.sampling == Vec2(1, 1)
                })
            })
        {
            return Err(bad(format!(
                "a rough table has exactly the f32 channels {ROUGH_CHANNELS:?}"
            )));
        }
        crate::limits::check_allocation(
            &format!("{}: loading the rough table", path.display()),
            crate::limits::product(&[w as u64, (h * s) as u64, 3], 12),
        )?;
        let images = read_slices(path, &header).map_err(bad)?;
        let slices = RoughSlices {
            atlas: header.atlas.clone(),
            roughness: (0..s).map(|k| slice_roughness(k, s)).collect(),
            slices: images,
            blend_error: header.error.blend_error,
            measured: header.error.measured.clone(),
            grazing: header.error.grazing.clone(),
        };
        Ok(RoughLut { header, slices })
    }
}

/// Whether `path` is an OpenEXR file whose `irid` header says it is a
/// rough table (what `irid info` and `irid validate` dispatch on); false
/// for anything unreadable, which the smooth table's loader then reports.
pub fn is_rough_table(path: &Path) -> bool {
    first_header(path)
        .ok()
        .and_then(|h| attribute_text(&h).ok())
        .and_then(|json: String| serde_json::from_str::<serde_json::Value>(&json).ok())
        .is_some_and(|v| v.get("format").and_then(|f| f.as_str()) == Some(ROUGH_FORMAT))
}

/// The header from its JSON, checked: format and version first (so
/// another format is named as such), then every field a reader relies on.
fn parse_header(json: &str) -> std::result::Result<RoughHeader, String> {
    let value: serde_json::Value =
        serde_json::from_str(json).map_err(|e| format!("'{ATTRIBUTE}' header is not JSON: {e}"))?;
    if value.get("format").and_then(|f| f.as_str()) != Some(ROUGH_FORMAT) {
        return Err(format!(
            "header 'format' is not \"{ROUGH_FORMAT}\": not a rough table"
        ));
    }
    let version = value.get("version").and_then(|v| v.as_u64());
    if version != Some(u64::from(ROUGH_VERSION)) {
        return Err(format!(
            "rough table format version {} (this irid reads version {ROUGH_VERSION})",
            version.map_or("missing".into(), |v| v.to_string())
        ));
    }
    let header: RoughHeader =
        serde_json::from_value(value).map_err(|e| format!("'{ATTRIBUTE}' header: {e}"))?;
    if header.slice_rule != SLICE_RULE {
        return Err(format!("unknown slice rule '{}'", header.slice_rule));
    }
    if !(2..=slices::MAX_SLICES).contains(&header.slices) {
        return Err(format!(
            "{} slices (a rough table has 2 to {})",
            header.slices,
            slices::MAX_SLICES
        ));
    }
    check_atlas(&header.atlas)?;
    if header.layer == 0 || header.layer > header.stack.layers.len() {
        return Err(format!(
            "layer {} is not a layer of the stack ({} layers)",
            header.layer,
            header.stack.layers.len()
        ));
    }
    Ok(header)
}

/// The atlas a reader can trust: a positive size, a finite ascending
/// thickness range, and front-side charts of at least 2×2 nodes inside it
/// with finite coordinates.
fn check_atlas(atlas: &Atlas) -> std::result::Result<(), String> {
    let (t0, t1) = atlas.thickness_nm;
    if atlas.width == 0 || atlas.height == 0 || atlas.width > 1 << 16 || atlas.height > 1 << 16 {
        return Err(format!(
            "an atlas of {}x{} texels",
            atlas.width, atlas.height
        ));
    }
    if !(t0.is_finite() && t1.is_finite() && 0.0 <= t0 && t0 <= t1) {
        return Err(format!("thickness range {t0}..{t1}"));
    }
    if atlas.charts.is_empty() {
        return Err("no charts".into());
    }
    for (k, c) in atlas.charts.iter().enumerate() {
        let r = c.rect;
        let inside = r.width >= 2
            && r.height >= 2
            && r.x.checked_add(r.width).is_some_and(|e| e <= atlas.width)
            && r.y.checked_add(r.height).is_some_and(|e| e <= atlas.height);
        let finite = match c.coords {
            Coords::Band { p, c } => [p.p0_nm, p.lo_nm, p.hi_nm, c.lo, c.hi, c.anchor, c.offset]
                .iter()
                .all(|v| v.is_finite()),
            Coords::Corner { scale_nm, radius } => {
                scale_nm.is_finite() && scale_nm > 0.0 && radius.is_finite() && radius > 0.0
            }
        };
        if c.side != Side::Front || !inside || !finite {
            return Err(format!(
                "chart {k} is not a front chart of at least 2x2 texels inside the atlas with finite coordinates"
            ));
        }
    }
    Ok(())
}

/// The slices' images from the file (sizes checked before).
fn read_slices(path: &Path, header: &RoughHeader) -> std::result::Result<Vec<Image>, String> {
    let (w, h, s) = (header.atlas.width, header.atlas.height, header.slices);
    let planes = read_planes(path, (w, h * s), &ROUGH_CHANNELS)?;
    let mut slices = vec![Image::new(w, h, 3); s];
    for (k, (name, plane)) in ROUGH_CHANNELS.iter().zip(&planes).enumerate() {
        for (p, &v) in plane.iter().enumerate() {
            if !v.is_finite() {
                return Err(format!(
                    "channel '{name}' holds {v} at texel ({}, {}) of slice {}",
                    p % w,
                    (p / w) % h,
                    p / (w * h)
                ));
            }
            slices[p / (w * h)].data[(p % (w * h)) * 3 + k] = v;
        }
    }
    Ok(slices)
}

/// The largest texture side of a rough table's atlas.
const MAX_ATLAS_SIDE: usize = 8192;

/// Bakes the rough table of `spec` (an rgb film in the atlas layout): the
/// smooth atlas first (its front charts and texels are slice 0), then the
/// slices for `max_error`, measured against irid's rough reflectance.
/// `progress` receives one line per stage.
pub fn bake_rough(spec: &BakeSpec, max_error: f64, progress: &dyn Fn(&str)) -> Result<RoughLut> {
    if !(max_error > 0.0 && max_error.is_finite()) {
        return Err(Error::invalid(
            "rough-max-error",
            format!("{max_error} is not a positive number"),
        ));
    }
    if spec.kind != Kind::Rgb {
        return Err(Error::invalid(
            "rough",
            "a rough table holds the rgb colour F_eff; a spectral table cannot hold it (bake --kind rgb)",
        ));
    }
    if spec.layout() != Layout::Atlas {
        return Err(Error::invalid(
            "rough",
            "a rough table is built on the atlas: bake with an error target, not --resolution or --layout grid",
        ));
    }
    let smooth = super::bake(spec)?;
    let header = smooth.header();
    let table = header
        .atlas
        .as_ref()
        .ok_or_else(|| Error::invalid("rough", "the smooth bake gave no atlas"))?;
    crate::rough::refuse_unsought_band(table.critical_band_cos.map(|[lo, hi]| (lo, hi)))?;
    let channels = header.channel_names().len();
    let image = Image {
        width: table.atlas.width,
        height: smooth.data().len() / (table.atlas.width * channels),
        channels,
        data: smooth.data().to_vec(),
    };
    let integrator = SpectralIntegrator::with_white(spec.sampling, spec.white);
    let film = crate::atlas::Film::new(&spec.stack, spec.layer, integrator.clone())?;
    let request = slices::SliceRequest {
        film: &film,
        atlas: &table.atlas,
        image: &image,
        max_error,
        max_side: MAX_ATLAS_SIDE,
        reference: None,
    };
    let built = slices::build(&spec.stack, spec.layer, &integrator, &request, progress)?;
    Ok(RoughLut::new(
        built,
        &spec.stack,
        spec.layer,
        (spec.sampling, spec.white),
        max_error,
    ))
}
