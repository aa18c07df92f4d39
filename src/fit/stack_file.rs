//! The fitted stack as a stack file: the original file's TOML with the
//! varied layers' `thickness_nm` replaced.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// The stack file `text` (read from folder `from_dir`) with layer `l`
/// (1-based) set to thickness `d` for each `(l, d)` of `thicknesses`, to be
/// written into folder `to_dir`: a `table = "..."` path relative to the
/// original folder is made absolute when the folders differ, so that the
/// new file still finds its tables. Comments are not kept.
pub fn with_thicknesses(
    text: &str,
    origin: &str,
    thicknesses: &[(usize, f64)],
    from_dir: &Path,
    to_dir: &Path,
) -> Result<String> {
    let mut doc: toml::Table =
        toml::from_str(text).map_err(|e| crate::error::toml_error(origin, &e, text))?;
    let same_dir = same_folder(from_dir, to_dir);
    if !same_dir {
        for key in ["ambient", "substrate"] {
            if let Some(toml::Value::Table(medium)) = doc.get_mut(key) {
                anchor_table(medium, from_dir);
            }
        }
    }
    let Some(toml::Value::Array(layers)) = doc.get_mut("layers") else {
        return Err(Error::malformed(origin, "no [[layers]] to set"));
    };
    for layer in layers.iter_mut() {
        if let (toml::Value::Table(medium), false) = (layer, same_dir) {
            anchor_table(medium, from_dir);
        }
    }
    for &(l, d) in thicknesses {
        let Some(toml::Value::Table(layer)) = layers.get_mut(l - 1) else {
            return Err(Error::malformed(origin, format!("no layer {l}")));
        };
        layer.insert("thickness_nm".into(), toml::Value::Float(d));
    }
    toml::to_string(&doc).map_err(|e| Error::invalid(origin, e.to_string()))
}

fn same_folder(a: &Path, b: &Path) -> bool {
    let canonical = |p: &Path| {
        let p = if p.as_os_str().is_empty() {
            Path::new(".")
        } else {
            p
        };
        p.canonicalize().unwrap_or_else(|_| p.to_path_buf())
    };
    canonical(a) == canonical(b)
}

fn anchor_table(medium: &mut toml::Table, from_dir: &Path) {
    if let Some(toml::Value::String(path)) = medium.get_mut("table") {
        let p = PathBuf::from(&*path);
        if p.is_relative() {
            let joined = from_dir.join(&p);
            let absolute = joined.canonicalize().unwrap_or(joined);
            *path = absolute.display().to_string();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets_the_thickness_and_anchors_tables() {
        let text = "ambient = { n = 1.0 }\nsubstrate = { table = \"glass.csv\" }\n\
                    [[layers]]\nn = 1.33\nthickness_nm = 500.0\n[[layers]]\nn = 2\nthickness_nm = 10\n";
        let here = Path::new("/nonexistent/a");
        let out = with_thicknesses(
            text,
            "s.toml",
            &[(2, 12.5)],
            here,
            Path::new("/nonexistent/b"),
        )
        .unwrap();
        let doc: toml::Table = toml::from_str(&out).unwrap();
        let layers = doc["layers"].as_array().unwrap();
        assert_eq!(layers[0]["thickness_nm"].as_float(), Some(500.0));
        assert_eq!(layers[1]["thickness_nm"].as_float(), Some(12.5));
        assert_eq!(
            doc["substrate"]["table"].as_str(),
            Some("/nonexistent/a/glass.csv")
        );
        // In the same folder the path stays as written.
        let same = with_thicknesses(text, "s.toml", &[(1, 1.0)], here, here).unwrap();
        assert!(same.contains("\"glass.csv\""), "{same}");
    }
}
