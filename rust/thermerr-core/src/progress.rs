//! Progress of a long call, for a front end to show while the call runs.
//!
//! The core never prints. A long call that takes a [`Progress`] counts its planned and finished
//! units of work (for the diagnosis: calibrations) and the stage it is in (its round); the
//! front end reads [`Progress::snapshot`] from another thread (the Python binding, every 50 ms
//! while it watches for Ctrl-C) and draws a bar. The plan can grow while the call runs (a
//! later round adds its candidates), so the total is a lower bound until the call returns.
//! Several calls may share one `Progress` (the axes of one diagnosis, in parallel): the counts
//! add up and the stage is the furthest reached.

use std::sync::atomic::{AtomicUsize, Ordering};

#[derive(Debug, Default)]
pub struct Progress {
    planned: AtomicUsize,
    done: AtomicUsize,
    stage: AtomicUsize,
}

impl Progress {
    pub fn new() -> Self {
        Progress::default()
    }

    /// `n` more units of work are planned.
    pub fn plan(&self, n: usize) {
        self.planned.fetch_add(n, Ordering::Relaxed);
    }

    /// One planned unit is finished.
    pub fn step(&self) {
        self.done.fetch_add(1, Ordering::Relaxed);
    }

    /// The call has reached stage `s` (stages only move forward).
    pub fn stage(&self, s: usize) {
        self.stage.fetch_max(s, Ordering::Relaxed);
    }

    /// (finished, planned, stage).
    pub fn snapshot(&self) -> (usize, usize, usize) {
        (
            self.done.load(Ordering::Relaxed),
            self.planned.load(Ordering::Relaxed),
            self.stage.load(Ordering::Relaxed),
        )
    }
}

/// Counts on an optional [`Progress`]: a call without one pays nothing.
pub(crate) fn plan(p: Option<&Progress>, n: usize) {
    if let Some(p) = p {
        p.plan(n);
    }
}

pub(crate) fn step(p: Option<&Progress>) {
    if let Some(p) = p {
        p.step();
    }
}

pub(crate) fn stage(p: Option<&Progress>, s: usize) {
    if let Some(p) = p {
        p.stage(s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_add_up_and_the_stage_only_moves_forward() {
        let p = Progress::new();
        plan(Some(&p), 3);
        step(Some(&p));
        stage(Some(&p), 2);
        stage(Some(&p), 1);
        plan(None, 5);
        assert_eq!(p.snapshot(), (1, 3, 2));
    }
}
