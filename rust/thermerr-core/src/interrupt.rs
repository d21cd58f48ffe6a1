//! Cooperative interruption of long calls (Ctrl-C).
//!
//! The core knows nothing of signals: a front end (the Python binding, which polls Python's
//! signal handlers while a kernel runs) calls [`request`], and every long loop of the core —
//! SMO, the swarm searches, calibration, clustering, network training, the simulation's time
//! loop — calls [`check`] often enough that the call returns [`Error::Interrupted`] well within
//! a second. One flag for the process: Ctrl-C is addressed to the process, so every running
//! kernel stops; the front end clears the flag when the interrupted call has returned.

use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::{Error, Result};

/// A stop flag; the process has one, [`REQUESTED`].
pub struct Flag(AtomicBool);

impl Flag {
    pub const fn new() -> Self {
        Flag(AtomicBool::new(false))
    }

    pub fn request(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    pub fn clear(&self) {
        self.0.store(false, Ordering::Relaxed);
    }

    pub fn requested(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// `Err(Error::Interrupted)` once a stop has been requested: a relaxed atomic load, cheap
    /// enough for every iteration of a loop.
    #[inline]
    pub fn check(&self) -> Result<()> {
        if self.requested() {
            Err(Error::Interrupted)
        } else {
            Ok(())
        }
    }
}

impl Default for Flag {
    fn default() -> Self {
        Flag::new()
    }
}

/// The process's flag, which every long loop of the core checks.
pub static REQUESTED: Flag = Flag::new();

/// Asks every running kernel to stop at its next check.
pub fn request() {
    REQUESTED.request();
}

/// Withdraws a request (once the interrupted call has returned).
pub fn clear() {
    REQUESTED.clear();
}

/// Whether a stop has been requested.
pub fn requested() -> bool {
    REQUESTED.requested()
}

/// [`Flag::check`] of the process's flag.
#[inline]
pub fn check() -> Result<()> {
    REQUESTED.check()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_request_is_seen_until_cleared() {
        // a flag of its own: other tests run in parallel in this process and check the global one
        let f = Flag::new();
        assert!(f.check().is_ok());
        f.request();
        assert!(matches!(f.check(), Err(Error::Interrupted)));
        f.clear();
        assert!(f.check().is_ok());
    }
}
