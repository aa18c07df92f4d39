//! A write interrupted by SIGINT, SIGTERM or SIGKILL leaves no temporary
//! file, on both paths of `irid::atomic`: the unnamed `O_TMPFILE` file, and
//! named temporaries (removed by the signal handler, or after SIGKILL by the
//! next write's sweep). The test runs itself as the child that is killed in
//! the middle of writing.

use std::path::{Path, PathBuf};
use std::process::{Child, Command};
use std::time::{Duration, Instant};

const CHILD_DIR: &str = "IRID_TEST_ATOMIC_CHILD_DIR";

/// In the child: start writing `DIR/out.bin`, write half, say so, hang.
fn child_writes_forever(dir: &Path) {
    // The child takes SIGINT and SIGTERM's default action whatever the test
    // run inherited (a job a shell starts in the background without job
    // control inherits SIGINT ignored, and exec keeps that), as in a
    // terminal; the parent gives up after a minute rather than hang.
    // SAFETY: setting a disposition to SIG_DFL installs no handler.
    unsafe {
        libc::signal(libc::SIGINT, libc::SIG_DFL);
        libc::signal(libc::SIGTERM, libc::SIG_DFL);
    }
    irid::atomic::write_with(&dir.join("out.bin"), |tmp| {
        std::fs::write(tmp, vec![7u8; 1 << 16]).unwrap();
        std::fs::write(dir.join("started"), b"").unwrap();
        loop {
            std::thread::sleep(Duration::from_secs(1));
        }
    })
    .unwrap();
}

fn spawn_child(dir: &Path, named: bool) -> Child {
    let mut cmd = Command::new(std::env::current_exe().unwrap());
    cmd.args(["--exact", "interrupted_writes_leave_nothing", "--nocapture"])
        .env(CHILD_DIR, dir);
    if named {
        cmd.env(irid::atomic::NAMED_TEMPORARIES_ENV, "1");
    } else {
        cmd.env_remove(irid::atomic::NAMED_TEMPORARIES_ENV);
    }
    cmd.spawn().unwrap()
}

fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "started")
        .collect();
    names.sort();
    names
}

fn wait_for(path: &Path) {
    let start = Instant::now();
    while !path.exists() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "child never started"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// The child's exit status; a child still alive after `limit` is killed
/// and the test fails, rather than hang.
fn wait_at_most(child: &mut Child, limit: Duration) -> std::process::ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("the child outlived its signal by {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn interrupted_writes_leave_nothing() {
    if let Some(dir) = std::env::var_os(CHILD_DIR) {
        child_writes_forever(&PathBuf::from(dir));
        return;
    }
    for named in [false, true] {
        for signal in [libc::SIGINT, libc::SIGTERM, libc::SIGKILL] {
            let dir = tempfile::tempdir().unwrap();
            let mut child = spawn_child(dir.path(), named);
            wait_for(&dir.path().join("started"));
            if named {
                // The named temporary is there while the child writes.
                assert_eq!(listing(dir.path()).len(), 1, "{:?}", listing(dir.path()));
            } else {
                assert_eq!(listing(dir.path()), Vec::<String>::new());
            }
            // SAFETY: signals a child process this test started.
            unsafe { libc::kill(child.id() as i32, signal) };
            let status = wait_at_most(&mut child, Duration::from_secs(60));
            assert!(!status.success());
            let left = listing(dir.path());
            if named && signal == libc::SIGKILL {
                // Nothing could run in the child: the next write sweeps it.
                assert_eq!(left.len(), 1, "{left:?}");
                irid::atomic::write(&dir.path().join("next.bin"), b"x").unwrap();
                assert_eq!(listing(dir.path()), ["next.bin"]);
            } else {
                assert!(
                    left.is_empty(),
                    "named {named}, signal {signal}: left {left:?}"
                );
            }
        }
    }
}
