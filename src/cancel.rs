//! Stopping a long computation from another thread.
//!
//! A caller that may need to abandon a call (the Python package, on
//! Ctrl-C) passes a [`Cancel`] to the `_cancellable` form of the call and
//! sets it from another thread; the computation looks at it between blocks
//! of a few milliseconds of work and returns [`Error::Cancelled`]. A look
//! is one relaxed atomic load per block, nothing beside the block's work.
//! The plain forms pass [`Cancel::never`].

use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::{Error, Result};

/// Set once the call it was passed to should stop.
#[derive(Debug, Default)]
pub struct Cancel(AtomicBool);

/// The flag of every call that cannot be cancelled.
static NEVER: Cancel = Cancel::new();

impl Cancel {
    /// A flag not set.
    pub const fn new() -> Cancel {
        Cancel(AtomicBool::new(false))
    }

    /// A flag nobody sets: the plain, uncancellable forms pass it.
    pub fn never() -> &'static Cancel {
        &NEVER
    }

    /// Asks the calls holding this flag to stop at their next look.
    pub fn set(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`Self::set`] has been called.
    pub fn is_set(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// [`Error::Cancelled`] once set: a computation's look between blocks.
    pub fn check(&self) -> Result<()> {
        if self.is_set() {
            Err(Error::Cancelled)
        } else {
            Ok(())
        }
    }
}
