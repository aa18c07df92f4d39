//! The browser preview: writes a folder holding the WebGL2 page of `web/`
//! and one or more exports (`irid export` folders), ready to open.
//!
//! The page's assets are compiled into the binary, so a preview never mixes
//! a page and an irid of different versions. The exports are copied into
//! `exports/NAME/` (the page can fetch them when the folder is served) and
//! embedded in `exports.js`, base64 for the textures, because a page opened
//! from `file://` may run scripts but not fetch files.

use std::fs;
use std::path::{Path, PathBuf};

use serde_json::{json, Map, Value};

use crate::atomic::{OutputSet, Replace};
use crate::error::{Error, Result};

/// The page's files, as `web/` holds them (index.html loads the scripts).
const ASSETS: [(&str, &str); 12] = [
    ("index.html", include_str!("../web/index.html")),
    ("style.css", include_str!("../web/style.css")),
    ("png16.js", include_str!("../web/png16.js")),
    ("exr.js", include_str!("../web/exr.js")),
    ("film-json.js", include_str!("../web/film-json.js")),
    (
        "preview/sources.js",
        include_str!("../web/preview/sources.js"),
    ),
    (
        "preview/export.js",
        include_str!("../web/preview/export.js"),
    ),
    (
        "preview/meshes.js",
        include_str!("../web/preview/meshes.js"),
    ),
    (
        "preview/matrices.js",
        include_str!("../web/preview/matrices.js"),
    ),
    (
        "preview/shaders.js",
        include_str!("../web/preview/shaders.js"),
    ),
    ("preview/ggx.js", include_str!("../web/preview/ggx.js")),
    ("preview/page.js", include_str!("../web/preview/page.js")),
];

/// The file a preview folder is recognised by (and may be replaced for).
const MARKER: &str = "exports.js";

/// One export, read and checked.
struct Export {
    name: String,
    /// Every regular file of the export folder, by file name.
    files: Vec<(String, Vec<u8>)>,
    /// The files the page reads: film.json, the sampler, two textures.
    used: Vec<String>,
}

/// What [`write_preview`] wrote.
#[derive(Debug)]
pub struct Preview {
    /// The page to open: `index.html` inside the preview folder.
    pub index: PathBuf,
    /// The names the exports are listed under in the page, in order.
    pub exports: Vec<String>,
}

/// Writes a preview of `exports` (export folders) into `out`. `out` must not
/// exist, be empty, or be an earlier preview (which is replaced whole), and
/// is checked before the exports are read. The preview is assembled beside
/// `out` and moved into place at the end (a folder output of
/// [`crate::atomic::OutputSet`]), so a failure leaves no half-written folder.
pub fn write_preview(exports: &[PathBuf], out: &Path) -> Result<Preview> {
    if exports.is_empty() {
        return Err(Error::invalid("exports", "give at least one export folder"));
    }
    let mut set = OutputSet::new();
    for dir in exports {
        set.input(dir);
    }
    let folder = set.folder(
        out,
        Replace {
            allowed: replaceable,
            otherwise:
                "exists and holds files that are not an irid preview; give a new or empty folder",
        },
    );
    let mut prepared = set.prepare()?;
    let mut read = Vec::new();
    for dir in exports {
        let mut export = read_export(dir)?;
        // Two folders of the same name (a/film, b/film) get film, film-2, ...
        let base = export.name.clone();
        let mut k = 2;
        while read.iter().any(|e: &Export| e.name == export.name) {
            export.name = format!("{base}-{k}");
            k += 1;
        }
        read.push(export);
    }
    prepared.write(folder, |staging| assemble(&read, staging))?;
    prepared.commit()?;
    Ok(Preview {
        index: out.join("index.html"),
        exports: read.into_iter().map(|e| e.name).collect(),
    })
}

/// Whether an existing folder may be replaced: empty, or a preview.
fn replaceable(out: &Path) -> bool {
    let empty = fs::read_dir(out).is_ok_and(|mut d| d.next().is_none());
    empty || out.join(MARKER).is_file()
}

fn read_export(dir: &Path) -> Result<Export> {
    let film_path = dir.join("film.json");
    let film = read_film_json(&film_path)?;
    let texture = film
        .get("texture")
        .ok_or_else(|| Error::malformed(&film_path, "no \"texture\""))?;
    // The page reads the EXRs, and the 16-bit PNGs only when no EXR is listed.
    let listed = match texture.get("files") {
        Some(files) if files.is_object() => files,
        _ => texture
            .get("png")
            .filter(|png| png.is_object())
            .ok_or_else(|| Error::malformed(&film_path, "lists no texture files"))?,
    };
    let mut used = vec!["film.json".to_string(), "irid_film_es.glsl".to_string()];
    for which in ["reflectance", "transmittance"] {
        let name = listed
            .get(which)
            .and_then(Value::as_str)
            .ok_or_else(|| Error::malformed(&film_path, format!("no texture file for {which}")))?;
        used.push(plain_file_name(name, &film_path)?);
    }
    used.extend(rough_files(&film, &film_path)?);

    let mut files = Vec::new();
    for entry in fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let path = entry.path();
        if !path.is_file() {
            continue;
        }
        let bytes = fs::read(&path).map_err(|e| Error::io(&path, e))?;
        files.push((entry.file_name().to_string_lossy().into_owned(), bytes));
    }
    files.sort();
    for name in &used {
        if !files.iter().any(|(f, _)| f == name) {
            return Err(Error::io(
                dir.join(name),
                std::io::Error::from(std::io::ErrorKind::NotFound),
            ));
        }
    }
    let name = fs::canonicalize(dir)
        .ok()
        .and_then(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .filter(|n| !n.is_empty())
        .unwrap_or_else(|| "export".to_string());
    Ok(Export { name, files, used })
}

/// Reads the film.json at `film_path` and checks it by the one reader rule
/// ([`check_film_json`]).
pub fn read_film_json(film_path: &Path) -> Result<Value> {
    let text = fs::read_to_string(film_path).map_err(|e| Error::io(film_path, e))?;
    let film: Value = serde_json::from_str(&text)
        .map_err(|e| Error::malformed(film_path, format!("not JSON ({e})")))?;
    check_film_json(&film, film_path)?;
    Ok(film)
}

/// Checks film.json by the one reader rule (docs/gpu.md, "Reading
/// film.json: the one rule"), as web/film-json.js does for the page and the
/// three.js module; the error names `film_path` and the field.
pub fn check_film_json(film: &Value, film_path: &Path) -> Result<()> {
    match film_json_violation(film) {
        None => Ok(()),
        Some(why) => Err(Error::malformed(film_path, why)),
    }
}

/// The first way `film` breaks the rule, as "field: what".
fn film_json_violation(film: &Value) -> Option<String> {
    let is_object = |v: Option<&Value>| v.is_some_and(Value::is_object);
    let is_size = |v: Option<&Value>| v.and_then(Value::as_u64).is_some_and(|n| n >= 1);
    let null_or_object = |v: Option<&Value>| v.is_none_or(|v| v.is_null() || v.is_object());
    let Some(top) = film.as_object() else {
        return Some("not a JSON object".into());
    };
    let format = top.get("format");
    if format.and_then(Value::as_str) != Some(crate::export::FILM_FORMAT) {
        return Some(format!(
            "format is {}, not \"{}\"",
            shown(format),
            crate::export::FILM_FORMAT
        ));
    }
    let version = top.get("version");
    if version.and_then(Value::as_u64) != Some(u64::from(crate::export::FILM_VERSION)) {
        return Some(format!(
            "version {}: readers take version {} only; export the film again with this irid",
            shown(version),
            crate::export::FILM_VERSION
        ));
    }
    let texture = top.get("texture");
    let domain = top.get("domain");
    let sides = top.get("sides");
    let checks: [(bool, &str); 15] = [
        (is_object(texture), "texture must be an object"),
        (
            is_size(field(texture, "width")),
            "texture.width must be a positive integer",
        ),
        (
            is_size(field(texture, "height")),
            "texture.height must be a positive integer",
        ),
        (
            is_object(field(texture, "row_check")),
            "texture.row_check must be an object (export the film again with this irid)",
        ),
        (is_object(domain), "domain must be an object"),
        (
            is_range(field(domain, "thickness_nm"), f64::INFINITY),
            "domain.thickness_nm must be [min, max] with 0 ≤ min ≤ max",
        ),
        (
            is_range(field(domain, "cos_theta"), 1.0),
            "domain.cos_theta must be [min, max] with 0 ≤ min ≤ max ≤ 1",
        ),
        (
            top.get("charts")
                .and_then(Value::as_array)
                .is_some_and(|c| !c.is_empty()),
            "charts must be a non-empty array",
        ),
        (is_object(sides), "sides must be an object"),
        (
            is_object(field(sides, "front")),
            "sides.front must be an object",
        ),
        (
            null_or_object(field(sides, "back")),
            "sides.back must be an object or null",
        ),
        (
            top.get("opaque").is_some_and(Value::is_boolean),
            "opaque must be true or false",
        ),
        (
            matches!(top.get("white").and_then(Value::as_str), Some("d65" | "e")),
            "white must be \"d65\" or \"e\"",
        ),
        (is_object(top.get("stack")), "stack must be an object"),
        (
            null_or_object(top.get("rough")),
            "rough must be an object or null",
        ),
    ];
    checks
        .into_iter()
        .find(|(ok, _)| !ok)
        .map(|(_, why)| why.to_string())
}

/// `value`'s field `key`, when `value` is there and has it.
fn field<'a>(value: Option<&'a Value>, key: &str) -> Option<&'a Value> {
    value.and_then(|v| v.get(key))
}

/// Whether `pair` is [min, max] of numbers with 0 ≤ min ≤ max ≤ `hi`.
fn is_range(pair: Option<&Value>, hi: f64) -> bool {
    let Some([lo, up]) = pair.and_then(Value::as_array).map(Vec::as_slice) else {
        return false;
    };
    match (lo.as_f64(), up.as_f64()) {
        (Some(a), Some(b)) => 0.0 <= a && a <= b && b <= hi,
        _ => false,
    }
}

/// A field's value as film.json spells it, or "missing".
fn shown(value: Option<&Value>) -> String {
    value.map_or("missing".to_string(), Value::to_string)
}

/// `name` when it is a file beside film.json: film.json names files there,
/// never elsewhere.
fn plain_file_name(name: &str, film_path: &Path) -> Result<String> {
    if name.is_empty() || name.contains(['/', '\\']) || name == ".." {
        return Err(Error::malformed(
            film_path,
            format!("texture file {name:?} is not a plain file name"),
        ));
    }
    Ok(name.to_string())
}

/// The files the page reads for the rough table (`irid export --rough`):
/// its texture and GLSL ES sampler, none for an export without it.
fn rough_files(film: &Value, film_path: &Path) -> Result<Vec<String>> {
    let Some(rough) = film.get("rough").filter(|r| !r.is_null()) else {
        return Ok(Vec::new());
    };
    let texture = rough
        .get("texture")
        .and_then(|t| t.get("file"))
        .and_then(Value::as_str)
        .ok_or_else(|| Error::malformed(film_path, "\"rough\" names no texture file"))?;
    // The page reads the GLSL ES sampler film.json lists (the file ending in
    // _es.glsl), by default irid_film_rough_es.glsl.
    let shader = rough
        .get("shaders")
        .and_then(Value::as_array)
        .and_then(|shaders| {
            shaders
                .iter()
                .filter_map(Value::as_str)
                .find(|s| s.ends_with("_es.glsl"))
        })
        .unwrap_or("irid_film_rough_es.glsl");
    Ok(vec![
        plain_file_name(texture, film_path)?,
        plain_file_name(shader, film_path)?,
    ])
}

fn assemble(exports: &[Export], staging: &Path) -> Result<()> {
    fs::create_dir(staging).map_err(|e| Error::io(staging, e))?;
    let write =
        |path: PathBuf, bytes: &[u8]| fs::write(&path, bytes).map_err(|e| Error::io(&path, e));
    let scripts = staging.join("preview");
    fs::create_dir(&scripts).map_err(|e| Error::io(&scripts, e))?;
    for (name, text) in ASSETS {
        write(staging.join(name), text.as_bytes())?;
    }
    let mut embedded = Vec::new();
    for export in exports {
        let dir = staging.join("exports").join(&export.name);
        fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
        let mut files = Map::new();
        for (name, bytes) in &export.files {
            write(dir.join(name), bytes)?;
            if !export.used.contains(name) {
                continue;
            }
            let item = match std::str::from_utf8(bytes) {
                Ok(text) if name.ends_with(".json") || name.ends_with(".glsl") => {
                    json!({ "text": text })
                }
                _ => json!({ "base64": base64(bytes) }),
            };
            files.insert(name.clone(), item);
        }
        embedded.push(json!({ "name": export.name, "files": files }));
    }
    let script = format!(
        "// Written by irid preview: the exports, embedded so that index.html also opens from file://.\n\
         window.IRID_EXPORTS = {};\n",
        Value::Array(embedded)
    );
    write(staging.join(MARKER), script.as_bytes())
}

/// Standard base64 (RFC 4648, with padding).
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for (i, shift) in [18, 12, 6, 0].into_iter().enumerate() {
            if i <= chunk.len() {
                out.push(char::from(ALPHABET[((n >> shift) & 63) as usize]));
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{base64, rough_files};
    use serde_json::json;
    use std::path::Path;

    #[test]
    fn rough_files_are_the_texture_and_the_es_sampler_film_json_names() {
        let at = Path::new("film.json");
        assert!(rough_files(&json!({ "rough": null }), at)
            .unwrap()
            .is_empty());
        assert!(rough_files(&json!({}), at).unwrap().is_empty());
        let film = json!({ "rough": { "texture": { "file": "rough.exr" },
            "shaders": ["irid_film_rough.wgsl", "irid_film_rough_es.glsl"] } });
        assert_eq!(
            rough_files(&film, at).unwrap(),
            ["rough.exr", "irid_film_rough_es.glsl"]
        );
        let outside = json!({ "rough": { "texture": { "file": "../rough.exr" } } });
        assert!(rough_files(&outside, at)
            .unwrap_err()
            .to_string()
            .contains("not a plain file name"));
        let none = json!({ "rough": { "shaders": [] } });
        assert!(rough_files(&none, at)
            .unwrap_err()
            .to_string()
            .contains("names no texture file"));
    }

    #[test]
    fn base64_matches_rfc_4648_vectors() {
        let cases = [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ];
        for (input, expected) in cases {
            assert_eq!(base64(input.as_bytes()), expected);
        }
        assert_eq!(base64(&[0xff, 0xfe, 0x00]), "//4A");
    }
}
