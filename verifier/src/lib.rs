//! `bip-verifier`: verification of bip models.
//!
//! - [`explore::verify`]: explicit-state verification, breadth-first and parallel, with
//!   shortest counterexamples (`explore.rs`, over the visited set of `visited.rs`);
//! - [`report`]: the verdicts and statistics any method produces;
//! - [`promela`]: the same system as a Promela model, to cross-check with SPIN.
//!
//! Every method uses `bip-model`'s step relation and deadlock definition; none has a
//! notion of its own of "enabled" or "deadlock".

pub mod explore;
pub mod memory;
pub mod promela;
pub mod report;
pub mod visited;

pub use explore::{verify, Options, Progress, VerifyError, RANGE_ERRORS};
pub use report::{Method, Outcome, PropertyKind, PropertyResult, Report, Stats, Stop, Verdict};
