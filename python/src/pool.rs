//! The thread pool every computation of the package runs on, one per
//! process.
//!
//! `fork()` copies only the thread that calls it, so in a forked child the
//! worker threads of any pool the parent started do not exist: work queued
//! on them waits forever. rayon's global pool cannot be rebuilt, so the
//! package never uses it. It owns a pool tagged with the id of the process
//! that built it, and a process whose id differs (a forked child) builds its
//! own. Inside [`compute`] the library's parallel code (the bake's sweep,
//! validation, anything using rayon's `par_iter`) runs on the current pool,
//! which is this one; work too small to split runs on the calling thread
//! without touching rayon.

use std::ptr::null_mut;
use std::sync::atomic::{AtomicPtr, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Duration;

use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use rayon::{ThreadPool, ThreadPoolBuilder};

/// A pool and the process it belongs to.
struct ProcessPool {
    pid: u32,
    pool: ThreadPool,
}

/// The current process's pool, leaked so that it can be handed out as
/// `'static`. No lock guards it: a lock another thread held at the moment
/// of a fork would stay locked in the child.
static POOL: AtomicPtr<ProcessPool> = AtomicPtr::new(null_mut());

/// This process's pool, built on first use (`RAYON_NUM_THREADS` threads,
/// else one per core). A pool inherited from the parent of a fork is left
/// untouched and leaked: its threads are gone, and dropping it would wake
/// them through locks that may have been held when the process forked.
fn process_pool() -> PyResult<&'static ThreadPool> {
    let pid = std::process::id();
    loop {
        let current = POOL.load(Ordering::Acquire);
        // SAFETY: POOL only ever holds null or a pointer from Box::into_raw
        // below that is never freed.
        if let Some(p) = unsafe { current.as_ref() } {
            if p.pid == pid {
                return Ok(&p.pool);
            }
        }
        let pool = ThreadPoolBuilder::new()
            .thread_name(|i| format!("irid-{i}"))
            .build()
            .map_err(|e| PyOSError::new_err(format!("thread pool: cannot start threads: {e}")))?;
        let fresh = Box::into_raw(Box::new(ProcessPool { pid, pool }));
        match POOL.compare_exchange(current, fresh, Ordering::AcqRel, Ordering::Acquire) {
            // SAFETY: just published, never freed.
            Ok(_) => return Ok(unsafe { &(*fresh).pool }),
            // Another thread of this process installed its pool first: ours
            // never ran anything and can go; use the one installed.
            // SAFETY: `fresh` came from Box::into_raw and was not published.
            Err(_) => drop(unsafe { Box::from_raw(fresh) }),
        }
    }
}

/// Runs `work` with the GIL released: on this process's pool when
/// `parallel`, else on the calling thread, which saves the handoff to a
/// worker and back (tens of microseconds on a busy machine, more than a
/// small call's whole work). `work` may use rayon only when `parallel`: on
/// the calling thread rayon's parallel iterators would split onto its
/// global pool, whose threads a forked child lacks. Every entry point's
/// computation goes through here or [`compute_interruptible`]; a parallel
/// one is interrupted as that describes, though only once `work` is done.
pub fn compute<T: Send>(
    py: Python<'_>,
    parallel: bool,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    if !parallel {
        return Ok(py.allow_threads(work));
    }
    compute_interruptible(py, |_| work())
}

/// How often the calling thread looks for signals while the pool works.
const SIGNAL_POLL: Duration = Duration::from_millis(20);

/// Set when the call that passed it is interrupted: its work stops at the
/// next block that looks and its partial result is thrown away.
pub use irid::cancel::Cancel;

/// [`compute_interruptible`] when `on_pool` (work long enough to be worth
/// the handoff), else `work` on the calling thread with a flag never set:
/// a call that short ends before a signal could be noticed anyway.
pub fn compute_cancellable<T: Send>(
    py: Python<'_>,
    on_pool: bool,
    work: impl FnOnce(&Cancel) -> T + Send,
) -> PyResult<T> {
    if on_pool {
        compute_interruptible(py, work)
    } else {
        compute(py, false, || work(Cancel::never()))
    }
}

/// Runs `work` on this process's pool with the GIL released, while the
/// calling thread runs Python's signal handlers every [`SIGNAL_POLL`]: a
/// handler that raises (Ctrl-C's `KeyboardInterrupt`) sets the [`Cancel`]
/// flag `work` polls between its blocks, and once `work` returns the call
/// raises that exception, its result discarded. Without this a signal
/// waits for the whole call, since Python runs handlers only between
/// bytecodes of the main thread.
pub fn compute_interruptible<T: Send>(
    py: Python<'_>,
    work: impl FnOnce(&Cancel) -> T + Send,
) -> PyResult<T> {
    let pool = process_pool()?;
    let cancel = Cancel::default();
    let (result, interrupt) = py.allow_threads(|| {
        pool.in_place_scope(|scope| {
            let (done, finished) = mpsc::channel();
            let cancel = &cancel;
            scope.spawn(move |_| {
                // A send fails only once the receiver is gone, which it
                // is not before this job ends (the scope waits for it).
                let _ = done.send(work(cancel));
            });
            let mut interrupt = None;
            loop {
                match finished.recv_timeout(SIGNAL_POLL) {
                    Ok(result) => return (Some(result), interrupt),
                    // The job panicked: the scope passes the panic on.
                    Err(RecvTimeoutError::Disconnected) => return (None, interrupt),
                    Err(RecvTimeoutError::Timeout) if interrupt.is_none() => {
                        interrupt = Python::with_gil(|py| py.check_signals()).err();
                        if interrupt.is_some() {
                            cancel.set();
                        }
                    }
                    Err(RecvTimeoutError::Timeout) => {}
                }
            }
        })
    });
    match (interrupt, result) {
        (Some(e), _) => Err(e),
        (None, Some(result)) => Ok(result),
        (None, None) => unreachable!("a job that panicked ends the scope with its panic"),
    }
}
