//! Temporaries: the unnamed or named file an output is written into, the
//! folder a folder output is built in, their names, and the sweep of those
//! a killed process left behind.

use std::ffi::OsStr;
use std::fs::File;
use std::os::unix::ffi::OsStrExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use super::check::{c_path, Target};
use super::signals::Registered;
use super::NAME_MAX;
use crate::error::{Error, Result};

/// The mark of a temporary holding a new output: `.PID-N.tmp.NAME`.
pub(super) const NEW: &str = "tmp";
/// The mark of an original kept while its set commits: `.PID-N.old.NAME`.
/// The sweep leaves these alone.
pub(super) const KEPT: &str = "old";

/// One file output's temporary.
#[derive(Debug)]
pub(super) struct Temp {
    /// Where the writer writes: `/proc/self/fd/N` of an unnamed file, or
    /// the named temporary; empty once placed.
    pub path: PathBuf,
    /// The unnamed file, kept open so that it lives until linked.
    unnamed: Option<File>,
    /// The named temporary's signal registration (named kind only).
    guard: Option<Registered>,
}

impl Temp {
    /// An unnamed file in the target's folder, or where that is unsupported
    /// or `named` is asked for, a named one (created now, so that a folder
    /// that refuses it fails before the work).
    pub fn new(target: &Target, named: bool) -> Result<Temp> {
        if !named {
            if let Some(file) =
                open_unnamed(&target.dir).map_err(|e| Error::io(&target.given, e))?
            {
                use std::os::fd::AsRawFd;
                let path = PathBuf::from(format!("/proc/self/fd/{}", file.as_raw_fd()));
                if path.exists() {
                    return Ok(Temp {
                        path,
                        unnamed: Some(file),
                        guard: None,
                    });
                }
            }
        }
        let path = temporary_name(&target.dir, &target.name, NEW);
        // Registered before it exists: a signal in between removes nothing.
        // A file of that name can only be a stale one of an earlier process
        // with this process's id (the counter is this process's own).
        let guard = Registered::new(&path);
        File::options()
            .write(true)
            .create(true)
            .truncate(true)
            .open(&path)
            .map_err(|e| Error::io(&target.given, e))?;
        Ok(Temp {
            path,
            unnamed: None,
            guard: Some(guard),
        })
    }

    /// Gives an unnamed file a name (`.PID-N.tmp.NAME`, registered for
    /// removal on a signal) in the target's folder: `rename` can then put it
    /// in place. A named temporary already has one.
    pub fn stage(&mut self, target: &Target) -> Result<()> {
        if self.unnamed.is_none() {
            return Ok(());
        }
        let named = temporary_name(&target.dir, &target.name, NEW);
        let guard = Registered::new(&named);
        let from = c_path(&self.path)?;
        let to = c_path(&named)?;
        // SAFETY: both strings are NUL-terminated; AT_SYMLINK_FOLLOW
        // resolves /proc/self/fd/N to the open unnamed file.
        let linked = unsafe {
            libc::linkat(
                libc::AT_FDCWD,
                from.as_ptr(),
                libc::AT_FDCWD,
                to.as_ptr(),
                libc::AT_SYMLINK_FOLLOW,
            )
        };
        if linked != 0 {
            return Err(Error::io(&target.given, std::io::Error::last_os_error()));
        }
        self.unnamed = None;
        self.path = named;
        self.guard = Some(guard);
        Ok(())
    }

    /// The temporary has become the output: nothing to remove any more.
    pub fn disarm(&mut self) {
        self.guard = None;
        self.path = PathBuf::new();
    }
}

impl Drop for Temp {
    fn drop(&mut self) {
        if self.unnamed.is_none() && !self.path.as_os_str().is_empty() {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// Where a folder output is built: `.PID-N.tmp.NAME` beside its target,
/// removed with everything in it unless it was put in place.
#[derive(Debug)]
pub(super) struct Staging {
    /// Empty once placed.
    pub path: PathBuf,
}

impl Staging {
    pub fn new(target: &Target) -> Staging {
        Staging {
            path: temporary_name(&target.dir, &target.name, NEW),
        }
    }

    pub fn disarm(&mut self) {
        self.path = PathBuf::new();
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.path.as_os_str().is_empty() {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

/// Distinguishes the temporaries of one process.
static COUNTER: AtomicUsize = AtomicUsize::new(0);

/// `.PID-N.MARK.NAME` in `dir`, NAME shortened from the front (keeping its
/// extension) so the whole stays within [`NAME_MAX`] bytes.
pub(super) fn temporary_name(dir: &Path, name: &OsStr, mark: &str) -> PathBuf {
    let prefix = format!(
        ".{}-{}.{mark}.",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    );
    let bytes = name.as_bytes();
    let keep = NAME_MAX.saturating_sub(prefix.len()).min(bytes.len());
    let tail = &bytes[bytes.len() - keep..];
    let mut full = prefix.into_bytes();
    full.extend_from_slice(tail);
    dir.join(OsStr::from_bytes(&full))
}

/// The process id in a new output's temporary name, if it is one of ours.
pub(super) fn temporary_owner(name: &[u8]) -> Option<i32> {
    let rest = name.strip_prefix(b".")?;
    let end = rest.iter().position(|&b| b == b'-')?;
    let (pid, rest) = rest.split_at(end);
    let rest = &rest[1..];
    let n_end = rest.iter().position(|&b| !b.is_ascii_digit())?;
    if n_end == 0 || !rest[n_end..].starts_with(format!(".{NEW}.").as_bytes()) {
        return None;
    }
    std::str::from_utf8(pid).ok()?.parse().ok()
}

/// Removes the temporary files in `dir` left by processes that no longer
/// exist (killed while writing through named temporaries). Folders are
/// left alone: one killed mid-commit may hold an original. Best effort: a
/// file that cannot be read or removed is left alone.
pub(super) fn sweep_stale(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = temporary_owner(name.as_bytes()) else {
            continue;
        };
        if pid <= 0
            || pid as u32 == std::process::id()
            || !entry.file_type().is_ok_and(|t| t.is_file())
        {
            continue;
        }
        // SAFETY: kill with signal 0 only checks whether the process exists.
        let gone = unsafe { libc::kill(pid, 0) } != 0
            && std::io::Error::last_os_error().raw_os_error() == Some(libc::ESRCH);
        if gone {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// An unnamed file in `dir`; None where the system or file system does not
/// support `O_TMPFILE`; the error where the folder refuses it.
fn open_unnamed(dir: &Path) -> std::io::Result<Option<File>> {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::OpenOptionsExt;
        let opened = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(libc::O_TMPFILE)
            .open(dir);
        match opened {
            Ok(file) => Ok(Some(file)),
            // Unsupported: by the file system (EOPNOTSUPP), or by a kernel
            // older than O_TMPFILE, which takes it for O_DIRECTORY (EISDIR).
            Err(e)
                if matches!(
                    e.raw_os_error(),
                    Some(libc::EOPNOTSUPP | libc::EISDIR | libc::EINVAL)
                ) =>
            {
                Ok(None)
            }
            Err(e) => Err(e),
        }
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = dir;
        Ok(None)
    }
}
