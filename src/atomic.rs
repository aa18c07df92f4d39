//! Output files appear whole or not at all, alone or as a set.
//!
//! On Linux each output is first written to an unnamed file in the target's
//! directory (`O_TMPFILE`): if the process dies, even by SIGKILL, the file
//! vanishes with it. Once every output of a set is written, each is linked
//! under a temporary name and renamed over its target. Where `O_TMPFILE` is
//! unsupported (other systems, some file systems) or disabled by the
//! [`NAMED_TEMPORARIES_ENV`] environment variable, outputs are written to
//! named temporaries `.PID-N.tmp.NAME`, removed on failure, on SIGINT and on
//! SIGTERM; those a killed process left behind are swept at the next write
//! into the same directory once their process is gone.

use std::ffi::CString;
use std::fs::File;
use std::os::unix::ffi::OsStrExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicPtr, AtomicUsize, Ordering};

use crate::error::{Error, Result};

/// Set (to anything) to write through named temporaries even where
/// `O_TMPFILE` works: the fallback path, for tests.
pub const NAMED_TEMPORARIES_ENV: &str = "IRID_NAMED_TEMPORARIES";

/// The longest file name (bytes) on the file systems irid writes to; a
/// temporary name is shortened from the front to fit.
pub const NAME_MAX: usize = 255;

/// A writer of one output: given a path to write (a temporary), it writes
/// the whole file there.
pub type Writer<'a> = Box<dyn FnOnce(&Path) -> Result<()> + 'a>;

/// Runs `write` on a temporary in the target's directory, then moves the
/// result to `path`; on any failure nothing is left behind.
pub fn write_with(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    write_set(vec![(path.to_path_buf(), Box::new(write))])
}

/// Writes `bytes` to `path` atomically; errors name `path`, not the temporary.
pub fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    write_with(path, |tmp| {
        std::fs::write(tmp, bytes).map_err(|e| Error::io(path, e))
    })
}

/// Writes several outputs as a set: every writer runs first, each into its
/// own temporary, and only when all have succeeded are the files moved into
/// place. A failed writer leaves every target as it was. Two outputs naming
/// the same file, a target that is a directory, or a missing directory are
/// refused before anything is written.
pub fn write_set(outputs: Vec<(PathBuf, Writer<'_>)>) -> Result<()> {
    let named = std::env::var_os(NAMED_TEMPORARIES_ENV).is_some();
    write_set_with(outputs, named)
}

/// [`write_set`] with the temporary kind chosen: `named` forces the fallback.
pub fn write_set_with(outputs: Vec<(PathBuf, Writer<'_>)>, named: bool) -> Result<()> {
    let mut seen: Vec<(PathBuf, std::ffi::OsString)> = Vec::new();
    for (path, _) in &outputs {
        let (dir, name) = split(path)?;
        let key = (
            dir.canonicalize().unwrap_or(dir.clone()),
            name.to_os_string(),
        );
        if seen.contains(&key) {
            return Err(Error::invalid(
                path.display().to_string(),
                "named twice as an output: each output needs its own file",
            ));
        }
        if path.is_dir() {
            return Err(Error::io(
                path,
                std::io::Error::new(std::io::ErrorKind::IsADirectory, "is a directory"),
            ));
        }
        sweep_stale(&dir);
        seen.push(key);
    }
    let mut temps = Vec::with_capacity(outputs.len());
    for (path, write) in outputs {
        let temp = Temp::new(&path, named)?;
        write(&temp.path)?;
        temps.push((path, temp));
    }
    for (path, temp) in temps {
        temp.commit(&path)?;
    }
    Ok(())
}

/// The target's directory ("." for a bare name) and file name; the
/// directory must exist.
fn split(path: &Path) -> Result<(PathBuf, &std::ffi::OsStr)> {
    let name = path
        .file_name()
        .ok_or_else(|| Error::invalid(path.display().to_string(), "not a file path"))?;
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
    Ok((dir, name))
}

/// Distinguishes the temporaries of one process.
static COUNTER: AtomicUsize = AtomicUsize::new(0);

/// `.PID-N.tmp.NAME` in `dir`, NAME shortened from the front (keeping its
/// extension) so the whole stays within [`NAME_MAX`] bytes.
fn temporary_name(dir: &Path, name: &std::ffi::OsStr) -> PathBuf {
    let prefix = format!(
        ".{}-{}.tmp.",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    );
    let bytes = name.as_bytes();
    let keep = NAME_MAX.saturating_sub(prefix.len()).min(bytes.len());
    let tail = &bytes[bytes.len() - keep..];
    let mut full = prefix.into_bytes();
    full.extend_from_slice(tail);
    dir.join(std::ffi::OsStr::from_bytes(&full))
}

/// The process id in a temporary's name, if it is one of ours.
fn temporary_owner(name: &[u8]) -> Option<i32> {
    let rest = name.strip_prefix(b".")?;
    let end = rest.iter().position(|&b| b == b'-')?;
    let (pid, rest) = rest.split_at(end);
    let rest = &rest[1..];
    let n_end = rest.iter().position(|&b| !b.is_ascii_digit())?;
    if n_end == 0 || !rest[n_end..].starts_with(b".tmp.") {
        return None;
    }
    std::str::from_utf8(pid).ok()?.parse().ok()
}

/// Removes temporaries in `dir` left by processes that no longer exist
/// (killed while writing through named temporaries). Best effort: a file
/// that cannot be read or removed is left alone.
fn sweep_stale(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = temporary_owner(name.as_bytes()) else {
            continue;
        };
        if pid <= 0 || pid as u32 == std::process::id() {
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

/// One output's temporary.
struct Temp {
    /// Where the writer writes: `/proc/self/fd/N` of an unnamed file, or
    /// the named temporary.
    path: PathBuf,
    /// The unnamed file, kept open so that it lives until linked.
    unnamed: Option<File>,
    /// The named temporary's signal registration (named kind only).
    guard: Option<Registered>,
    dir: PathBuf,
    name: std::ffi::OsString,
}

impl Temp {
    fn new(target: &Path, named: bool) -> Result<Temp> {
        let (dir, name) = split(target)?;
        let name = name.to_os_string();
        if !named {
            if let Some(file) = open_unnamed(&dir) {
                use std::os::fd::AsRawFd;
                let path = PathBuf::from(format!("/proc/self/fd/{}", file.as_raw_fd()));
                if path.exists() {
                    return Ok(Temp {
                        path,
                        unnamed: Some(file),
                        guard: None,
                        dir,
                        name,
                    });
                }
            }
        }
        let path = temporary_name(&dir, &name);
        let guard = Registered::new(&path);
        Ok(Temp {
            path,
            unnamed: None,
            guard: Some(guard),
            dir,
            name,
        })
    }

    /// Moves the written file to `target`.
    fn commit(mut self, target: &Path) -> Result<()> {
        if self.unnamed.is_some() {
            // linkat needs a name that does not exist yet: link under a
            // fresh temporary (registered for signals), then rename.
            let named = temporary_name(&self.dir, &self.name);
            let guard = Registered::new(&named);
            let from = CString::new(self.path.as_os_str().as_bytes()).expect("no NUL in a path");
            let to = CString::new(named.as_os_str().as_bytes())
                .map_err(|_| Error::invalid(target.display().to_string(), "NUL in the path"))?;
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
                return Err(Error::io(target, std::io::Error::last_os_error()));
            }
            self.unnamed = None;
            self.path = named;
            self.guard = Some(guard);
        }
        std::fs::rename(&self.path, target).map_err(|e| Error::io(target, e))?;
        // Renamed: nothing to remove any more.
        self.guard = None;
        self.path = PathBuf::new();
        Ok(())
    }
}

impl Drop for Temp {
    fn drop(&mut self) {
        if self.unnamed.is_none() && !self.path.as_os_str().is_empty() {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// An unnamed file in `dir`, or None where the system or file system does
/// not support `O_TMPFILE`.
fn open_unnamed(dir: &Path) -> Option<File> {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::OpenOptionsExt;
        std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(libc::O_TMPFILE)
            .open(dir)
            .ok()
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = dir;
        None
    }
}

/// Named temporaries that a SIGINT or SIGTERM handler removes. The paths
/// are leaked C strings: the handler may read one at any moment, so they
/// are never freed (a hundred bytes per named write).
static PENDING: [AtomicPtr<libc::c_char>; 64] =
    [const { AtomicPtr::new(std::ptr::null_mut()) }; 64];

/// The dispositions SIGINT and SIGTERM had before ours, restored and
/// re-raised once the temporaries are gone.
struct Previous([libc::sigaction; 2]);
// SAFETY: written once before the handler is installed, then only read.
unsafe impl Sync for Previous {}
// SAFETY: as for Sync: the saved dispositions are plain data, never mutated after the first write.
unsafe impl Send for Previous {}
static PREVIOUS: std::sync::OnceLock<Previous> = std::sync::OnceLock::new();
const SIGNALS: [libc::c_int; 2] = [libc::SIGINT, libc::SIGTERM];

extern "C" fn remove_pending_and_reraise(signal: libc::c_int) {
    for slot in &PENDING {
        let p = slot.load(Ordering::SeqCst);
        if !p.is_null() {
            // SAFETY: p is a leaked, NUL-terminated path; unlink is
            // async-signal-safe.
            unsafe { libc::unlink(p) };
        }
    }
    if let (Some(previous), Some(k)) = (PREVIOUS.get(), SIGNALS.iter().position(|&s| s == signal)) {
        // SAFETY: restores the disposition saved at installation, then
        // delivers the signal to it (by default: the process ends).
        unsafe {
            libc::sigaction(signal, &previous.0[k], std::ptr::null_mut());
            libc::raise(signal);
        }
    }
}

fn install_handlers() {
    PREVIOUS.get_or_init(|| {
        // SAFETY: sigaction with a zeroed struct, our handler and an empty
        // mask; the old dispositions are saved for the handler to restore.
        unsafe {
            let mut old: [libc::sigaction; 2] = std::mem::zeroed();
            for (k, &signal) in SIGNALS.iter().enumerate() {
                let mut action: libc::sigaction = std::mem::zeroed();
                action.sa_sigaction =
                    remove_pending_and_reraise as extern "C" fn(libc::c_int) as usize;
                libc::sigemptyset(&mut action.sa_mask);
                libc::sigaction(signal, &action, &mut old[k]);
            }
            Previous(old)
        }
    });
}

/// A named temporary registered for removal on SIGINT and SIGTERM while
/// this lives (if a slot is free; otherwise the next write's sweep
/// removes it should the process be killed).
struct Registered(Option<usize>);

impl Registered {
    fn new(path: &Path) -> Registered {
        install_handlers();
        let Ok(c) = CString::new(path.as_os_str().as_bytes()) else {
            return Registered(None);
        };
        let raw = c.into_raw();
        for (k, slot) in PENDING.iter().enumerate() {
            if slot
                .compare_exchange(
                    std::ptr::null_mut(),
                    raw,
                    Ordering::SeqCst,
                    Ordering::SeqCst,
                )
                .is_ok()
            {
                return Registered(Some(k));
            }
        }
        Registered(None)
    }
}

impl Drop for Registered {
    fn drop(&mut self) {
        if let Some(k) = self.0 {
            PENDING[k].store(std::ptr::null_mut(), Ordering::SeqCst);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn listing(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn writes_whole_files_and_leaves_nothing_on_failure() {
        for named in [false, true] {
            let dir = tempfile::tempdir().unwrap();
            let target = dir.path().join("out.txt");
            let bytes = |b: &'static [u8]| -> Writer<'static> {
                Box::new(move |tmp: &Path| std::fs::write(tmp, b).map_err(|e| Error::io(tmp, e)))
            };
            write_set_with(vec![(target.clone(), bytes(b"hello"))], named).unwrap();
            assert_eq!(std::fs::read(&target).unwrap(), b"hello");

            // A set whose second writer fails leaves the first target as
            // it was and no temporary.
            let other = dir.path().join("other.txt");
            let failing: Writer = Box::new(|tmp: &Path| {
                std::fs::write(tmp, b"half").unwrap();
                Err(Error::invalid("writer", "stopped half-way"))
            });
            let err = write_set_with(
                vec![(target.clone(), bytes(b"new")), (other.clone(), failing)],
                named,
            );
            assert!(err.is_err());
            assert_eq!(std::fs::read(&target).unwrap(), b"hello");
            assert_eq!(listing(dir.path()), ["out.txt"], "named: {named}");

            // The same file twice, and a directory as target, are refused.
            let twice = write_set_with(
                vec![
                    (target.clone(), bytes(b"a")),
                    (dir.path().join("./out.txt"), bytes(b"b")),
                ],
                named,
            );
            assert!(twice.unwrap_err().to_string().contains("named twice"));
            std::fs::create_dir(dir.path().join("sub")).unwrap();
            let into_dir = write_set_with(
                vec![
                    (other.clone(), bytes(b"a")),
                    (dir.path().join("sub"), bytes(b"b")),
                ],
                named,
            );
            assert!(into_dir.is_err());
            assert!(!other.exists());
            assert_eq!(listing(dir.path()), ["out.txt", "sub"]);

            let missing_dir = dir.path().join("nope").join("x.txt");
            assert!(write(&missing_dir, b"x").is_err());
        }
    }

    /// A name of NAME_MAX bytes is writable: its temporary is shortened.
    #[test]
    fn longest_names_are_writable() {
        for named in [false, true] {
            let dir = tempfile::tempdir().unwrap();
            let name = format!("{}.exr", "n".repeat(NAME_MAX - 4));
            let target = dir.path().join(&name);
            let writer: Writer =
                Box::new(|tmp: &Path| std::fs::write(tmp, b"x").map_err(|e| Error::io(tmp, e)));
            write_set_with(vec![(target.clone(), writer)], named).unwrap();
            assert_eq!(listing(dir.path()), [name]);
        }
        let short = temporary_name(Path::new("d"), std::ffi::OsStr::new(&"é".repeat(200)));
        let file = short.file_name().unwrap().as_bytes();
        assert!(file.len() <= NAME_MAX && file.ends_with("é".as_bytes()));
    }

    /// Temporaries of a process that is gone are swept at the next write;
    /// those of live processes and other files are not.
    #[test]
    fn stale_temporaries_are_swept() {
        let dir = tempfile::tempdir().unwrap();
        // Beyond the kernel's largest process id: never alive.
        let stale = ".999999999-3.tmp.t.exr";
        let live = format!(".{}-0.tmp.t.exr", std::process::id());
        for name in [stale, live.as_str(), ".12-x.tmp.a", "keep.exr"] {
            std::fs::write(dir.path().join(name), b"x").unwrap();
        }
        write(&dir.path().join("t.exr"), b"new").unwrap();
        let mut want = vec![
            live.clone(),
            ".12-x.tmp.a".into(),
            "keep.exr".into(),
            "t.exr".into(),
        ];
        want.sort();
        assert_eq!(listing(dir.path()), want);
        assert_eq!(temporary_owner(b".42-7.tmp.x"), Some(42));
        assert_eq!(temporary_owner(b".42.tmp.x"), None);
    }
}
