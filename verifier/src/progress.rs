//! What a long run reports while it runs, for a progress line.

use std::time::Duration;

/// Progress of a run. The explicit exploration reports it about four times a second (also
/// in `--method auto`'s explicit phase); the symbolic method reports none.
#[derive(Clone, Debug)]
pub struct Progress {
    pub states: u64,
    pub transitions: u64,
    pub depth: u32,
    /// States of the level being explored, and how many of them are done.
    pub level_states: u64,
    pub level_done: u64,
    pub elapsed: Duration,
    pub store_bytes: u64,
}
