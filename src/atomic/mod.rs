//! Outputs appear whole or not at all, alone or as a set.
//!
//! A command declares every output it will write in an [`OutputSet`] before
//! it does any work. [`OutputSet::prepare`] checks them all (see
//! [`OutputSet::prepare`] for the list) without touching anything, so a bad
//! path fails in milliseconds, before a bake or a render; then it creates
//! every file's temporary. The command writes each output into its temporary
//! ([`Prepared::write`]) as its work produces it, and [`Prepared::commit`]
//! puts the whole set in place, or none of it.
//!
//! On Linux a file's temporary is an unnamed file in the target's folder
//! (`O_TMPFILE`): if the process dies, even by SIGKILL, it vanishes with it.
//! Where `O_TMPFILE` is unsupported (other systems, some file systems) or
//! disabled by the [`NAMED_TEMPORARIES_ENV`] environment variable, outputs
//! are written to named temporaries `.PID-N.tmp.NAME`, removed on failure, on
//! SIGINT and on SIGTERM; those a killed process left behind are swept at the
//! next write into the same folder once their process is gone. A folder
//! output (an export, a preview) is built in a named folder of that form
//! beside its target.
//!
//! The commit gives every file a name in its folder (`.PID-N.tmp.NAME`),
//! then, output by output, keeps what the target held as `.PID-N.old.NAME`
//! (a hard link to a file; a folder is swapped with `renameat2`
//! `RENAME_EXCHANGE`, else moved aside) and renames the new one over it. If
//! any step fails, or SIGINT or SIGTERM arrives meanwhile (both are held
//! back during the commit), the outputs already placed are undone: each kept
//! original is renamed back, and a target that did not exist before is
//! removed. Only once every output is in place are the kept originals
//! deleted. A SIGKILL in the middle of those renames (microseconds) can leave
//! part of a set in place; the originals it replaced then remain as
//! `.PID-N.old.NAME` beside their targets, which no sweep removes.
//!
//! An output that is a symbolic link is written through it: the file it
//! points to is replaced and the link stays.

mod check;
mod place;
mod signals;
mod temp;

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

pub use check::Replace;
use check::{Checked, Target};
use place::Placed;
use temp::{Staging, Temp};

/// Set (to anything) to write through named temporaries even where
/// `O_TMPFILE` works: the fallback path, for tests.
pub const NAMED_TEMPORARIES_ENV: &str = "IRID_NAMED_TEMPORARIES";

/// The longest file name (bytes) on the file systems irid writes to; a
/// temporary name is shortened from the front to fit.
pub const NAME_MAX: usize = 255;

/// A writer of one output: given a path to write (a temporary), it writes
/// the whole file there.
pub type Writer<'a> = Box<dyn FnOnce(&Path) -> Result<()> + 'a>;

/// Runs `write` on a temporary in the target's folder, then moves the
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

/// Writes several files as a set ([`OutputSet`] with files only): every
/// path is checked first, every writer runs into its own temporary, and the
/// files appear together only when all have succeeded.
pub fn write_set(outputs: Vec<(PathBuf, Writer<'_>)>) -> Result<()> {
    let mut set = OutputSet::new();
    let handles: Vec<Output> = outputs.iter().map(|(path, _)| set.file(path)).collect();
    let mut prepared = set.prepare()?;
    for (handle, (_, writer)) in handles.into_iter().zip(outputs) {
        prepared.write(handle, writer)?;
    }
    prepared.commit()
}

/// Every output of one command, declared before the command's work.
#[derive(Debug)]
pub struct OutputSet {
    outputs: Vec<(PathBuf, Kind)>,
    inputs: Vec<PathBuf>,
    new_folders: Vec<PathBuf>,
    named: bool,
}

/// One declared output of an [`OutputSet`], to write and commit through the
/// [`Prepared`] set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Output(usize);

#[derive(Clone, Copy, Debug)]
enum Kind {
    File,
    Folder(Replace),
}

impl Default for OutputSet {
    fn default() -> Self {
        Self::new()
    }
}

impl OutputSet {
    /// An empty set; its temporaries are named when [`NAMED_TEMPORARIES_ENV`]
    /// is set.
    pub fn new() -> OutputSet {
        OutputSet {
            outputs: Vec::new(),
            inputs: Vec::new(),
            new_folders: Vec::new(),
            named: std::env::var_os(NAMED_TEMPORARIES_ENV).is_some(),
        }
    }

    /// Chooses the temporaries' kind: `named` forces the fallback.
    pub fn named_temporaries(mut self, named: bool) -> OutputSet {
        self.named = named;
        self
    }

    /// Declares a file output.
    pub fn file(&mut self, path: impl Into<PathBuf>) -> Output {
        self.outputs.push((path.into(), Kind::File));
        Output(self.outputs.len() - 1)
    }

    /// Declares a folder output, built whole and then put in place of
    /// `path`; an existing folder there is replaced only if `replace`
    /// allows it.
    pub fn folder(&mut self, path: impl Into<PathBuf>, replace: Replace) -> Output {
        self.outputs.push((path.into(), Kind::Folder(replace)));
        Output(self.outputs.len() - 1)
    }

    /// Declares a file or folder the command reads: no output may be it.
    pub fn input(&mut self, path: impl Into<PathBuf>) {
        self.inputs.push(path.into());
    }

    /// Declares a folder that outputs go into and that is made if missing
    /// (its parent must exist, as for `mkdir`); one this set makes is
    /// removed again unless the set commits.
    pub fn new_folder(&mut self, path: impl Into<PathBuf>) {
        self.new_folders.push(path.into());
    }

    /// Checks every output, changing nothing: each path fits the system's
    /// PATH_MAX and its name the file system's NAME_MAX; its folder exists
    /// (or is a [`new_folder`](Self::new_folder) whose parent does) and is
    /// writable; a file output is not a folder, and a folder output is not a
    /// file and is absent or replaceable; no two outputs are the same file
    /// (however spelled: `./`, symbolic links, hard links, bind mounts) and
    /// none is an input. Then it makes the missing new folders and creates
    /// every file's temporary.
    pub fn prepare(self) -> Result<Prepared> {
        let folders = self
            .new_folders
            .iter()
            .map(|f| check::new_folder(f))
            .collect::<Result<Vec<_>>>()?;
        let checked = self
            .outputs
            .iter()
            .map(|(path, kind)| check::output(path, matches!(kind, Kind::File), &folders))
            .collect::<Result<Vec<Checked>>>()?;
        check::distinct(&checked, &self.inputs)?;
        for ((_, kind), c) in self.outputs.iter().zip(&checked) {
            if let Kind::Folder(replace) = kind {
                replace.check(&c.target)?;
            }
        }

        let mut prepared = Prepared {
            entries: Vec::with_capacity(checked.len()),
            made_folders: Vec::new(),
            committed: false,
        };
        for folder in folders.iter().filter(|f| f.missing) {
            // Registered first: SIGINT or SIGTERM removes it again, once empty.
            let guard = signals::Registered::new(&folder.path);
            std::fs::create_dir(&folder.path).map_err(|e| Error::io(&folder.path, e))?;
            prepared.made_folders.push((folder.path.clone(), guard));
        }
        let mut swept: Vec<&Path> = Vec::new();
        for c in &checked {
            if !swept.contains(&c.target.dir.as_path()) {
                temp::sweep_stale(&c.target.dir);
                swept.push(&c.target.dir);
            }
        }
        for ((_, kind), c) in self.outputs.iter().zip(checked) {
            let content = match kind {
                Kind::File => Content::File(Temp::new(&c.target, self.named)?),
                Kind::Folder(replace) => Content::Folder(Staging::new(&c.target), *replace),
            };
            prepared.entries.push(Entry {
                target: c.target,
                content,
                written: false,
            });
        }
        Ok(prepared)
    }
}

/// A checked [`OutputSet`] with its temporaries: write every output, then
/// [`commit`](Self::commit). Dropped without a commit, it leaves every
/// target as it was and removes what it made.
#[derive(Debug)]
pub struct Prepared {
    entries: Vec<Entry>,
    /// Folders this set made, each registered for removal on a signal.
    made_folders: Vec<(PathBuf, signals::Registered)>,
    committed: bool,
}

#[derive(Debug)]
struct Entry {
    target: Target,
    content: Content,
    written: bool,
}

#[derive(Debug)]
enum Content {
    File(Temp),
    Folder(Staging, Replace),
}

impl Prepared {
    /// Writes `output`: `write` gets the path to write to (a file output's
    /// temporary, which it writes whole; for a folder output, the path at
    /// which it creates and fills the folder). Its errors should name the
    /// output, not that path.
    pub fn write(&mut self, output: Output, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
        let entry = self
            .entries
            .get_mut(output.0)
            .ok_or_else(|| Error::invalid("output", "not an output of this set"))?;
        if entry.written {
            return Err(Error::invalid(
                entry.target.given.display().to_string(),
                "written twice",
            ));
        }
        match &entry.content {
            Content::File(temp) => write(&temp.path)?,
            Content::Folder(staging, _) => {
                write(&staging.path)?;
                if !staging.path.is_dir() {
                    return Err(Error::invalid(
                        entry.target.given.display().to_string(),
                        "its writer made no folder",
                    ));
                }
            }
        }
        entry.written = true;
        Ok(())
    }

    /// Puts every output in place, or none: see the module's description.
    /// Every output must have been written.
    pub fn commit(mut self) -> Result<()> {
        if let Some(e) = self.entries.iter().find(|e| !e.written) {
            return Err(Error::invalid(
                e.target.given.display().to_string(),
                "was never written",
            ));
        }
        let committing = signals::Committing::begin();
        let result = self.put_in_place(&committing);
        if result.is_err() {
            self.discard();
        }
        // A signal held back is delivered here, once nothing is left behind.
        drop(committing);
        result
    }

    fn put_in_place(&mut self, committing: &signals::Committing) -> Result<()> {
        for entry in &mut self.entries {
            if let Content::File(temp) = &mut entry.content {
                temp.stage(&entry.target)?;
            }
        }
        let mut placed: Vec<Placed> = Vec::with_capacity(self.entries.len());
        for (k, entry) in self.entries.iter_mut().enumerate() {
            match place::place(entry, k) {
                Ok(p) => placed.push(p),
                Err(e) => {
                    place::undo(placed);
                    return Err(e);
                }
            }
        }
        if let Some(signal) = committing.interrupted() {
            place::undo(placed);
            return Err(Error::invalid(
                "outputs",
                format!("not written: signal {signal} arrived while they were put in place"),
            ));
        }
        for p in placed {
            p.finish();
        }
        self.committed = true;
        Ok(())
    }

    /// Removes every temporary, and the folders this set made.
    fn discard(&mut self) {
        // Temporaries first: a folder this set made is removed only once empty.
        self.entries.clear();
        if !self.committed {
            for (folder, _) in self.made_folders.drain(..).rev() {
                let _ = std::fs::remove_dir(folder);
            }
        }
    }
}

impl Drop for Prepared {
    fn drop(&mut self) {
        self.discard();
    }
}

#[cfg(test)]
mod tests;
