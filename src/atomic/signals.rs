//! SIGINT and SIGTERM: outside a commit they remove the named temporaries
//! and end the process as they would have; during a commit they are held
//! back until the commit has finished or been undone.

use std::ffi::CString;
use std::os::unix::ffi::OsStrExt;
use std::path::Path;
use std::sync::atomic::{AtomicI32, AtomicPtr, AtomicUsize, Ordering};

/// Named temporaries, and folders a set made, that a SIGINT or SIGTERM
/// handler removes (a folder only once empty). The paths
/// are leaked C strings: the handler may read one at any moment, so they
/// are never freed (a hundred bytes per named write).
static PENDING: [AtomicPtr<libc::c_char>; 64] =
    [const { AtomicPtr::new(std::ptr::null_mut()) }; 64];

/// Commits under way; while there are any, the handler only notes its
/// signal in [`HELD`].
static COMMITTING: AtomicUsize = AtomicUsize::new(0);
/// A signal that arrived during a commit (0: none).
static HELD: AtomicI32 = AtomicI32::new(0);

/// The dispositions SIGINT and SIGTERM had before ours, restored and
/// re-raised once the temporaries are gone.
struct Previous([libc::sigaction; 2]);
// SAFETY: written once before the handler is installed, then only read.
unsafe impl Sync for Previous {}
// SAFETY: as for Sync: the saved dispositions are plain data, never mutated after the first write.
unsafe impl Send for Previous {}
static PREVIOUS: std::sync::OnceLock<Previous> = std::sync::OnceLock::new();
const SIGNALS: [libc::c_int; 2] = [libc::SIGINT, libc::SIGTERM];

extern "C" fn on_signal(signal: libc::c_int) {
    if COMMITTING.load(Ordering::SeqCst) > 0 {
        HELD.store(signal, Ordering::SeqCst);
        return;
    }
    remove_pending_and_reraise(signal);
}

/// Unlinks every registered temporary, then removes every registered
/// folder that is empty, restores the disposition the signal had before
/// ours and raises it again (by default: the process ends).
/// Async-signal-safe: atomics, unlink, rmdir, sigaction and raise only.
fn remove_pending_and_reraise(signal: libc::c_int) {
    for remove in [libc::unlink, libc::rmdir] {
        for slot in &PENDING {
            let p = slot.load(Ordering::SeqCst);
            if !p.is_null() {
                // SAFETY: p is a leaked, NUL-terminated path; unlink and
                // rmdir are async-signal-safe, and rmdir removes only an
                // empty folder (unlink, only a file).
                unsafe { remove(p) };
            }
        }
    }
    if let (Some(previous), Some(k)) = (PREVIOUS.get(), SIGNALS.iter().position(|&s| s == signal)) {
        // SAFETY: restores the disposition saved at installation, then
        // delivers the signal to it.
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
        // A signal the process ignores stays ignored (a job started in the
        // background by a shell without job control ignores SIGINT).
        unsafe {
            let mut old: [libc::sigaction; 2] = std::mem::zeroed();
            for (k, &signal) in SIGNALS.iter().enumerate() {
                let mut action: libc::sigaction = std::mem::zeroed();
                action.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as usize;
                libc::sigemptyset(&mut action.sa_mask);
                libc::sigaction(signal, &action, &mut old[k]);
                if old[k].sa_sigaction == libc::SIG_IGN {
                    libc::sigaction(signal, &old[k], std::ptr::null_mut());
                }
            }
            Previous(old)
        }
    });
}

/// A named temporary, or a folder a set made, registered for removal on
/// SIGINT and SIGTERM while this lives (if a slot is free; otherwise the next write's sweep
/// removes it should the process be killed).
#[derive(Debug)]
pub(super) struct Registered(Option<usize>);

impl Registered {
    pub fn new(path: &Path) -> Registered {
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

/// A commit under way: SIGINT and SIGTERM are held back until it drops,
/// and then delivered.
pub(super) struct Committing;

impl Committing {
    pub fn begin() -> Committing {
        install_handlers();
        COMMITTING.fetch_add(1, Ordering::SeqCst);
        Committing
    }

    /// The signal held back so far, if any.
    pub fn interrupted(&self) -> Option<libc::c_int> {
        Some(HELD.load(Ordering::SeqCst)).filter(|&s| s != 0)
    }
}

impl Drop for Committing {
    fn drop(&mut self) {
        if COMMITTING.fetch_sub(1, Ordering::SeqCst) == 1 {
            let held = HELD.swap(0, Ordering::SeqCst);
            if held != 0 {
                remove_pending_and_reraise(held);
            }
        }
    }
}
