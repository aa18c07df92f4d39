//! Output files are written to a temporary file beside the target and
//! renamed into place, so an interrupted or failed write never leaves a
//! half-written file under the name the user asked for.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Runs `write` on a temporary path in the target's directory, then renames
/// it to `path`; on any failure the temporary file is removed. The temporary
/// name ends with the target's own name, so writers that choose a format by
/// extension see the right one.
pub fn write_with(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let name = path
        .file_name()
        .ok_or_else(|| Error::invalid(path.display().to_string(), "not a file path"))?
        .to_string_lossy()
        .into_owned();
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(Error::io(
            path,
            std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "output directory does not exist",
            ),
        ));
    }
    let tmp = dir.join(format!(".{}.tmp.{name}", std::process::id()));
    let result =
        write(&tmp).and_then(|()| std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e)));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Writes `bytes` to `path` atomically; errors name `path`, not the temporary.
pub fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    write_with(path, |tmp| {
        std::fs::write(tmp, bytes).map_err(|e| Error::io(path, e))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_whole_files_and_leaves_nothing_on_failure() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.txt");
        write(&target, b"hello").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"hello");

        let failed = dir.path().join("failed.txt");
        let err = write_with(&failed, |tmp| {
            std::fs::write(tmp, b"half").unwrap();
            Err(Error::invalid("writer", "stopped half-way"))
        });
        assert!(err.is_err());
        assert!(!failed.exists());
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "only out.txt remains: {left:?}");

        let missing_dir = dir.path().join("nope").join("x.txt");
        assert!(write(&missing_dir, b"x").is_err());
    }
}
