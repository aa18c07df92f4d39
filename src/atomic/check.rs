//! The checks an output set passes before anything is written: they read
//! the file system and change nothing.

use std::ffi::{CString, OsString};
use std::fs::Metadata;
use std::io::ErrorKind;
use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use super::NAME_MAX;
use crate::error::{Error, Result};

/// The longest path (bytes, without the terminating NUL) a system call takes.
const PATH_MAX: usize = libc::PATH_MAX as usize - 1;

/// Symbolic links followed from one output before giving up, as Linux does.
const MAX_SYMLINKS: usize = 40;

/// The most a temporary's prefix `.PID-N.tmp.` adds to a name.
const TEMPORARY_PREFIX_MAX: usize = ".4294967295-18446744073709551615.tmp.".len();

/// Which existing folders a folder output may replace, and what to say of
/// any other.
#[derive(Clone, Copy, Debug)]
pub struct Replace {
    /// Whether the existing folder at the output's path may be replaced
    /// (an earlier output of the same kind, or an empty folder).
    pub allowed: fn(&Path) -> bool,
    /// Why another existing folder is refused.
    pub otherwise: &'static str,
}

impl Replace {
    /// The output's folder is absent, or present and replaceable.
    pub(super) fn check(&self, target: &Target) -> Result<()> {
        match std::fs::symlink_metadata(&target.path) {
            Err(_) => Ok(()),
            Ok(m) if !m.is_dir() => {
                Err(target
                    .refused_by_system(ErrorKind::NotADirectory, "exists and is not a folder"))
            }
            Ok(_) if (self.allowed)(&target.path) => Ok(()),
            Ok(_) => Err(target.refused(self.otherwise)),
        }
    }
}

/// Where an output goes: the path as given, and the folder and name it
/// resolves to once symbolic links at its end are followed.
#[derive(Debug)]
pub(super) struct Target {
    /// As the command was given it: what errors name.
    pub given: PathBuf,
    /// The folder the output goes into.
    pub dir: PathBuf,
    /// Its name in that folder.
    pub name: OsString,
    /// `dir` joined with `name`.
    pub path: PathBuf,
}

impl Target {
    pub(super) fn refused(&self, why: impl Into<String>) -> Error {
        Error::invalid(self.given.display().to_string(), why)
    }

    /// Refused for what the file system holds (a folder missing, a file
    /// where a folder goes, no permission, a name too long): an I/O error
    /// of `kind`, which Python raises as the OSError it names. The message
    /// is the same `path: why` line.
    pub(super) fn refused_by_system(&self, kind: ErrorKind, why: impl Into<String>) -> Error {
        Error::io(&self.given, std::io::Error::new(kind, why.into()))
    }
}

/// An output that passed its own checks, with what tells it apart.
pub(super) struct Checked {
    pub target: Target,
    /// The folder (device and inode) and the name within it: equal for two
    /// spellings of one path, through `./`, symbolic links or bind mounts.
    key: (u64, u64, PathBuf),
    /// The existing file's device and inode: equal for two hard links.
    existing: Option<(u64, u64)>,
}

/// A folder outputs go into, made if missing.
pub(super) struct NewFolder {
    pub path: PathBuf,
    pub missing: bool,
    /// The parent folder (device, inode, NAME_MAX) of a missing one.
    parent: (u64, u64, usize),
    name: OsString,
}

/// Checks a folder to make if missing: an existing one must be a folder; a
/// missing one needs an existing, writable parent and a name that fits.
pub(super) fn new_folder(path: &Path) -> Result<NewFolder> {
    let target = split(path, path)?;
    fits_path_max(&target, path.as_os_str().len())?;
    let parent = existing_folder(&target)?;
    fits_name_max(&target, parent.2)?;
    let missing = match std::fs::metadata(path) {
        Ok(m) if m.is_dir() => false,
        Ok(_) => {
            return Err(
                target.refused_by_system(ErrorKind::NotADirectory, "exists and is not a folder")
            )
        }
        Err(e) if e.kind() == ErrorKind::NotFound => {
            writable(&target)?;
            true
        }
        Err(e) => return Err(Error::io(path, e)),
    };
    Ok(NewFolder {
        path: path.to_path_buf(),
        missing,
        parent,
        name: target.name,
    })
}

/// Checks one output on its own: the path fits PATH_MAX and the name
/// NAME_MAX, the folder exists (or is a new folder that will) and is
/// writable, and a file output's path is not a folder.
pub(super) fn output(given: &Path, is_file: bool, new_folders: &[NewFolder]) -> Result<Checked> {
    let target = resolve(given)?;
    fits_path_max(&target, given.as_os_str().len())?;
    fits_path_max(&target, target.path.as_os_str().len())?;
    let temporary = target.name.len().saturating_add(TEMPORARY_PREFIX_MAX);
    let temporary_path = target.dir.as_os_str().len() + 1 + temporary.min(NAME_MAX);
    fits_path_max(&target, temporary_path)?;
    if let Some(folder) = new_folders
        .iter()
        .find(|f| f.missing && f.path == target.dir)
    {
        // Inside a folder the set makes: nothing is there yet.
        fits_name_max(&target, folder.parent.2)?;
        let (dev, ino, _) = folder.parent;
        let key = (dev, ino, Path::new(&folder.name).join(&target.name));
        return Ok(Checked {
            target,
            key,
            existing: None,
        });
    }
    let (dev, ino, name_max) = existing_folder(&target)?;
    fits_name_max(&target, name_max)?;
    writable(&target)?;
    let existing = match std::fs::symlink_metadata(&target.path) {
        Ok(m) if is_file && m.is_dir() => {
            return Err(target.refused_by_system(
                ErrorKind::IsADirectory,
                "is a folder; an output file needs a file name",
            ))
        }
        Ok(m) => Some(identity(&m)),
        Err(e) if e.kind() == ErrorKind::NotFound => None,
        Err(e) => return Err(Error::io(given, e)),
    };
    let key = (dev, ino, PathBuf::from(&target.name));
    Ok(Checked {
        target,
        key,
        existing,
    })
}

/// No two outputs are one file, and none is an input.
pub(super) fn distinct(checked: &[Checked], inputs: &[PathBuf]) -> Result<()> {
    for (k, b) in checked.iter().enumerate() {
        let same =
            |a: &&Checked| a.key == b.key || (a.existing.is_some() && a.existing == b.existing);
        if let Some(a) = checked[..k].iter().find(same) {
            return Err(b.target.refused(format!(
                "the same file as {}; outputs must be different files",
                a.target.given.display()
            )));
        }
    }
    for input in inputs {
        let Ok(meta) = std::fs::metadata(input) else {
            continue;
        };
        if let Some(c) = checked.iter().find(|c| c.existing == Some(identity(&meta))) {
            return Err(c.target.refused(format!(
                "is also an input ({}); an output must be a different file",
                input.display()
            )));
        }
    }
    Ok(())
}

/// `given` with symbolic links at its end followed: an output written
/// through a link replaces the file it points to, and the link stays.
fn resolve(given: &Path) -> Result<Target> {
    let mut target = split(given, given)?;
    for _ in 0..MAX_SYMLINKS {
        match std::fs::symlink_metadata(&target.path) {
            Ok(m) if m.file_type().is_symlink() => {
                let to = std::fs::read_link(&target.path).map_err(|e| Error::io(given, e))?;
                // An absolute link replaces the folder it is joined to.
                target = split(given, &target.dir.join(to))?;
            }
            _ => return Ok(target),
        }
    }
    Err(Error::invalid(
        given.display().to_string(),
        "too many levels of symbolic links",
    ))
}

/// `path` as a folder ("." for a bare name) and a name in it.
fn split(given: &Path, path: &Path) -> Result<Target> {
    let name = path.file_name().ok_or_else(|| {
        Error::invalid(
            given.display().to_string(),
            "names no file or folder to write",
        )
    })?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    Ok(Target {
        given: given.to_path_buf(),
        path: dir.join(name),
        name: name.to_os_string(),
        dir,
    })
}

fn fits_path_max(target: &Target, bytes: usize) -> Result<()> {
    if bytes > PATH_MAX {
        return Err(target.refused_by_system(
            ErrorKind::InvalidFilename,
            format!("the path is {bytes} bytes, longer than the {PATH_MAX} the system allows"),
        ));
    }
    Ok(())
}

fn fits_name_max(target: &Target, name_max: usize) -> Result<()> {
    let bytes = target.name.len();
    if bytes > name_max {
        return Err(target.refused_by_system(
            ErrorKind::InvalidFilename,
            format!(
                "its name is {bytes} bytes, longer than the {name_max} its folder's file system allows"
            ),
        ));
    }
    Ok(())
}

/// The target's folder exists and is a folder: its device, inode and
/// NAME_MAX.
fn existing_folder(target: &Target) -> Result<(u64, u64, usize)> {
    let dir = &target.dir;
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => {
            let (dev, ino) = identity(&m);
            Ok((dev, ino, name_max(dir)))
        }
        Ok(_) => Err(target.refused_by_system(
            ErrorKind::NotADirectory,
            format!("{} is not a folder", dir.display()),
        )),
        Err(e) if e.kind() == ErrorKind::NotFound => Err(target.refused_by_system(
            ErrorKind::NotFound,
            format!("its folder {} does not exist", dir.display()),
        )),
        Err(e) => {
            Err(target.refused_by_system(e.kind(), format!("its folder {}: {e}", dir.display())))
        }
    }
}

/// The target's folder is writable by this process: `faccessat` with the
/// effective ids, which also reports a read-only file system to root.
fn writable(target: &Target) -> Result<()> {
    let dir = c_path(&target.dir)?;
    // SAFETY: dir is a NUL-terminated path; faccessat only reads it.
    let rc = unsafe {
        libc::faccessat(
            libc::AT_FDCWD,
            dir.as_ptr(),
            libc::W_OK | libc::X_OK,
            libc::AT_EACCESS,
        )
    };
    if rc != 0 {
        let e = std::io::Error::last_os_error();
        return Err(target.refused_by_system(
            e.kind(),
            format!("cannot write in its folder {}: {e}", target.dir.display()),
        ));
    }
    Ok(())
}

/// The longest name the file system holding `dir` allows ([`NAME_MAX`]
/// where it does not say).
fn name_max(dir: &Path) -> usize {
    let Ok(dir) = c_path(dir) else {
        return NAME_MAX;
    };
    // SAFETY: dir is a NUL-terminated path; pathconf only reads it.
    let n = unsafe { libc::pathconf(dir.as_ptr(), libc::_PC_NAME_MAX) };
    usize::try_from(n)
        .ok()
        .filter(|&n| n > 0)
        .unwrap_or(NAME_MAX)
}

pub(super) fn c_path(path: &Path) -> Result<CString> {
    CString::new(path.as_os_str().as_bytes())
        .map_err(|_| Error::invalid(path.display().to_string(), "a NUL byte in the path"))
}

fn identity(meta: &Metadata) -> (u64, u64) {
    (meta.dev(), meta.ino())
}
