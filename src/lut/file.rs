//! Tables on disk: a single-part scanline OpenEXR image (half-float tables
//! ZIP-compressed, float tables uncompressed: see [`encoding`]), one channel
//! per stored quantity, and the JSON header in a text attribute named
//! `irid`. See `docs/lut-format.md`.

use std::path::Path;

use exr::meta::header::Header as ExrHeader;
use exr::meta::MetaData;
use exr::prelude::{
    read, AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, Layer,
    LayerAttributes, ReadChannels, ReadLayers, SampleType, SmallVec, Text, Vec2, WritableImage,
};

use super::header::{
    readable_version, version_for, Header, FORMAT_NAME, NEWEST_READABLE_VERSION,
    OLDEST_READABLE_VERSION,
};
use super::sample::{check_header, Lut};
use super::Kind;
use crate::error::{Error, Result};

/// How a table's pixels are stored. Deflate pays on half floats (5–25 %
/// smaller on the tables of `luts/`) but hardly on 32-bit floats, whose low
/// mantissa bits are noise to it: the default rgb bake's table is 2.4 %
/// smaller with ZIP, and compressing it took four times as long as writing
/// it uncompressed (about 8 ms against 2 of a 75 ms bake). Both are
/// lossless, and every OpenEXR reader opens either.
fn encoding(half: bool) -> Encoding {
    if half {
        Encoding::SMALL_LOSSLESS
    } else {
        Encoding::UNCOMPRESSED
    }
}

/// The header attribute's name.
pub const ATTRIBUTE: &str = "irid";

impl Lut {
    /// Writes the table atomically: to a temporary file in the same
    /// directory, then renamed over `path`, so an interrupted write never
    /// leaves a partial table behind.
    pub fn write(&self, path: &Path) -> Result<()> {
        crate::atomic::write_with(path, |tmp| self.write_to(tmp, path))
    }

    /// Writes the table's file at `tmp` (an output's temporary, see
    /// [`crate::atomic::OutputSet`]); errors name `path`, the output.
    pub fn write_to(&self, tmp: &Path, path: &Path) -> Result<()> {
        let header = self.header();
        let channels = header.channel_names();
        let width = match &header.atlas {
            Some(t) => t.atlas.width,
            None => header.axes[0].nodes.len(),
        };
        let height = self.data().len() / (width * channels.len());
        let half = header.precision == "f16";
        // A table read from an older version is written in the current one:
        // its header is valid in this version too (see OLDEST_READABLE_VERSION).
        let current = Header {
            version: version_for(header.color.white, header.atlas.is_some()),
            ..header.clone()
        };
        let json = serde_json::to_string(&current)
            .map_err(|e| Error::invalid("table header", e.to_string()))?;
        let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
        for (k, name) in channels.iter().enumerate() {
            let plane = self.data().iter().skip(k).step_by(channels.len()).copied();
            let samples = if half {
                FlatSamples::F16(plane.map(half::f16::from_f32).collect())
            } else {
                FlatSamples::F32(plane.collect())
            };
            list.push(AnyChannel::new(*name, samples));
        }
        let mut attributes = LayerAttributes::default();
        attributes.other.insert(
            Text::from(ATTRIBUTE),
            AttributeValue::Text(Text::from(ascii_json(&json).as_str())),
        );
        let layer = Layer::new(
            (width, height),
            attributes,
            encoding(half),
            AnyChannels::sort(list),
        );
        write_layer(layer, tmp, path)
    }

    /// Reads and checks a table: the `irid` header's format name and
    /// version, axes, channel names and node counts against the image, all
    /// from the file's headers before a pixel is read, so a small file that
    /// declares a vast data window is refused without allocating it. Then
    /// the pixels, which must be finite. Any mismatch is an error naming the
    /// file, never a panic.
    pub fn load(path: &Path) -> Result<Lut> {
        let bad = |why: String| Error::malformed(path, why);
        let exr_header = first_header(path)?;
        let exr_header = &exr_header;
        let header = parse_header(exr_header).map_err(bad)?;
        let (width, height) = check_header(&header).map_err(bad)?;
        let sample_type = check_image(exr_header, &header, width, height).map_err(bad)?;
        check_load_allocation(path, &header, width, height, sample_type)?;
        let data = read_pixels(path, &header, width, height).map_err(bad)?;
        Lut::from_parts(header, data).map_err(bad)
    }
}

/// Writes one OpenEXR layer at `tmp`; errors name `path`, the output.
pub(crate) fn write_layer(
    layer: Layer<AnyChannels<FlatSamples>>,
    tmp: &Path,
    path: &Path,
) -> Result<()> {
    Image::from_layer(layer)
        .write()
        .to_file(tmp)
        .map_err(|e| match e {
            exr::error::Error::Io(io) => Error::io(path, io),
            other => Error::malformed(path, format!("cannot write OpenEXR: {other}")),
        })
}

/// The first (flat) image's header of the OpenEXR file at `path`, read
/// without its pixels. The system refusing the file (a folder, no
/// permission) is an I/O error; a file that ends too soon is malformed.
pub(crate) fn first_header(path: &Path) -> Result<ExrHeader> {
    let bad = |why: String| Error::malformed(path, why);
    if let Err(e) = std::fs::metadata(path) {
        return Err(Error::io(path, e));
    }
    let meta = MetaData::read_from_file(path, false).map_err(|e| match e {
        exr::error::Error::Io(io) if io.kind() != std::io::ErrorKind::UnexpectedEof => {
            Error::io(path, io)
        }
        e => bad(format!("not a readable OpenEXR file: {e}")),
    })?;
    let exr_header = meta
        .headers
        .into_iter()
        .next()
        .ok_or_else(|| bad("an OpenEXR file without an image".into()))?;
    if exr_header.deep {
        return Err(bad("a deep OpenEXR image is not an irid table".into()));
    }
    Ok(exr_header)
}

/// The text of the header's `irid` attribute.
pub(crate) fn attribute_text(exr_header: &ExrHeader) -> std::result::Result<String, String> {
    let text = exr_header
        .own_attributes
        .other
        .get(&Text::from(ATTRIBUTE))
        .or_else(|| {
            exr_header
                .shared_attributes
                .other
                .get(&Text::from(ATTRIBUTE))
        })
        .ok_or_else(|| format!("no '{ATTRIBUTE}' header attribute: not an irid table"))?;
    let AttributeValue::Text(text) = text else {
        return Err(format!("the '{ATTRIBUTE}' attribute is not text"));
    };
    Ok(text.bytes().iter().map(|&b| b as char).collect())
}

/// The `irid` attribute as a [`Header`]. The format name and version are
/// checked on the raw JSON first, so a table from another format or a
/// newer irid is named as such rather than as a field serde cannot parse.
fn parse_header(exr_header: &ExrHeader) -> std::result::Result<Header, String> {
    let json = attribute_text(exr_header)?;
    let value: serde_json::Value = serde_json::from_str(&json)
        .map_err(|e| format!("'{ATTRIBUTE}' header is not JSON: {e}"))?;
    if value.get("format").and_then(|f| f.as_str()) != Some(FORMAT_NAME) {
        return Err(format!("header 'format' is not \"{FORMAT_NAME}\""));
    }
    let version = value.get("version").and_then(|v| v.as_u64());
    if !version.is_some_and(readable_version) {
        return Err(format!(
            "format version {} (this irid reads versions {OLDEST_READABLE_VERSION} to {NEWEST_READABLE_VERSION})",
            version.map_or("missing".into(), |v| v.to_string()),
        ));
    }
    serde_json::from_value(value).map_err(|e| format!("'{ATTRIBUTE}' header: {e}"))
}

/// The image's size and channels against the header, from the file's
/// headers alone. Returns the sample type every channel is stored in.
fn check_image(
    exr_header: &ExrHeader,
    header: &Header,
    width: usize,
    height: usize,
) -> std::result::Result<SampleType, String> {
    let names = header.channel_names();
    let size = exr_header.layer_size;
    if (size.0, size.1) != (width, height) {
        return Err(format!(
            "the image is {}x{} pixels but the header's axes give {width}x{height} ({} thickness nodes across, cos θ{} nodes down)",
            size.0,
            size.1,
            header.axes[0].nodes.len(),
            if header.kind == Kind::Spectral { " × wavelength" } else { "" },
        ));
    }
    let stored = &exr_header.channels.list;
    if stored.len() != names.len() {
        return Err(format!(
            "{} channels, a {} table has exactly {names:?}",
            stored.len(),
            header.kind
        ));
    }
    let want_type = if header.precision == "f16" {
        SampleType::F16
    } else {
        SampleType::F32
    };
    for name in names {
        let channel = stored
            .iter()
            .find(|c| c.name == **name)
            .ok_or_else(|| format!("missing channel '{name}'"))?;
        if channel.sample_type != want_type || channel.sampling != Vec2(1, 1) {
            return Err(format!(
                "channel '{name}' sample type differs from header precision {}",
                header.precision
            ));
        }
    }
    Ok(want_type)
}

/// Refuses a table whose loading would exceed the memory budget, before
/// the reader allocates its planes.
fn check_load_allocation(
    path: &Path,
    header: &Header,
    width: usize,
    height: usize,
    sample_type: SampleType,
) -> Result<()> {
    // The reader's planes (stored sample size), their f32 copies, the
    // interleaved table and, for rgb, its SIMD layout (32 bytes a node).
    let channels = header.channel_names().len() as u64;
    let values = (width as u64).checked_mul(height as u64);
    let per_value = sample_type.bytes_per_sample() as u64 + 8;
    let estimate = values.and_then(|v| {
        let nodes_extra = if header.kind == Kind::Rgb { 32 } else { 0 };
        crate::limits::product(&[v, channels], per_value)?.checked_add(v.checked_mul(nodes_extra)?)
    });
    crate::limits::check_allocation(&format!("{}: loading the table", path.display()), estimate)
}

/// The pixels, interleaved channel by channel in the header's order.
fn read_pixels(
    path: &Path,
    header: &Header,
    width: usize,
    height: usize,
) -> std::result::Result<Vec<f32>, String> {
    let names = header.channel_names();
    let planes = read_planes(path, (width, height), names)?;
    let mut data = vec![0.0f32; width * height * names.len()];
    for (k, plane) in planes.iter().enumerate() {
        for (p, &v) in plane.iter().enumerate() {
            data[p * names.len() + k] = v;
        }
    }
    Ok(data)
}

/// The channels `names` of the file's first layer as f32 planes, the
/// image `size` (checked on an earlier read of its headers).
pub(crate) fn read_planes(
    path: &Path,
    size: (usize, usize),
    names: &[&str],
) -> std::result::Result<Vec<Vec<f32>>, String> {
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| format!("not a readable OpenEXR file: {e}"))?;
    let layer = &image.layer_data;
    if (layer.size.0, layer.size.1) != size {
        return Err("the image's size changed while it was read".into());
    }
    names
        .iter()
        .map(|name| {
            let channel = layer
                .channel_data
                .list
                .iter()
                .find(|c| c.name == **name)
                .ok_or_else(|| format!("missing channel '{name}'"))?;
            if channel.sample_data.len() != size.0 * size.1 {
                return Err(format!("channel '{name}' holds too few samples"));
            }
            Ok(channel.sample_data.values_as_f32().collect())
        })
        .collect()
}

/// EXR text is bytes; JSON allows any character as a \u escape, so the
/// header is stored as plain ASCII that every reader decodes the same way.
pub(crate) fn ascii_json(json: &str) -> String {
    let mut out = String::with_capacity(json.len());
    for c in json.chars() {
        if c.is_ascii() {
            out.push(c);
        } else {
            let mut buf = [0u16; 2];
            for unit in c.encode_utf16(&mut buf) {
                out.push_str(&format!("\\u{unit:04x}"));
            }
        }
    }
    out
}
