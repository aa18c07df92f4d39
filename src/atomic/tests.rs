use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::MetadataExt;

use super::place::tests::{FAIL_AT, RAISE_AT};
use super::temp::{temporary_name, temporary_owner, NEW};
use super::*;

fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Every entry under `dir` with its kind, size, inode and content (files),
/// to compare a folder before and after.
fn snapshot(dir: &Path) -> Vec<(String, bool, u64, u64, Vec<u8>)> {
    let mut all = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let m = std::fs::symlink_metadata(&path).unwrap();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let bytes = if m.is_file() {
            std::fs::read(&path).unwrap()
        } else {
            Vec::new()
        };
        all.push((name.clone(), m.is_dir(), m.len(), m.ino(), bytes));
        if m.is_dir() {
            for (sub, d, l, i, b) in snapshot(&path) {
                all.push((format!("{name}/{sub}"), d, l, i, b));
            }
        }
    }
    all.sort();
    all
}

fn bytes(b: &'static [u8]) -> impl FnOnce(&Path) -> Result<()> {
    move |tmp: &Path| std::fs::write(tmp, b).map_err(|e| Error::io(tmp, e))
}

/// Writes `outputs` (path, bytes) as one set.
fn write_files(outputs: &[(PathBuf, &'static [u8])], named: bool) -> Result<()> {
    let mut set = OutputSet::new().named_temporaries(named);
    let handles: Vec<Output> = outputs.iter().map(|(p, _)| set.file(p)).collect();
    let mut prepared = set.prepare()?;
    for (h, (_, b)) in handles.into_iter().zip(outputs) {
        prepared.write(h, bytes(b))?;
    }
    prepared.commit()
}

/// The error `outputs` are refused with, before anything is written.
fn refused(outputs: &[PathBuf], named: bool) -> String {
    let mut set = OutputSet::new().named_temporaries(named);
    for p in outputs {
        set.file(p);
    }
    set.prepare().unwrap_err().to_string()
}

#[test]
fn writes_whole_files_and_leaves_nothing_on_failure() {
    for named in [false, true] {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.txt");
        write_files(&[(target.clone(), b"hello")], named).unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"hello");

        // A set whose second writer fails leaves the first target as it was
        // and no temporary.
        let other = dir.path().join("other.txt");
        let mut set = OutputSet::new().named_temporaries(named);
        let (a, b) = (set.file(&target), set.file(&other));
        let mut prepared = set.prepare().unwrap();
        prepared.write(a, bytes(b"new")).unwrap();
        let failed = prepared.write(b, |tmp: &Path| {
            std::fs::write(tmp, b"half").unwrap();
            Err(Error::invalid("writer", "stopped half-way"))
        });
        assert!(failed.is_err());
        // Committing a set with an output unwritten is refused.
        assert!(prepared
            .commit()
            .unwrap_err()
            .to_string()
            .contains("never written"));
        assert_eq!(std::fs::read(&target).unwrap(), b"hello");
        assert_eq!(listing(dir.path()), ["out.txt"], "named: {named}");
    }
}

/// Each case is refused by prepare, which leaves the folder exactly as it
/// was: no temporary, no folder made.
#[test]
fn bad_outputs_are_refused_before_anything_is_written() {
    for named in [false, true] {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(d.join("keep.txt"), b"keep").unwrap();
        std::fs::create_dir(d.join("sub")).unwrap();
        std::os::unix::fs::symlink("sub", d.join("sublink")).unwrap();
        std::os::unix::fs::symlink("keep.txt", d.join("keeplink")).unwrap();
        std::fs::hard_link(d.join("keep.txt"), d.join("hard.txt")).unwrap();
        std::os::unix::fs::symlink("loop", d.join("loop")).unwrap();
        let before = snapshot(d);
        let ok = d.join("ok.txt");
        let long = d.join(format!("{}.exr", "n".repeat(300)));
        let deep = d.join(format!("{}x.txt", "a/".repeat(2100)));
        let cases: [(Vec<PathBuf>, &str); 11] = [
            (vec![ok.clone(), long], "304 bytes, longer than the 255"),
            (vec![ok.clone(), deep], "longer than the 4095"),
            (
                vec![ok.clone(), d.join("nope/x.txt")],
                "nope does not exist",
            ),
            (vec![ok.clone(), d.join("keep.txt/x")], "is not a folder"),
            (vec![ok.clone(), d.join("sub")], "is a folder"),
            (vec![ok.clone(), d.join("sublink")], "is a folder"),
            (vec![ok.clone(), d.join("./ok.txt")], "the same file as"),
            (
                vec![ok.clone(), d.join("sublink/../ok.txt")],
                "the same file as",
            ),
            (
                vec![d.join("keep.txt"), d.join("keeplink")],
                "the same file as",
            ),
            (
                vec![d.join("keep.txt"), d.join("hard.txt")],
                "the same file as",
            ),
            (vec![ok.clone(), d.join("loop")], "symbolic links"),
        ];
        for (outputs, why) in cases {
            let err = refused(&outputs, named);
            assert!(err.contains(why), "{outputs:?}: {err}");
            assert_eq!(snapshot(d), before, "{outputs:?}");
        }
        // Through a symbolic link to a folder, the same file as in it.
        let err = refused(&[d.join("sub/x"), d.join("sublink/x")], named);
        assert!(err.contains("the same file as"), "{err}");

        let mut set = OutputSet::new().named_temporaries(named);
        set.file(d.join("keeplink"));
        set.input(d.join("keep.txt"));
        let err = set.prepare().unwrap_err().to_string();
        assert!(err.contains("is also an input"), "{err}");

        // A new folder whose parent is missing; one that is a file.
        for (folder, why) in [
            ("nope/new", "nope does not exist"),
            ("keep.txt", "not a folder"),
        ] {
            let mut set = OutputSet::new().named_temporaries(named);
            set.new_folder(d.join(folder));
            set.file(d.join(folder).join("x.png"));
            let err = set.prepare().unwrap_err().to_string();
            assert!(err.contains(why), "{folder}: {err}");
        }
        assert_eq!(snapshot(d), before);
    }
}

/// A name of NAME_MAX bytes is writable: its temporary is shortened.
#[test]
fn longest_names_are_writable() {
    for named in [false, true] {
        let dir = tempfile::tempdir().unwrap();
        let name = format!("{}.exr", "n".repeat(NAME_MAX - 4));
        let target = dir.path().join(&name);
        write_files(&[(target.clone(), b"x")], named).unwrap();
        assert_eq!(listing(dir.path()), [name]);
    }
    let short = temporary_name(Path::new("d"), std::ffi::OsStr::new(&"é".repeat(200)), NEW);
    let file = short.file_name().unwrap().as_bytes();
    assert!(file.len() <= NAME_MAX && file.ends_with("é".as_bytes()));
}

/// Through a symbolic link the file it points to is replaced; the link stays.
#[test]
fn outputs_are_written_through_symbolic_links() {
    for named in [false, true] {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("real")).unwrap();
        std::fs::write(d.join("real/t.txt"), b"old").unwrap();
        std::os::unix::fs::symlink("real/t.txt", d.join("link.txt")).unwrap();
        // A dangling link: its file is made.
        std::os::unix::fs::symlink("real/new.txt", d.join("dangling.txt")).unwrap();
        write_files(
            &[
                (d.join("link.txt"), b"new"),
                (d.join("dangling.txt"), b"made"),
            ],
            named,
        )
        .unwrap();
        assert!(std::fs::symlink_metadata(d.join("link.txt"))
            .unwrap()
            .is_symlink());
        assert_eq!(std::fs::read(d.join("real/t.txt")).unwrap(), b"new");
        assert_eq!(std::fs::read(d.join("real/new.txt")).unwrap(), b"made");
        assert_eq!(listing(&d.join("real")), ["new.txt", "t.txt"]);
    }
}

/// When putting a later output in place fails, the ones already placed
/// are taken back: replaced files get their original (same inode) back,
/// new ones are removed, a replaced folder is restored, and nothing else
/// is left.
#[test]
fn a_set_that_fails_while_placed_is_undone() {
    for named in [false, true] {
        for fail_at in 0..4 {
            let dir = tempfile::tempdir().unwrap();
            let d = dir.path();
            std::fs::write(d.join("a.txt"), b"original a").unwrap();
            std::fs::create_dir(d.join("folder")).unwrap();
            std::fs::write(d.join("folder/mark"), b"original folder").unwrap();
            let before = snapshot(d);
            let mut set = OutputSet::new().named_temporaries(named);
            let a = set.file(d.join("a.txt"));
            let b = set.file(d.join("b.txt"));
            let replace = Replace {
                allowed: |p| p.join("mark").is_file(),
                otherwise: "not ours",
            };
            let folder = set.folder(d.join("folder"), replace);
            let c = set.folder(d.join("c"), replace);
            let mut prepared = set.prepare().unwrap();
            prepared.write(a, bytes(b"new a")).unwrap();
            prepared.write(b, bytes(b"new b")).unwrap();
            for out in [folder, c] {
                prepared
                    .write(out, |p| {
                        std::fs::create_dir(p).unwrap();
                        std::fs::write(p.join("mark"), b"new").map_err(|e| Error::io(p, e))
                    })
                    .unwrap();
            }
            FAIL_AT.set(Some(fail_at));
            let err = prepared.commit();
            FAIL_AT.set(None);
            assert!(err.is_err());
            assert_eq!(snapshot(d), before, "named {named}, failing at {fail_at}");
        }
    }
}

/// A set that commits replaces what was there, the folder included, and
/// keeps nothing.
#[test]
fn a_set_that_commits_replaces_files_and_folders() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("a.txt"), b"original a").unwrap();
    std::fs::create_dir(d.join("folder")).unwrap();
    std::fs::write(d.join("folder/old"), b"old").unwrap();
    let mut set = OutputSet::new();
    set.new_folder(d.join("made"));
    let a = set.file(d.join("a.txt"));
    let m = set.file(d.join("made/m.txt"));
    let folder = set.folder(
        d.join("folder"),
        Replace {
            allowed: |p| p.join("old").is_file(),
            otherwise: "not ours",
        },
    );
    let mut prepared = set.prepare().unwrap();
    assert!(d.join("made").is_dir());
    prepared.write(a, bytes(b"new a")).unwrap();
    prepared.write(m, bytes(b"m")).unwrap();
    prepared
        .write(folder, |p| {
            std::fs::create_dir(p).unwrap();
            std::fs::write(p.join("new"), b"new").map_err(|e| Error::io(p, e))
        })
        .unwrap();
    prepared.commit().unwrap();
    assert_eq!(listing(d), ["a.txt", "folder", "made"]);
    assert_eq!(listing(&d.join("folder")), ["new"]);
    assert_eq!(listing(&d.join("made")), ["m.txt"]);
    assert_eq!(std::fs::read(d.join("a.txt")).unwrap(), b"new a");

    // A folder the set made goes again when the set does not commit; an
    // existing one stays.
    let mut set = OutputSet::new();
    set.new_folder(d.join("again"));
    set.new_folder(d.join("made"));
    set.file(d.join("again/x"));
    set.file(d.join("made/y"));
    drop(set.prepare().unwrap());
    assert_eq!(listing(d), ["a.txt", "folder", "made"]);
    assert_eq!(listing(&d.join("made")), ["m.txt"]);
}

/// A folder that is neither absent nor replaceable is refused, as is a
/// file where a folder output goes.
#[test]
fn folder_outputs_replace_only_what_they_may() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("mine")).unwrap();
    std::fs::write(d.join("file"), b"x").unwrap();
    let replace = Replace {
        allowed: |_| false,
        otherwise: "holds other things",
    };
    for (name, why) in [("mine", "holds other things"), ("file", "not a folder")] {
        let mut set = OutputSet::new();
        set.folder(d.join(name), replace);
        let err = set.prepare().unwrap_err().to_string();
        assert!(err.contains(why), "{err}");
    }
    assert_eq!(listing(d), ["file", "mine"]);
}

const CHILD: &str = "IRID_TEST_SIGNAL_DURING_COMMIT";

/// SIGTERM arriving while a set is put in place is held back; the set is
/// undone, and then the signal ends the process. Run in a child process,
/// which the signal kills.
#[test]
fn a_signal_during_the_commit_undoes_the_set() {
    if let Some(dir) = std::env::var_os(CHILD) {
        let d = PathBuf::from(dir);
        // SAFETY: sets the default disposition, installing no handler.
        unsafe { libc::signal(libc::SIGTERM, libc::SIG_DFL) };
        let mut set = OutputSet::new();
        let a = set.file(d.join("a.txt"));
        let b = set.file(d.join("b.txt"));
        let mut prepared = set.prepare().unwrap();
        prepared.write(a, bytes(b"new a")).unwrap();
        prepared.write(b, bytes(b"new b")).unwrap();
        RAISE_AT.set(Some((1, libc::SIGTERM)));
        let _ = prepared.commit();
        // Not reached: the signal ends the process once the set is undone.
        std::fs::write(d.join("survived"), b"").unwrap();
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("a.txt"), b"original a").unwrap();
    let before = snapshot(d);
    let status = std::process::Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "atomic::tests::a_signal_during_the_commit_undoes_the_set",
            "--nocapture",
        ])
        .env(CHILD, d)
        .status()
        .unwrap();
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(status.signal(), Some(libc::SIGTERM), "{status:?}");
    assert_eq!(snapshot(d), before);
}

/// Temporaries of a process that is gone are swept at the next write;
/// those of live processes, originals kept by a commit, and other files
/// are not.
#[test]
fn stale_temporaries_are_swept() {
    let dir = tempfile::tempdir().unwrap();
    // Beyond the kernel's largest process id: never alive.
    let stale = ".999999999-3.tmp.t.exr";
    let kept = ".999999999-4.old.t.exr";
    let live = format!(".{}-0.tmp.t.exr", std::process::id());
    for name in [stale, kept, live.as_str(), ".12-x.tmp.a", "keep.exr"] {
        std::fs::write(dir.path().join(name), b"x").unwrap();
    }
    write(&dir.path().join("t.exr"), b"new").unwrap();
    let mut want = vec![
        live.clone(),
        kept.into(),
        ".12-x.tmp.a".into(),
        "keep.exr".into(),
        "t.exr".into(),
    ];
    want.sort();
    assert_eq!(listing(dir.path()), want);
    assert_eq!(temporary_owner(b".42-7.tmp.x"), Some(42));
    assert_eq!(temporary_owner(b".42-7.old.x"), None);
    assert_eq!(temporary_owner(b".42.tmp.x"), None);
}
