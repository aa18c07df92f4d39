//! Putting one written output in place, keeping what it replaces until the
//! whole set is in place, and undoing it if the set fails.

use std::io::ErrorKind;
use std::path::{Path, PathBuf};

use super::check::{c_path, Target};
use super::temp::{temporary_name, KEPT, NEW};
use super::{Content, Entry};
use crate::error::{Error, Result};

/// An output in place, with what it replaced.
pub(super) struct Placed {
    target: PathBuf,
    folder: bool,
    /// The original the output replaced, kept as `.PID-N.old.NAME`; None
    /// where the target did not exist.
    kept: Option<PathBuf>,
}

/// Puts the `k`-th output of a set in place.
pub(super) fn place(entry: &mut Entry, k: usize) -> Result<Placed> {
    #[cfg(test)]
    tests::before_placing(k)?;
    #[cfg(not(test))]
    let _ = k;
    let target = &entry.target;
    match &mut entry.content {
        Content::File(temp) => {
            let placed = place_file(&temp.path, target)?;
            temp.disarm();
            Ok(placed)
        }
        Content::Folder(staging, replace) => {
            // Checked again: the folder may have changed during the work.
            replace.check(target)?;
            let placed = place_folder(&staging.path, target)?;
            staging.disarm();
            Ok(placed)
        }
    }
}

/// Renames `staged` over the target, first keeping an existing target as a
/// hard link (or, where the file system refuses one, moving it aside).
fn place_file(staged: &Path, target: &Target) -> Result<Placed> {
    let io = |e: std::io::Error| Error::io(&target.given, e);
    let mut placed = Placed::new(target, false);
    match std::fs::symlink_metadata(&target.path) {
        Err(e) if e.kind() == ErrorKind::NotFound => {
            std::fs::rename(staged, &target.path).map_err(io)?;
            return Ok(placed);
        }
        Err(e) => return Err(io(e)),
        Ok(m) if m.is_dir() => {
            return Err(target.refused("is a folder; an output file needs a file name"))
        }
        Ok(_) => {}
    }
    let kept = temporary_name(&target.dir, &target.name, KEPT);
    if std::fs::hard_link(&target.path, &kept).is_ok() {
        if let Err(e) = std::fs::rename(staged, &target.path) {
            let _ = std::fs::remove_file(&kept);
            return Err(io(e));
        }
    } else {
        move_aside_and_rename(staged, &target.path, &kept).map_err(io)?;
    }
    placed.kept = Some(kept);
    Ok(placed)
}

/// Renames the built folder `staging` to the target; an existing target is
/// swapped with it in one step where the system can (so that the target is
/// at every moment the old folder or the new one), else moved aside first,
/// and kept as `.PID-N.old.NAME`.
fn place_folder(staging: &Path, target: &Target) -> Result<Placed> {
    let io = |e: std::io::Error| Error::io(&target.given, e);
    let mut placed = Placed::new(target, true);
    if !target.path.exists() {
        std::fs::rename(staging, &target.path).map_err(io)?;
        return Ok(placed);
    }
    let kept = temporary_name(&target.dir, &target.name, KEPT);
    if exchange(staging, &target.path) {
        if let Err(e) = std::fs::rename(staging, &kept) {
            exchange(staging, &target.path);
            return Err(io(e));
        }
    } else {
        move_aside_and_rename(staging, &target.path, &kept).map_err(io)?;
    }
    placed.kept = Some(kept);
    Ok(placed)
}

/// Renames `target` to `kept`, then `new` to `target`; if the second
/// rename fails, `target` is put back.
fn move_aside_and_rename(new: &Path, target: &Path, kept: &Path) -> std::io::Result<()> {
    std::fs::rename(target, kept)?;
    std::fs::rename(new, target).inspect_err(|_| {
        let _ = std::fs::rename(kept, target);
    })
}

/// Takes back outputs already placed, last first: each kept original is
/// renamed back over its target, and a target that did not exist before is
/// removed. Best effort: every step is tried.
pub(super) fn undo(placed: Vec<Placed>) {
    for p in placed.into_iter().rev() {
        match (&p.kept, p.folder) {
            (Some(kept), false) => {
                let _ = std::fs::rename(kept, &p.target);
            }
            (None, false) => {
                let _ = std::fs::remove_file(&p.target);
            }
            (Some(kept), true) => {
                if exchange(kept, &p.target) {
                    let _ = std::fs::remove_dir_all(kept);
                } else {
                    let aside = aside(&p.target);
                    let _ = std::fs::rename(&p.target, &aside);
                    let _ = std::fs::rename(kept, &p.target);
                    let _ = std::fs::remove_dir_all(aside);
                }
            }
            (None, true) => {
                let aside = aside(&p.target);
                if std::fs::rename(&p.target, &aside).is_ok() {
                    let _ = std::fs::remove_dir_all(aside);
                }
            }
        }
    }
}

impl Placed {
    fn new(target: &Target, folder: bool) -> Placed {
        Placed {
            target: target.path.clone(),
            folder,
            kept: None,
        }
    }

    /// The whole set is in place: the kept original goes.
    pub fn finish(self) {
        match (self.kept, self.folder) {
            (Some(kept), false) => {
                let _ = std::fs::remove_file(kept);
            }
            (Some(kept), true) => {
                let _ = std::fs::remove_dir_all(kept);
            }
            (None, _) => {}
        }
    }
}

/// A temporary name beside `path`, for a folder on its way out.
fn aside(path: &Path) -> PathBuf {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    temporary_name(dir, path.file_name().unwrap_or_default(), NEW)
}

/// Swaps two paths atomically (renameat2 RENAME_EXCHANGE); false when the
/// system or file system does not support it.
fn exchange(a: &Path, b: &Path) -> bool {
    #[cfg(target_os = "linux")]
    {
        let (Ok(a), Ok(b)) = (c_path(a), c_path(b)) else {
            return false;
        };
        // SAFETY: both arguments are valid NUL-terminated paths that outlive
        // the call; AT_FDCWD resolves them like open(2) would.
        let rc = unsafe {
            libc::renameat2(
                libc::AT_FDCWD,
                a.as_ptr(),
                libc::AT_FDCWD,
                b.as_ptr(),
                libc::RENAME_EXCHANGE,
            )
        };
        rc == 0
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = (a, b);
        false
    }
}

#[cfg(test)]
pub(super) mod tests {
    use std::cell::Cell;

    use crate::error::{Error, Result};

    thread_local! {
        /// Placing the output of this index fails (a fault injected by a test).
        pub static FAIL_AT: Cell<Option<usize>> = const { Cell::new(None) };
        /// Before placing the output of this index, the process raises this
        /// signal.
        pub static RAISE_AT: Cell<Option<(usize, libc::c_int)>> = const { Cell::new(None) };
    }

    pub fn before_placing(k: usize) -> Result<()> {
        if let Some((at, signal)) = RAISE_AT.get() {
            if at == k {
                // SAFETY: raises a signal in this test process, whose
                // handler is installed.
                unsafe { libc::raise(signal) };
            }
        }
        if FAIL_AT.get() == Some(k) {
            return Err(Error::invalid("test", format!("placing output {k} fails")));
        }
        Ok(())
    }
}
