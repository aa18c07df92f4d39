//! The export directory: the atlas's two RGBA half-float OpenEXR textures,
//! optional 16-bit PNGs, film.json and the shaders, written into a
//! temporary directory beside the target and renamed into place (a folder
//! output of [`crate::atomic::OutputSet`]).

use std::path::Path;

use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, SmallVec,
    WritableImage,
};
use serde_json::json;

use super::{Export, Side, Texture, HEADER_VEC4, SHADERS, UNIFORM_VEC4};
use crate::atlas::{Atlas, Chart, Coords, PARAMS_PER_CHART};
use crate::atomic::{Output, OutputSet, Prepared, Replace};
use crate::error::{Error, Result};

/// film.json's `format` and `version`.
pub const FILM_FORMAT: &str = "irid-film";
/// See [`FILM_FORMAT`]. Version 1 had one chart (the front) and its
/// parameters as nine named fields; 2 an atlas of one chart per side in
/// physical thickness with square-root warps; 3 is the atlas of
/// [`crate::atlas`] (bands in optical thickness, a polar corner chart, the
/// chart chosen in closed form per lookup).
pub const FILM_VERSION: u32 = 3;

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

pub(super) fn write_exr(texture: &Texture, path: &Path) -> Result<()> {
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

/// An error's figures as film.json states them: its fields by name (a
/// side's and the rough table's [`crate::stats::Figures`]).
pub(super) fn error_json<E: serde::Serialize>(e: &E) -> serde_json::Value {
    // Numbers and arrays of numbers: nothing that can fail to serialize.
    serde_json::to_value(e).unwrap_or(serde_json::Value::Null)
}

/// The name of a side in film.json.
fn side_name(side: Side) -> &'static str {
    match side {
        Side::Front => "front",
        Side::Back => "back",
    }
}

/// The names of a chart's uniform values by its kind (docs/gpu.md); empty
/// names are zeros.
pub fn chart_param_names(chart: &Chart) -> [&'static str; PARAMS_PER_CHART] {
    let head = ["x0", "y0", "width", "height", "side", "kind", "a", "floor"];
    let tail = match chart.coords {
        Coords::Band { .. } => [
            "p0_nm", "p_lo_nm", "p_hi_nm", "", "cos_lo", "cos_hi", "anchor", "offset",
        ],
        Coords::Corner { .. } => ["scale_nm", "radius", "", "", "", "", "", ""],
    };
    let mut names = [""; PARAMS_PER_CHART];
    names[..8].copy_from_slice(&head);
    names[8..].copy_from_slice(&tail);
    names
}

/// film.json's `charts` (and `rough.charts`): each chart of `atlas` with
/// its side, kind, rectangle and named parameters (the values of the
/// uniform array, as f32), and its coordinates in full precision.
pub(super) fn charts_json(atlas: &Atlas) -> serde_json::Value {
    let uniform = atlas.uniform_f32();
    let charts: Vec<serde_json::Value> = atlas
        .charts
        .iter()
        .enumerate()
        .map(|(k, chart)| {
            let at = 4 * HEADER_VEC4 + k * PARAMS_PER_CHART;
            let params: serde_json::Map<String, serde_json::Value> = chart_param_names(chart)
                .iter()
                .zip(&uniform[at..at + PARAMS_PER_CHART])
                .filter(|(name, _)| !name.is_empty())
                .map(|(name, v)| (name.to_string(), json!(v)))
                .collect();
            let r = chart.rect;
            json!({
                "side": chart.side,
                "kind": match chart.coords {
                    Coords::Band { .. } => "band",
                    Coords::Corner { .. } => "corner",
                },
                "rect": [r.x, r.y, r.width, r.height],
                "params": params,
                "optical": chart.optical,
                "coords": chart.coords,
            })
        })
        .collect();
    json!(charts)
}

/// film.json's `sides`: for each side, its number in the shader, the
/// charts it reads, the stack as seen from it, where its colour
/// integration is aliased and its dispersive critical band; `back` is null when light cannot arrive from
/// the substrate (its lookups then read the front's charts).
fn sides_json(export: &Export) -> serde_json::Value {
    let spec = &export.spec;
    let entry = |side: Side| match export.side(side) {
        None => serde_json::Value::Null,
        Some(s) => {
            let seen = spec.seen_from(side);
            json!({
                "index": side.index(),
                "charts": s.charts,
                "light_from": if side == Side::Front { "ambient" } else { "substrate" },
                "stack": if side == Side::Front { "as written" } else { "reversed" },
                "layer": if seen.stack.layers.is_empty() { 0 } else { seen.layer },
                "critical_cos": super::critical_cos(&seen.stack),
                "aliased_below_cos": s.aliased_below,
                "critical_band_cos": s.critical_band.map(|(a, b)| [a, b]),
            })
        }
    };
    json!({ "front": entry(Side::Front), "back": entry(Side::Back) })
}

/// film.json's `refraction`: the substrate's index over the ambient's at
/// 550 nm (real parts), for hosts that bend transmitted rays; null when no
/// light leaves through the substrate.
fn refraction_json(export: &Export) -> serde_json::Value {
    const NM: f64 = 550.0;
    let stack = &export.spec.stack;
    match (stack.ambient.index_at(NM), stack.substrate.index_at(NM)) {
        (Ok(n0), Ok(ns)) if !export.opaque => json!({
            "wavelength_nm": NM,
            "substrate_over_ambient": ns.re / n0.re,
        }),
        _ => serde_json::Value::Null,
    }
}

/// film.json's `error`: each side's measured error, its target, the 8-bit
/// filter bound and the PNGs' error.
fn errors_json(export: &Export) -> serde_json::Value {
    let mut error = json!({
        "channels": ["R.r", "R.g", "R.b", "T.r", "T.g", "T.b"],
        "metric": "absolute difference (relative to the exact value where that exceeds 1 in magnitude: \
         |got - exact| / max(1, |exact|), as f16 is a floating format) between the bilinear filtering (f32 weights, clamp to edge) of the f16 \
         texels at the shader's texture coordinates (f32) and irid's exact solver on the stack as seen from the \
         side, at random points uniform over the whole domain; delta_e00 is CIEDE2000 of the reflected [0] and \
         transmitted [1] colour; aliased: the same over the points below the side's aliased_below_cos, where \
         the colour integration itself is aliased and the target is not sought (null when there are none);          critical_band: the same at points of its own uniform over the side's critical_band_cos, the band over          which a dispersive ambient's critical angle moves, where the target is not sought either (null when the          side has no such band); sought: the same over the points where the target is sought (above \
         aliased_below_cos, outside critical_band_cos; null when that is every point)",
        "front": null,
        "back": null,
    });
    for side in &export.sides {
        let mut e = error_json(&side.error);
        e["target_max_abs"] = json!(export.spec.target(side.side));
        e["weights_8bit_extra_max_abs"] = json!(side.weights_8bit_extra);
        e["aliased"] = side.aliased_error.as_ref().map_or(
            serde_json::Value::Null,
            error_json::<crate::stats::ColourFigures>,
        );
        e["sought"] = side.sought_error.as_ref().map_or(
            serde_json::Value::Null,
            error_json::<crate::stats::ColourFigures>,
        );
        e["critical_band"] = side.critical_error.as_ref().map_or(
            serde_json::Value::Null,
            error_json::<crate::stats::ColourFigures>,
        );
        e["png"] = side.png_error.as_ref().map_or(
            serde_json::Value::Null,
            error_json::<crate::stats::ColourFigures>,
        );
        error[side_name(side.side)] = e;
    }
    error
}

/// film.json's `row_check` of one texture (see [`Texture::row_check`]):
/// f16 values, written exactly.
pub(super) fn row_check_json(texture: &Texture) -> serde_json::Value {
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
    let spec = &export.spec;
    let png = match export.png_scale {
        Some(scale) => json!({
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
            "width": export.atlas.width,
            "height": export.atlas.height,
            "format": "rgba16f",
            "alpha": "1 everywhere: WebGPU has no 3-channel 16-bit float format (docs/gpu.md)",
            "files": {"reflectance": "reflectance.exr", "transmittance": "transmittance.exr"},
            "png": png,
            "row_check": {
                "reflectance": row_check_json(&export.reflectance),
                "transmittance": row_check_json(&export.transmittance),
            },
        },
        "domain": {
            "thickness_nm": [spec.thickness_nm.0, spec.thickness_nm.1],
            "cos_theta": [spec.cos_theta.0, spec.cos_theta.1],
        },
        "uniform_f32": export.uniform_f32(),
        "uniform_vec4": UNIFORM_VEC4,
        "charts": charts_json(&export.atlas),
        "sides": sides_json(export),
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
        "refraction": refraction_json(export),
        "error": errors_json(export),
        "rough": export.rough.as_ref().map_or(serde_json::Value::Null, super::rough::rough_json),
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

/// Writes each (file name, text) into `dir`.
pub(super) fn write_texts(dir: &Path, files: &[(&str, &str)]) -> Result<()> {
    for (file, text) in files {
        let path = dir.join(file);
        std::fs::write(&path, text).map_err(|e| Error::io(&path, e))?;
    }
    Ok(())
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
    if let Some(scale) = export.png_scale {
        write_png(&export.reflectance, scale, &tmp.join("reflectance.png"))?;
        write_png(&export.transmittance, scale, &tmp.join("transmittance.png"))?;
    }
    let json = serde_json::to_string_pretty(&film_json(export))
        .map_err(|e| Error::invalid("film.json", e.to_string()))?;
    let path = tmp.join("film.json");
    std::fs::write(&path, json + "\n").map_err(|e| Error::io(&path, e))?;
    write_texts(tmp, &SHADERS)?;
    if let Some(rough) = &export.rough {
        super::rough::fill(rough, tmp)?;
    }
    Ok(())
}
