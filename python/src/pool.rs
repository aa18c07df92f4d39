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
/// computation goes through here.
pub fn compute<T: Send>(
    py: Python<'_>,
    parallel: bool,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    if !parallel {
        return Ok(py.allow_threads(work));
    }
    let pool = process_pool()?;
    Ok(py.allow_threads(|| pool.install(work)))
}
