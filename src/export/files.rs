//! The export directory: two RGBA half-float OpenEXR textures, optional
//! 16-bit PNGs, film.json and the shaders, written into a temporary
//! directory beside the target and renamed into place (a folder output of
//! [`crate::atomic::OutputSet`]).

use std::path::Path;

use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, SmallVec,
    WritableImage,
};
use serde_json::json;

use super::mapping::{Texture, PARAM_NAMES};
use super::{Export, SHADERS};
use crate::atomic::{Output, OutputSet, Prepared, Replace};
use crate::error::{Error, Result};

/// film.json's `format` and `version`.
pub const FILM_FORMAT: &str = "irid-film";
/// See [`FILM_FORMAT`].
pub const FILM_VERSION: u32 = 1;

/// The PNGs' scale: texel value = PNG value / 65535 × scale. 1 when every
/// value lies in [0, 1], else the largest value rounded up to a multiple of
/// 1/16 (a gain film, or a passive one whose saturated colours exceed 1 in
/// a channel: the sRGB matching functions have negative lobes).
pub(super) fn png_scale(export: &Export) -> f64 {
    let largest = [&export.reflectance, &export.transmittance]
        .iter()
        .flat_map(|t| t.texels.iter().flat_map(|x| x[..3].iter()))
        .fold(0.0f32, |a, &b| a.max(b));
    if largest <= 1.0 {
        1.0
    } else {
        (f64::from(largest) * 16.0).ceil() / 16.0
    }
}

/// A texture's RGB as 16-bit PNG values (alpha 65535).
fn png_values(texture: &Texture, scale: f64) -> Vec<u16> {
    texture
        .texels
        .iter()
        .flat_map(|x| {
            let q = |v: f32| {
                (f64::from(v.max(0.0)) / scale * 65535.0)
                    .round()
                    .min(65535.0) as u16
            };
            [q(x[0]), q(x[1]), q(x[2]), 65535]
        })
        .collect()
}

/// The textures a loader gets from the PNGs (value / 65535 × scale).
pub(super) fn png_textures(export: &Export, scale: f64) -> (Texture, Texture) {
    let back = |t: &Texture| Texture {
        width: t.width,
        height: t.height,
        texels: png_values(t, scale)
            .chunks_exact(4)
            .map(|q| {
                let v = |k: usize| (f64::from(q[k]) / 65535.0 * scale) as f32;
                [v(0), v(1), v(2), 1.0]
            })
            .collect(),
    };
    (back(&export.reflectance), back(&export.transmittance))
}

fn write_exr(texture: &Texture, path: &Path) -> Result<()> {
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (k, name) in ["R", "G", "B", "A"].iter().enumerate() {
        let plane = texture
            .texels
            .iter()
            .map(|x| half::f16::from_f32(x[k]))
            .collect();
        list.push(AnyChannel::new(*name, FlatSamples::F16(plane)));
    }
    let layer = Layer::new(
        (texture.width, texture.height),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    Image::from_layer(layer)
        .write()
        .to_file(path)
        .map_err(|e| match e {
            exr::error::Error::Io(io) => Error::io(path, io),
            other => Error::malformed(path, format!("cannot write OpenEXR: {other}")),
        })
}

fn write_png(texture: &Texture, scale: f64, path: &Path) -> Result<()> {
    let values = png_values(texture, scale);
    let image = image::ImageBuffer::<image::Rgba<u16>, Vec<u16>>::from_raw(
        texture.width as u32,
        texture.height as u32,
        values,
    )
    .ok_or_else(|| Error::invalid("png", "texture size does not match its texels"))?;
    image
        .save_with_format(path, image::ImageFormat::Png)
        .map_err(|e| Error::malformed(path, format!("cannot write PNG: {e}")))
}

fn error_json(e: &super::ExportError) -> serde_json::Value {
    json!({
        "max_abs": e.max_abs,
        "p99_abs": e.p99_abs,
        "mean_abs": e.mean_abs,
        "max_delta_e00": e.max_delta_e00,
        "mean_delta_e00": e.mean_delta_e00,
        "points": e.points,
        "seed": e.seed,
        "worst_point": e.worst_point,
    })
}

/// film.json's `row_check` of one texture (see [`Texture::row_check`]):
/// f16 values, written exactly.
fn row_check_json(texture: &Texture) -> serde_json::Value {
    match texture.row_check() {
        Some(c) => json!({
            "x": c.x,
            "y": c.y,
            "value": c.value.map(f64::from),
            "mirrored": c.mirrored.map(f64::from),
        }),
        None => serde_json::Value::Null,
    }
}

/// film.json: everything a third party needs to use the textures.
pub fn film_json(export: &Export) -> serde_json::Value {
    let m = &export.mapping;
    let params: serde_json::Map<String, serde_json::Value> = PARAM_NAMES
        .iter()
        .zip(m.params_f32())
        .map(|(name, v)| (name.to_string(), json!(v)))
        .collect();
    let spec = &export.spec;
    let mut error = error_json(&export.error);
    error["target_max_abs"] = json!(spec.max_error);
    error["channels"] = json!(["R.r", "R.g", "R.b", "T.r", "T.g", "T.b"]);
    error["metric"] = json!(
        "absolute difference between the bilinear filtering (f32 weights, clamp to edge) of the f16 \
         texels at the shader's texture coordinates and irid's exact solver, at random points uniform \
         over the domain; delta_e00 is CIEDE2000 of the reflected [0] and transmitted [1] colour"
    );
    error["weights_8bit_extra_max_abs"] = json!(export.weights_8bit_extra);
    error["png"] = match &export.png {
        Some((_, e)) => error_json(e),
        None => serde_json::Value::Null,
    };
    let png = match &export.png {
        Some((scale, _)) => json!({
            "reflectance": "reflectance.png",
            "transmittance": "transmittance.png",
            "scale": scale,
        }),
        None => serde_json::Value::Null,
    };
    json!({
        "format": FILM_FORMAT,
        "version": FILM_VERSION,
        "texture": {
            "width": m.size_u,
            "height": m.size_v,
            "format": "rgba16f",
            "files": {"reflectance": "reflectance.exr", "transmittance": "transmittance.exr"},
            "png": png,
            "row_check": {
                "reflectance": row_check_json(&export.reflectance),
                "transmittance": row_check_json(&export.transmittance),
            },
        },
        "domain": {
            "thickness_nm": [m.thickness_min_nm, m.thickness_max_nm],
            "cos_theta": [m.cos_min, m.cos_max],
        },
        "params": params,
        "white": spec.white.name(),
        "color": {
            "illuminant": spec.white.illuminant(),
            "observer": "CIE 1931 2°",
            "space": "linear sRGB (IEC 61966-2-1 primaries)",
        },
        "stack": spec.stack,
        "layer": if spec.stack.layers.is_empty() { 0 } else { spec.layer },
        "sampling": spec.sampling.to_string(),
        "opaque": export.opaque,
        "error": error,
        "axes": {
            "thickness_nm": m.thickness_nodes(),
            "cos_theta": m.cos_nodes(),
        },
        "shaders": SHADERS.iter().map(|(name, _)| *name).collect::<Vec<_>>(),
        "tool": concat!("irid ", env!("CARGO_PKG_VERSION")),
    })
}

/// Writes the export into `dir`, atomically: every file goes into a
/// temporary directory beside it, which then takes `dir`'s place (see
/// [`crate::atomic`]). An existing `dir` is replaced only when it is empty
/// or an earlier export (it holds a film.json of this format): anything
/// else is refused rather than deleted.
pub fn write_dir(export: &Export, dir: &Path) -> Result<()> {
    let mut set = OutputSet::new();
    let output = declare_dir(&mut set, dir);
    let mut prepared = set.prepare()?;
    fill_dir(export, &mut prepared, output)?;
    prepared.commit()
}

/// Declares `dir` as an export folder of `set`, so that its path is
/// checked before the export is computed; [`fill_dir`] writes it.
pub fn declare_dir(set: &mut OutputSet, dir: &Path) -> Output {
    set.folder(
        dir,
        Replace {
            allowed: replaceable,
            otherwise:
                "exists and is neither empty nor an irid export; choose another -o or remove it",
        },
    )
}

/// Writes the export into its folder of a prepared set, to appear when the
/// set commits.
pub fn fill_dir(export: &Export, prepared: &mut Prepared, output: Output) -> Result<()> {
    prepared.write(output, |tmp| fill(export, tmp))
}

/// Whether an existing directory may be replaced: empty, or an export.
fn replaceable(dir: &Path) -> bool {
    let empty = std::fs::read_dir(dir).is_ok_and(|mut d| d.next().is_none());
    empty
        || std::fs::read_to_string(dir.join("film.json"))
            .ok()
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
            .is_some_and(|v| v["format"] == FILM_FORMAT)
}

fn fill(export: &Export, tmp: &Path) -> Result<()> {
    std::fs::create_dir(tmp).map_err(|e| Error::io(tmp, e))?;
    write_exr(&export.reflectance, &tmp.join("reflectance.exr"))?;
    write_exr(&export.transmittance, &tmp.join("transmittance.exr"))?;
    if let Some((scale, _)) = export.png {
        write_png(&export.reflectance, scale, &tmp.join("reflectance.png"))?;
        write_png(&export.transmittance, scale, &tmp.join("transmittance.png"))?;
    }
    let json = serde_json::to_string_pretty(&film_json(export))
        .map_err(|e| Error::invalid("film.json", e.to_string()))?;
    let path = tmp.join("film.json");
    std::fs::write(&path, json + "\n").map_err(|e| Error::io(&path, e))?;
    for (file, text) in SHADERS {
        let path = tmp.join(file);
        std::fs::write(&path, text).map_err(|e| Error::io(&path, e))?;
    }
    Ok(())
}
