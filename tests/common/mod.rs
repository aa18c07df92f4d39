//! What the integration tests share: one way to run the `irid` binary and
//! capture what it did, one way to make a scratch folder, random stacks
//! and the renderer's white furnace.

// Each test binary compiles its own copy and uses only part of it.
#![allow(dead_code)]

pub mod furnace;
pub mod gradient;
pub mod random_stack;

#[cfg(feature = "cli")]
use std::ffi::OsStr;
use std::ops::Deref;
use std::path::{Path, PathBuf};
#[cfg(feature = "cli")]
use std::process::Command;

// The binary is built only with the `cli` feature, and without it a stale
// one from an earlier build may still sit in target/: the helpers that run
// it exist only with the feature, so a test that runs it and is not gated
// on the feature does not compile.

/// The `irid` binary, to run in the crate's root unless told otherwise,
/// with tables baked on demand kept in the build's scratch folder rather
/// than the user's cache.
#[cfg(feature = "cli")]
pub fn command() -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_irid"));
    cmd.current_dir(env!("CARGO_MANIFEST_DIR"));
    cmd.env(
        "IRID_CACHE_DIR",
        Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-cache"),
    );
    cmd
}

/// What one run of `irid` did.
#[derive(Debug)]
pub struct Run {
    /// None when a signal ended it.
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

impl Run {
    pub fn success(&self) -> bool {
        self.code == Some(0)
    }

    /// Asserts the command-line error shape: exit code 2 and one stderr line
    /// `irid: ...` naming each of `needles`; `what` says which run failed.
    pub fn assert_one_line_error(&self, what: &str, needles: &[&str]) {
        let err = &self.stderr;
        assert_eq!(self.code, Some(2), "{what}: {err}");
        assert_eq!(err.lines().count(), 1, "{what}: {err}");
        assert!(err.starts_with("irid: "), "{what}: {err}");
        for needle in needles {
            assert!(err.contains(needle), "{what}: {err:?} lacks {needle:?}");
        }
    }
}

/// Runs `irid args...` in the crate's root and waits for it.
#[cfg(feature = "cli")]
pub fn irid<I: IntoIterator<Item = S>, S: AsRef<OsStr>>(args: I) -> Run {
    run(command().args(args))
}

/// Runs `irid args...` in `dir` and waits for it.
#[cfg(feature = "cli")]
pub fn irid_in<I: IntoIterator<Item = S>, S: AsRef<OsStr>>(dir: &Path, args: I) -> Run {
    run(command().args(args).current_dir(dir))
}

#[cfg(feature = "cli")]
fn run(cmd: &mut Command) -> Run {
    let out = cmd.output().expect("irid runs");
    Run {
        code: out.status.code(),
        stdout: String::from_utf8(out.stdout).expect("irid writes UTF-8 to stdout"),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// A fresh folder in the system's temporary directory, removed with
/// everything in it when dropped; it reads as its path.
pub struct Scratch(tempfile::TempDir);

impl Scratch {
    /// `name` appears in the folder's name, to tell whose it is.
    pub fn new(name: &str) -> Scratch {
        Scratch(
            tempfile::Builder::new()
                .prefix(&format!("irid-{name}-"))
                .tempdir()
                .expect("a scratch folder"),
        )
    }

    pub fn path(&self) -> &Path {
        self.0.path()
    }

    /// Writes `contents` to `name` in the folder; its path.
    pub fn write(&self, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
        let path = self.join(name);
        std::fs::write(&path, contents).unwrap();
        path
    }
}

impl Deref for Scratch {
    type Target = Path;

    fn deref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        self.0.path()
    }
}

/// An OpenEXR file read whole: its first layer, every channel as flat
/// samples, and every attribute (the irid header among them).
pub fn read_exr(
    path: &Path,
) -> exr::prelude::Image<exr::prelude::Layer<exr::prelude::AnyChannels<exr::prelude::FlatSamples>>>
{
    use exr::prelude::{ReadChannels, ReadLayers};
    exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}
