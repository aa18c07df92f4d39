//! Every output a command writes is checked before its work starts, and a
//! set of outputs appears together or not at all: `render`, `bake`,
//! `export`, `preview` and `demo` each refuse a name too long, a missing
//! folder, a read-only folder, a folder where a file goes (or a file where
//! a folder goes) and two outputs that are one file (or an output that is
//! an input) with one line and exit code 2, and leave the folder they were
//! run in exactly as it was: every entry's kind, size, modification time,
//! inode and mode, the folder's own included. Each refusal is made with
//! both kinds of temporaries (unnamed `O_TMPFILE` files and named ones).

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

mod common;

use std::fs;
use std::os::unix::fs::{symlink, MetadataExt};
use std::path::{Path, PathBuf};
use std::process::Command;

use common::{command, irid_in, Run, Scratch};

/// Every entry under `dir` and `dir` itself, one line each: path, kind,
/// size, modification time (ns), inode and mode.
fn listing(dir: &Path) -> Vec<String> {
    let mut lines = Vec::new();
    let mut stack = vec![PathBuf::new()];
    while let Some(rel) = stack.pop() {
        let path = dir.join(&rel);
        let m = fs::symlink_metadata(&path).unwrap();
        let kind = if m.is_dir() {
            "dir"
        } else if m.is_symlink() {
            "link"
        } else {
            "file"
        };
        lines.push(format!(
            "{} {kind} {} {}.{:09} ino {} mode {:o}",
            rel.display(),
            m.len(),
            m.mtime(),
            m.mtime_nsec(),
            m.ino(),
            m.mode()
        ));
        if m.is_dir() {
            for entry in fs::read_dir(&path).unwrap() {
                stack.push(rel.join(entry.unwrap().file_name()));
            }
        }
    }
    lines.sort();
    lines
}

/// Runs `irid args...` in `dir` with named temporaries or not.
fn irid_named(dir: &Path, args: &[&str], named: bool) -> Run {
    let mut cmd = command();
    cmd.args(args).current_dir(dir);
    set_named(&mut cmd, named);
    run(&mut cmd)
}

fn set_named(cmd: &mut Command, named: bool) {
    if named {
        cmd.env(irid::atomic::NAMED_TEMPORARIES_ENV, "1");
    } else {
        cmd.env_remove(irid::atomic::NAMED_TEMPORARIES_ENV);
    }
}

fn run(cmd: &mut Command) -> Run {
    let out = cmd.output().expect("the command runs");
    Run {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// `irid args...` in `dir` fails with one line naming each of `needles`,
/// writes nothing on stdout (the work never started), and leaves `dir`
/// exactly as it was; with both kinds of temporaries.
fn refuses(dir: &Path, args: &[&str], needles: &[&str]) {
    for named in [false, true] {
        let before = listing(dir);
        let run = irid_named(dir, args, named);
        let what = format!("{args:?} (named temporaries: {named})");
        run.assert_one_line_error(&what, needles);
        assert_eq!(run.stdout, "", "{what}");
        assert_eq!(listing(dir), before, "{what} changed the folder");
    }
}

fn is_root() -> bool {
    // SAFETY: geteuid has no preconditions.
    unsafe { libc::geteuid() == 0 }
}

/// Runs `irid args...` in `dir` in a mount namespace of its own in which
/// `read_only` (inside `dir`) is a read-only bind mount: honest for root,
/// whom permission bits do not stop. A user who is not root maps
/// themselves to root in a user namespace to make the mount.
fn irid_read_only(dir: &Path, read_only: &str, args: &[&str], named: bool) -> Run {
    let mut cmd = Command::new("unshare");
    if !is_root() {
        cmd.arg("--map-root-user");
    }
    cmd.args([
        "--mount",
        "sh",
        "-c",
        r#"mount --bind "$1" "$1" && mount -o remount,bind,ro "$1" || exit 99; shift; exec "$@""#,
        "sh",
        read_only,
        env!("CARGO_BIN_EXE_irid"),
    ])
    .args(args)
    .current_dir(dir)
    .env(
        "IRID_CACHE_DIR",
        Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-cache"),
    );
    set_named(&mut cmd, named);
    let run = run(&mut cmd);
    assert_ne!(
        run.code,
        Some(99),
        "cannot make a read-only bind mount (needs util-linux's unshare and mount, and mount namespaces): {}",
        run.stderr
    );
    run
}

/// `irid args...` in `dir`, with the folder `read_only` read-only, fails
/// naming it and leaves `dir` as it was: on a read-only mount, and for a
/// user who is not root also through permission bits (0555).
fn refuses_read_only(dir: &Path, read_only: &str, args: &[&str]) {
    let needles = [read_only, "cannot write in its folder"];
    for named in [false, true] {
        let before = listing(dir);
        let run = irid_read_only(dir, read_only, args, named);
        let what = format!("{args:?} with {read_only} read-only (named: {named})");
        run.assert_one_line_error(&what, &needles);
        assert!(
            run.stderr.contains("Read-only file system"),
            "{what}: {}",
            run.stderr
        );
        assert_eq!(run.stdout, "", "{what}");
        assert_eq!(listing(dir), before, "{what} changed the folder");
    }
    if !is_root() {
        let folder = dir.join(read_only);
        let mode = fs::metadata(&folder).unwrap().mode();
        let read_only_mode = std::os::unix::fs::PermissionsExt::from_mode(0o555);
        fs::set_permissions(&folder, read_only_mode).unwrap();
        let before = listing(dir);
        let run = irid_named(dir, args, false);
        fs::set_permissions(&folder, std::os::unix::fs::PermissionsExt::from_mode(mode)).unwrap();
        run.assert_one_line_error(&format!("{args:?}, {read_only} mode 0555"), &needles);
        let mut after = listing(dir);
        // The mode was put back: only the listing taken while 0555 differs there.
        after.retain(|l| !l.starts_with(&format!("{read_only} ")));
        let mut was = before;
        was.retain(|l| !l.starts_with(&format!("{read_only} ")));
        assert_eq!(after, was);
    }
}

/// A name longer than NAME_MAX (255 bytes).
fn long_name(ext: &str) -> String {
    format!("{}{ext}", "n".repeat(300))
}

/// A path longer than PATH_MAX (4095 bytes).
fn long_path() -> String {
    format!("out/{}x", "a/".repeat(2100))
}

const SOAP: &str = "ambient = { n = 1.0 }\nsubstrate = { n = 1.0 }\n\
                    [[layers]]\nn = 1.33\nthickness_nm = 500.0\n";

/// A scratch folder with a stack file, `out/` holding an earlier image
/// `r.png` (with a hard link `hard.png` and a symbolic link `link.png` to
/// it) and a folder `sub`, and `outlink`, a symbolic link to `out`.
fn scratch(name: &str) -> Scratch {
    let dir = Scratch::new(name);
    dir.write("soap.toml", SOAP);
    fs::create_dir_all(dir.join("out/sub")).unwrap();
    fs::write(dir.join("out/r.png"), b"an earlier image").unwrap();
    fs::hard_link(dir.join("out/r.png"), dir.join("out/hard.png")).unwrap();
    symlink("r.png", dir.join("out/link.png")).unwrap();
    symlink("out", dir.join("outlink")).unwrap();
    dir
}

/// A small render, by direct evaluation: no table to bake.
const RENDER: [&str; 11] = [
    "render",
    "bubbles-uniform",
    "--width",
    "8",
    "--height",
    "6",
    "--spp",
    "1",
    "--film",
    "direct",
    "--sampling",
];

fn render(extra: &[&str]) -> Vec<String> {
    let mut args: Vec<String> = RENDER.iter().map(|s| s.to_string()).collect();
    args.push("rgb3".into());
    args.extend(extra.iter().map(|s| s.to_string()));
    args
}

fn strs(args: &[String]) -> Vec<&str> {
    args.iter().map(String::as_str).collect()
}

#[test]
fn render_checks_both_images_before_rendering() {
    let dir = scratch("outputs-render");
    let d = dir.path();
    let exr_long = format!("out/{}", long_name(".exr"));
    let long_path = long_path();
    let cases: [(&[&str], &[&str]); 7] = [
        (
            &["-o", "out/r.png", "--exr", &exr_long],
            &["304 bytes", "255"],
        ),
        (&["-o", "out/r.png", "--exr", &long_path], &["4095"]),
        (
            &["-o", "out/r.png", "--exr", "nope/r.exr"],
            &["nope does not exist"],
        ),
        // Without -o the PNG goes into out/ (made if missing): not made.
        (&["--exr", "nope/r.exr"], &["nope does not exist"]),
        (
            &["-o", "out/r.png", "--exr", "out/sub"],
            &["out/sub", "is a folder"],
        ),
        (
            &["-o", "out/sub", "--exr", "out/r.exr"],
            &["out/sub", "is a folder"],
        ),
        (
            &["-o", "out/x.png", "--exr", "out/sub/../x.png"],
            &["the same file as"],
        ),
    ];
    for (extra, needles) in cases {
        refuses(d, &strs(&render(extra)), needles);
    }
    // r.png itself, and through ./, a symbolic link to its folder, a
    // symbolic link to it and a hard link to it.
    for exr in [
        "out/r.png",
        "./out/r.png",
        "outlink/r.png",
        "out/link.png",
        "out/hard.png",
    ] {
        let args = render(&["-o", "out/r.png", "--exr", exr]);
        refuses(d, &strs(&args), &[exr, "the same file as out/r.png"]);
    }
    // A scene file is an input too.
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/hostile/render_exr_fail/scene.toml"
    );
    fs::copy(scene, d.join("scene.toml")).unwrap();
    let mut args = vec!["render", "scene.toml", "-o", "r.png", "--exr", "scene.toml"];
    args.extend_from_slice(&RENDER[2..]);
    args.push("rgb3");
    refuses(d, &args, &["is also an input"]);
    fs::create_dir(d.join("fine")).unwrap();
    refuses_read_only(
        d,
        "out",
        &strs(&render(&["-o", "fine/r.png", "--exr", "out/r.exr"])),
    );
    refuses_read_only(d, "out", &strs(&render(&["-o", "out/new.png"])));
}

#[test]
fn render_writes_both_images_and_keeps_links() {
    let dir = scratch("outputs-render-ok");
    let d = dir.path();
    for named in [false, true] {
        let args = render(&["-o", "out/link.png", "--exr", "out/r.exr"]);
        let run = irid_named(d, &strs(&args), named);
        assert!(run.success(), "{run:?}");
        // Written through the link: r.png is the new image, the link and
        // the hard link's old content stay.
        assert!(fs::symlink_metadata(d.join("out/link.png"))
            .unwrap()
            .is_symlink());
        assert!(fs::read(d.join("out/r.png"))
            .unwrap()
            .starts_with(b"\x89PNG"));
        assert_eq!(
            fs::read(d.join("out/hard.png")).unwrap(),
            b"an earlier image"
        );
        assert_eq!(
            names(&d.join("out")),
            ["hard.png", "link.png", "r.exr", "r.png", "sub"]
        );
    }
    // Without -o: out/SCENE.png, out/ made in a folder without one.
    fs::create_dir(d.join("fresh")).unwrap();
    let run = irid_in(&d.join("fresh"), strs(&render(&[])));
    assert!(run.success(), "{run:?}");
    assert_eq!(names(&d.join("fresh/out")), ["bubbles-uniform.png"]);
}

fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn bake(output: &str) -> Vec<String> {
    [
        "bake",
        "soap.toml",
        "--resolution",
        "4,4",
        "--validate-points",
        "0",
        "-o",
        output,
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

#[test]
fn bake_checks_its_table_before_baking() {
    let dir = scratch("outputs-bake");
    let d = dir.path();
    symlink("soap.toml", d.join("soaplink.toml")).unwrap();
    let long = format!("out/{}", long_name(".exr"));
    let cases: [(&str, &[&str]); 6] = [
        (&long, &["304 bytes", "255"]),
        (&long_path(), &["4095"]),
        ("nope/t.exr", &["nope does not exist"]),
        ("out/sub", &["out/sub", "is a folder"]),
        ("soap.toml", &["soap.toml", "is also an input"]),
        ("soaplink.toml", &["soaplink.toml", "is also an input"]),
    ];
    for (output, needles) in cases {
        refuses(d, &strs(&bake(output)), needles);
    }
    refuses_read_only(d, "out", &strs(&bake("out/t.exr")));
    for named in [false, true] {
        let run = irid_named(d, &strs(&bake("out/r.png")), named);
        assert!(run.success(), "{run:?}");
        assert!(fs::read(d.join("out/r.png"))
            .unwrap()
            .starts_with(&[0x76, 0x2f, 0x31, 0x01]));
        assert_eq!(
            fs::read(d.join("out/hard.png")).unwrap(),
            b"an earlier image"
        );
        assert_eq!(
            names(&d.join("out")),
            ["hard.png", "link.png", "r.png", "sub"]
        );
    }
}

fn export(output: &str) -> Vec<String> {
    ["export", "soap.toml", "--points", "100", "-q", "-o", output]
        .iter()
        .map(|s| s.to_string())
        .collect()
}

/// `out/mine`, a folder that is neither empty nor an export or preview.
fn foreign_folder(d: &Path) {
    fs::create_dir(d.join("out/mine")).unwrap();
    fs::write(d.join("out/mine/notes.txt"), b"keep").unwrap();
}

#[test]
fn export_checks_its_folder_before_computing() {
    let dir = scratch("outputs-export");
    let d = dir.path();
    foreign_folder(d);
    let long = format!("out/{}", long_name(""));
    let cases: [(&str, &[&str]); 6] = [
        (&long, &["300 bytes", "255"]),
        (&long_path(), &["4095"]),
        ("nope/e", &["nope does not exist"]),
        (
            "out/mine",
            &["out/mine", "neither empty nor an irid export"],
        ),
        ("out/r.png", &["out/r.png", "not a folder"]),
        ("soap.toml", &["soap.toml", "is also an input"]),
    ];
    for (output, needles) in cases {
        refuses(d, &strs(&export(output)), needles);
    }
    refuses_read_only(d, "out", &strs(&export("out/e")));

    // Written, then replaced by a second export; nothing else is left.
    for named in [false, true] {
        let run = irid_named(d, &strs(&export("out/e/")), named);
        assert!(run.success(), "{run:?}");
        assert!(names(&d.join("out/e")).contains(&"film.json".to_string()));
        assert_eq!(
            names(&d.join("out")),
            ["e", "hard.png", "link.png", "mine", "r.png", "sub"]
        );
    }
}

fn preview(output: &str) -> Vec<&str> {
    vec!["preview", "exp", "-o", output]
}

#[test]
fn preview_checks_its_folder_before_reading_the_exports() {
    let dir = scratch("outputs-preview");
    let d = dir.path();
    foreign_folder(d);
    let run = irid_in(d, strs(&export("exp")));
    assert!(run.success(), "{run:?}");
    let long = format!("out/{}", long_name(""));
    let long_path = long_path();
    let cases: [(&str, &[&str]); 8] = [
        (&long, &["300 bytes", "255"]),
        (&long_path, &["4095"]),
        ("nope/p", &["nope does not exist"]),
        ("out/mine", &["out/mine", "not an irid preview"]),
        ("out/r.png", &["out/r.png", "not a folder"]),
        ("exp", &["exp", "is also an input"]),
        ("./exp/", &["exp", "is also an input"]),
        ("out/../exp", &["exp", "is also an input"]),
    ];
    for (output, needles) in cases {
        refuses(d, &preview(output), needles);
    }
    refuses_read_only(d, "out", &preview("out/p"));
    for named in [false, true] {
        let run = irid_named(d, &preview("out/p"), named);
        assert!(run.success(), "{run:?}");
        assert!(d.join("out/p/index.html").is_file());
        assert_eq!(
            names(&d.join("out")),
            ["hard.png", "link.png", "mine", "p", "r.png", "sub"]
        );
    }
}

/// `irid demo --out OUT`, with its own table cache inside the scratch
/// folder: a refused demo leaves the cache unmade, as it bakes nothing.
fn demo(out: &str) -> Vec<&str> {
    vec!["demo", "--out", out, "--cache", "cache"]
}

#[test]
fn demo_checks_every_image_before_baking() {
    let dir = scratch("outputs-demo");
    let d = dir.path();
    // out/ with a folder where an image goes; a second folder whose images
    // include two names of one file (a hard link and a symbolic link).
    fs::create_dir(d.join("out/bubbles-noise.png")).unwrap();
    for (k, link) in [(0, "gain-ring.png"), (1, "blue-gem.direct.png")] {
        let folder = d.join(format!("twice{k}"));
        fs::create_dir(&folder).unwrap();
        fs::write(folder.join("bubbles-uniform.png"), b"earlier").unwrap();
        if k == 0 {
            fs::hard_link(folder.join("bubbles-uniform.png"), folder.join(link)).unwrap();
        } else {
            symlink("bubbles-uniform.png", folder.join(link)).unwrap();
        }
    }
    let long = long_name("");
    let long_path = long_path();
    let cases: [(&str, &[&str]); 7] = [
        (&long, &["300 bytes", "255"]),
        (&long_path, &["4095"]),
        ("nope/out", &["nope does not exist"]),
        ("out", &["out/bubbles-noise.png", "is a folder"]),
        ("out/r.png", &["out/r.png", "not a folder"]),
        ("twice0", &["twice0/gain-ring.png", "the same file as"]),
        (
            "twice1",
            &["twice1/blue-gem.direct.png", "the same file as"],
        ),
    ];
    for (out, needles) in cases {
        refuses(d, &demo(out), needles);
    }
    // A missing --out in a read-only folder, and a read-only --out.
    refuses_read_only(d, "out", &demo("out/new"));
    refuses_read_only(d, "out/sub", &demo("out/sub"));
    assert!(!d.join("cache").exists());
}

/// A demo ended by SIGTERM while it works leaves nothing: not its images,
/// not the `--out` folder it made (the one change is the modification time
/// of the folder it was made in); with both kinds of temporaries (the
/// named ones exist from the start of the work).
#[test]
fn an_interrupted_demo_leaves_nothing() {
    use std::io::BufRead;
    let dir = Scratch::new("outputs-demo-term");
    let cache = Scratch::new("outputs-demo-term-cache");
    for named in [false, true] {
        let before = listing(&dir);
        let mut cmd = command();
        cmd.args(["demo", "--out", "new", "--cache"])
            .arg(cache.path())
            .current_dir(dir.path())
            .stdout(std::process::Stdio::piped());
        set_named(&mut cmd, named);
        let mut child = cmd.spawn().unwrap();
        // The first line comes once the outputs are prepared, before the
        // first bake.
        let mut line = String::new();
        let mut stdout = std::io::BufReader::new(child.stdout.take().unwrap());
        stdout.read_line(&mut line).unwrap();
        assert!(line.starts_with("irid demo"), "{line}");
        assert!(dir.join("new").is_dir());
        if named {
            // A table-rendered and a directly rendered image per scene.
            let images = 2 * irid::render::builtin_names().len();
            assert_eq!(names(&dir.join("new")).len(), images);
        }
        // SAFETY: signals a child process this test started.
        unsafe { libc::kill(child.id() as i32, libc::SIGTERM) };
        let status = child.wait().unwrap();
        use std::os::unix::process::ExitStatusExt;
        assert_eq!(status.signal(), Some(libc::SIGTERM), "named {named}");
        // All but the folder's own modification time, which making and
        // removing `new` changed.
        let entries = |l: Vec<String>| l[1..].to_vec();
        assert!(listing(&dir)[0].starts_with(" dir "));
        assert_eq!(entries(listing(&dir)), entries(before), "named {named}");
        assert_eq!(names(&dir), Vec::<String>::new());
    }
}
