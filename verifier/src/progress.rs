//! What a long run reports while it runs, for a progress line.

use std::time::Duration;

/// Progress of a run, reported about four times a second by the explicit exploration
/// (also in `--method auto`'s explicit phase), and at every step of the symbolic method.
#[derive(Clone, Debug)]
pub enum Progress {
    /// The explicit exploration.
    Exploring {
        states: u64,
        transitions: u64,
        depth: u32,
        /// States of the level being explored, and how many of them are done.
        level_states: u64,
        level_done: u64,
        elapsed: Duration,
        store_bytes: u64,
    },
    /// The symbolic method: the property it is deciding and the step it is at (`computing
    /// invariants`, `k-induction, k = 3`, `deadlock candidate 12`, ...).
    Proving {
        property: String,
        step: String,
        solver_calls: u64,
        elapsed: Duration,
    },
}

impl Progress {
    /// Time since the method started.
    pub fn elapsed(&self) -> Duration {
        match self {
            Progress::Exploring { elapsed, .. } | Progress::Proving { elapsed, .. } => *elapsed,
        }
    }
}
