//! `bip-verifier`: verification of bip models.
//!
//! [`verify`] is the one entry point, for every [`Method`]:
//! - explicit-state verification, breadth-first and parallel, with shortest
//!   counterexamples (`explore/`, over the visited set of `visited.rs`);
//! - symbolic proofs with z3 (compositional deadlock freedom, k-induction, bounded model
//!   checking), with candidates confirmed explicitly (`symbolic/`);
//! - auto: explicit within a budget, symbolic for what it leaves open (`auto.rs`).
//!
//! Every method fills the same [`Report`] (`report.rs`). [`to_promela`] writes the same
//! system as a Promela model, to cross-check with SPIN (`promela.rs`).
//!
//! Every method uses `bip-model`'s step relation and deadlock definition; none has a
//! notion of its own of "enabled" or "deadlock".

mod auto;
mod error;
mod explore;
mod memory;
mod options;
mod progress;
mod promela;
mod properties;
mod report;
mod schedulability;
mod symbolic;
mod time_stops;
mod visited;
mod watch;

use bip_model::System;

pub use error::VerifyError;
pub use memory::{
    allocation_may_fail, default_limit as default_memory_limit, parse_size, resident_bytes,
};
pub use options::{Options, SymbolicOptions};
pub use progress::Progress;
pub use promela::{to_promela, ExportError};
pub use properties::{RANGE_ERRORS, TIME_PROGRESS};
pub use report::{
    human_bytes, CheckKind, Method, PropertyResult, PropertyVerdict, Report, RunStats, Stop,
    SymbolicStats, VerifyOutcome,
};
pub use schedulability::{
    has_time_budgets, schedulability, DemandChoice, DemandMethod, LayerTask, Schedulability,
    TaskKind, SCHEDULABLE,
};

/// Verifies every property of `system` (deadlock freedom if it declares none, range
/// errors always, and schedulability when it has time budgets) with
/// `method`, within the limits of `options`.
///
/// `progress` is called from time to time during long runs, from any thread.
pub fn verify(
    system: &System,
    method: Method,
    options: &Options,
    progress: &(dyn Fn(&Progress) + Sync),
) -> Result<Report, VerifyError> {
    let started = std::time::Instant::now();
    let mut report = match method {
        Method::Explicit => explore::verify(system, options, progress),
        Method::Symbolic => symbolic::verify(system, options, progress),
        Method::Auto => auto::verify(system, options, progress),
    }?;
    time_stops::qualify(system, &mut report.properties);
    report
        .properties
        .extend(schedulability::as_property(system, options, method));
    report.seconds = started.elapsed().as_secs_f64();
    report.peak_memory_bytes = memory::peak_resident_bytes();
    Ok(report)
}
