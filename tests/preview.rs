//! `irid preview`: the folder it writes, and its refusals. What the page
//! does with it is tested in a browser by tools/web/test_web.mjs.

mod common;

use std::fs;
use std::path::Path;

use common::{irid_in, Scratch};

/// The shared film.json fixture (tests/film-json/, docs/gpu.md's reader rule).
fn fixture(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/film-json")
        .join(name)
}

/// A folder shaped like an export: the preview copies files and reads only
/// film.json (by the reader rule) and its texture names, so the textures
/// need not decode. Without `exr`, film.json lists the PNGs only.
fn fake_export(dir: &Path, name: &str, exr: bool) {
    let d = dir.join(name);
    fs::create_dir_all(&d).unwrap();
    let mut film: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(fixture("good/soap-film.json")).unwrap()).unwrap();
    film["texture"]["files"] = if exr {
        serde_json::json!({"reflectance": "reflectance.exr", "transmittance": "transmittance.exr"})
    } else {
        serde_json::Value::Null
    };
    film["texture"]["png"] = serde_json::json!(
        {"reflectance": "reflectance.png", "transmittance": "transmittance.png", "scale": 1.0});
    let film = serde_json::to_string_pretty(&film).unwrap();
    fs::write(d.join("film.json"), film).unwrap();
    fs::write(
        d.join("irid_film_es.glsl"),
        "IridFilm irid_film(float t, float c);\n",
    )
    .unwrap();
    fs::write(d.join("irid_film.wgsl"), "// wgsl\n").unwrap();
    fs::write(d.join("reflectance.exr"), [0x76, 0x2f, 0x31, 0x01, 0, 255]).unwrap();
    fs::write(
        d.join("transmittance.exr"),
        [0x76, 0x2f, 0x31, 0x01, 1, 254],
    )
    .unwrap();
    fs::write(d.join("reflectance.png"), [137, 80, 78, 71, 0]).unwrap();
    fs::write(d.join("transmittance.png"), [137, 80, 78, 71, 1]).unwrap();
}

/// The JSON array `exports.js` assigns to `window.IRID_EXPORTS`.
fn embedded(out: &Path) -> serde_json::Value {
    let text = fs::read_to_string(out.join("exports.js")).unwrap();
    let start = text.find("window.IRID_EXPORTS = ").unwrap() + "window.IRID_EXPORTS = ".len();
    let end = text.rfind(';').unwrap();
    serde_json::from_str(&text[start..end]).unwrap()
}

#[test]
fn writes_the_page_the_exports_and_their_embedded_copy() {
    let dir = Scratch::new("preview");
    fake_export(dir.path(), "soap", true);
    fake_export(&dir.path().join("other"), "soap", false);
    let run = irid_in(dir.path(), ["preview", "soap", "other/soap", "-o", "out"]);
    assert!(run.success(), "{}", run.stderr);
    let out = dir.path().join("out");
    for asset in [
        "index.html",
        "style.css",
        "png16.js",
        "exr.js",
        "film-json.js",
        "preview/sources.js",
        "preview/export.js",
        "preview/meshes.js",
        "preview/matrices.js",
        "preview/shaders.js",
        "preview/ggx.js",
        "preview/page.js",
    ] {
        let repo = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("web")
            .join(asset);
        assert_eq!(
            fs::read(out.join(asset)).unwrap(),
            fs::read(repo).unwrap(),
            "{asset}"
        );
    }
    // Every script the page loads is there.
    let index = fs::read_to_string(out.join("index.html")).unwrap();
    let scripts: Vec<&str> = index
        .split("<script src=\"")
        .skip(1)
        .map(|rest| &rest[..rest.find('"').unwrap()])
        .collect();
    assert!(scripts.len() >= 10, "{scripts:?}");
    for script in scripts {
        assert!(out.join(script).is_file(), "index.html loads {script}");
    }
    // Both exports, the second renamed, copied whole.
    for (name, source) in [("soap", "soap"), ("soap-2", "other/soap")] {
        for entry in fs::read_dir(dir.path().join(source)).unwrap() {
            let entry = entry.unwrap();
            let copy = out.join("exports").join(name).join(entry.file_name());
            assert_eq!(fs::read(copy).unwrap(), fs::read(entry.path()).unwrap());
        }
    }
    let list = embedded(&out);
    let list = list.as_array().unwrap();
    assert_eq!(list.len(), 2);
    assert_eq!(list[0]["name"], "soap");
    assert_eq!(list[1]["name"], "soap-2");
    // The first embeds the EXRs (the page reads them), the second, which
    // lists none, the PNGs; text files as text, the rest base64; files the
    // page does not read stay out.
    let first = list[0]["files"].as_object().unwrap();
    let mut keys: Vec<&str> = first.keys().map(String::as_str).collect();
    keys.sort();
    assert_eq!(
        keys,
        [
            "film.json",
            "irid_film_es.glsl",
            "reflectance.exr",
            "transmittance.exr"
        ]
    );
    assert_eq!(
        first["film.json"]["text"].as_str().unwrap(),
        fs::read_to_string(dir.path().join("soap/film.json")).unwrap()
    );
    assert_eq!(first["reflectance.exr"]["base64"], "di8xAQD/");
    assert_eq!(first["transmittance.exr"]["base64"], "di8xAQH+");
    let second = list[1]["files"].as_object().unwrap();
    assert_eq!(second["reflectance.png"]["base64"], "iVBORwA=");
    assert!(!second.contains_key("reflectance.exr"));
    assert!(!second.contains_key("irid_film.wgsl"));

    // A second run replaces the earlier preview whole.
    let run = irid_in(dir.path(), ["preview", "other/soap", "-o", "out"]);
    assert!(run.success(), "{}", run.stderr);
    assert!(!out.join("exports/soap-2").exists());
    assert_eq!(embedded(&out).as_array().unwrap().len(), 1);
    // Nothing is left beside it.
    let leftovers: Vec<_> = fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("partial"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

#[test]
fn bad_exports_and_destinations_are_one_line_errors() {
    let dir = Scratch::new("preview-bad");
    let d = dir.path();
    fake_export(d, "soap", true);

    irid_in(d, ["preview", "missing", "-o", "out"])
        .assert_one_line_error("missing export", &["missing/film.json"]);
    irid_in(d, ["preview", "-o", "out"]).assert_one_line_error("no export", &["EXPORTS"]);

    fs::create_dir_all(d.join("broken")).unwrap();
    fs::write(d.join("broken/film.json"), "{\"format\": \"irid-film\",").unwrap();
    irid_in(d, ["preview", "broken", "-o", "out"])
        .assert_one_line_error("damaged film.json", &["broken/film.json", "not JSON"]);

    fs::write(d.join("broken/film.json"), "{\"format\": \"irid-lut\"}").unwrap();
    irid_in(d, ["preview", "broken", "-o", "out"])
        .assert_one_line_error("another format", &["broken/film.json", "irid-film"]);

    // An export of another film.json version (the single-chart version 1).
    fake_export(d, "old", true);
    let film = fs::read_to_string(d.join("old/film.json")).unwrap();
    fs::write(
        d.join("old/film.json"),
        film.replace("\"version\": 3", "\"version\": 1"),
    )
    .unwrap();
    irid_in(d, ["preview", "old", "-o", "out"])
        .assert_one_line_error("version 1", &["old/film.json", "version 1", "version 3"]);

    // One field of the reader rule, through the CLI (every field: below).
    fake_export(d, "no-domain", true);
    let mut film: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(d.join("no-domain/film.json")).unwrap()).unwrap();
    film.as_object_mut().unwrap().remove("domain");
    fs::write(d.join("no-domain/film.json"), film.to_string()).unwrap();
    irid_in(d, ["preview", "no-domain", "-o", "out"])
        .assert_one_line_error("no domain", &["no-domain/film.json", "domain"]);

    fake_export(d, "escape", true);
    let film = fs::read_to_string(d.join("escape/film.json")).unwrap();
    fs::write(
        d.join("escape/film.json"),
        film.replace("\"reflectance.exr\"", "\"../../etc/passwd\""),
    )
    .unwrap();
    irid_in(d, ["preview", "escape", "-o", "out"])
        .assert_one_line_error("a path in film.json", &["not a plain file name"]);

    fake_export(d, "incomplete", true);
    fs::remove_file(d.join("incomplete/transmittance.exr")).unwrap();
    irid_in(d, ["preview", "incomplete", "-o", "out"])
        .assert_one_line_error("a texture missing", &["incomplete/transmittance.exr"]);
    assert!(!d.join("out").exists());

    // A folder that is not a preview is never replaced.
    fs::create_dir_all(d.join("mine")).unwrap();
    fs::write(d.join("mine/notes.txt"), "keep").unwrap();
    irid_in(d, ["preview", "soap", "-o", "mine"])
        .assert_one_line_error("a foreign folder", &["mine", "not an irid preview"]);
    assert_eq!(
        fs::read_to_string(d.join("mine/notes.txt")).unwrap(),
        "keep"
    );
    fs::write(d.join("file"), "x").unwrap();
    irid_in(d, ["preview", "soap", "-o", "file"])
        .assert_one_line_error("a file", &["file", "not a folder"]);
}

/// Every file of the shared fixture: the good ones read, each bad one
/// refused in one line naming the file and the field cases.json gives.
#[test]
fn film_json_follows_the_one_reader_rule() {
    let cases: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(fixture("cases.json")).unwrap()).unwrap();
    let good = cases["good"].as_array().unwrap();
    assert!(good.len() >= 2);
    for name in good {
        let path = fixture(name.as_str().unwrap());
        if let Err(e) = irid::web::read_film_json(&path) {
            panic!("{}: refused: {e}", path.display());
        }
    }
    let bad = cases["bad"].as_object().unwrap();
    assert!(bad.len() >= 30);
    for (name, field) in bad {
        let path = fixture(name);
        let message = match irid::web::read_film_json(&path) {
            Ok(_) => panic!("{name}: accepted"),
            Err(e) => e.to_string(),
        };
        let field = field.as_str().unwrap();
        assert!(!message.contains('\n'), "{name}: {message}");
        assert!(
            message.contains(&path.display().to_string()),
            "{name}: {message}"
        );
        assert!(
            message.contains(field),
            "{name}: names not {field}: {message}"
        );
    }
}
