//! How to run a verification. One set of options serves every method; each method reads
//! the fields that apply to it, so that `--method auto` hands the same limits to both.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Duration;

/// How to run, whatever the method.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Worker threads (of the exploration, and of the symbolic method's explicit
    /// confirmation); 0 for one per core.
    pub jobs: usize,
    /// Explicit method: stop (inconclusive) once this many states are stored and more
    /// remain to explore.
    pub max_states: Option<u64>,
    /// Stop (inconclusive) before the process would use more memory (resident, z3's
    /// included); `None` takes 3/4 of the memory available when the run starts.
    pub max_memory: Option<u64>,
    /// Stop (inconclusive) after this long.
    pub timeout: Option<Duration>,
    /// Stop (inconclusive, "interrupted") once this flag is raised, as by Ctrl-C. Every
    /// method polls it, inside its batches and solver calls too.
    pub interrupt: Option<Arc<AtomicBool>>,
    /// Explicit method: stop as soon as one property fails.
    pub stop_at_first: bool,
    /// Explicit method: bound on the states the deadlock check explores by time steps
    /// alone from one state (0: `bip-model`'s default). Past it, the state's liveness is
    /// unknown and `DeadlockFree` cannot hold.
    pub liveness_bound: usize,
    /// What only the symbolic method reads.
    pub symbolic: SymbolicOptions,
}

/// The symbolic method's own settings.
#[derive(Clone, Debug)]
pub struct SymbolicOptions {
    /// Wall-clock limit of one solver call.
    pub solver_timeout: Option<Duration>,
    /// z3's deterministic resource limit per solver call (for reproducible runs).
    pub rlimit: Option<u32>,
    /// Deepest bounded model check, and largest k of k-induction.
    pub max_depth: u32,
    /// States the explicit confirmation of a candidate deadlock may explore (breadth-first,
    /// then steps of the greedy search); 0 turns confirmation off.
    pub confirm_states: u64,
    /// Memory the bounded breadth-first confirmation may use.
    pub confirm_memory: u64,
}

impl Default for SymbolicOptions {
    fn default() -> Self {
        SymbolicOptions {
            solver_timeout: Some(Duration::from_secs(120)),
            rlimit: None,
            max_depth: 20,
            confirm_states: 200_000,
            confirm_memory: 512 << 20,
        }
    }
}
