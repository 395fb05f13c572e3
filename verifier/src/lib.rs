//! `bip-verifier`: verification of bip models.
//!
//! - [`explore::verify`]: explicit-state verification, breadth-first and parallel, with
//!   shortest counterexamples (`explore.rs`, over the visited set of `visited.rs`);
//! - [`symbolic::verify`]: symbolic proofs with z3 (compositional deadlock freedom,
//!   k-induction, bounded model checking), with candidates confirmed explicitly;
//! - [`report`]: the verdicts and statistics any method produces;
//! - [`promela`]: the same system as a Promela model, to cross-check with SPIN.
//!
//! Every method uses `bip-model`'s step relation and deadlock definition; none has a
//! notion of its own of "enabled" or "deadlock".

pub mod auto;
pub mod explore;
pub mod memory;
pub mod promela;
pub mod report;
pub mod symbolic;
pub mod visited;

pub use auto::verify_auto;
pub use explore::{checked_properties, verify, Options, Progress, VerifyError, RANGE_ERRORS};
pub use report::{
    Method, Outcome, PropertyKind, PropertyResult, Report, Stats, Stop, SymbolicStats, Verdict,
};
pub use symbolic::SymbolicOptions;
