//! Symbolic verification with z3: proofs that do not enumerate the global states.
//!
//! - `encode.rs`, `term.rs`: the z3 encoding of states, guards, actions, priorities and
//!   steps, a second description of `bip-model`'s step relation (cross-checked against it
//!   by a property test);
//! - `invariants.rs`: component invariants (each component explored alone);
//! - `net.rs`, `traps.rs`, `semiflows.rs`: interaction invariants, from the Petri net the
//!   components and connectors form: traps (at least one of these locations is occupied)
//!   and semiflows (these locations' weighted occupation is constant);
//! - `deadlock.rs`: deadlock freedom as "invariants ∧ deadlock predicate is unsatisfiable",
//!   candidates examined with the step relation and confirmed by explicit search;
//! - `induction.rs`: invariants, reachability and range errors by bounded model checking
//!   and k-induction strengthened with the same invariants;
//! - `confirm.rs`: symbolic findings turned into traces with the step relation.
//!
//! Nothing here says "holds" without a proof: an unknown solver answer, a candidate that is
//! neither ruled out nor confirmed, a bound reached, all give "inconclusive".
//!
//! z3 on Debian's libz3 4.8.12 (see ARCHITECTURE.md): only `Int` and `Bool` terms, no
//! `FuncDecl::kind()`, never z3's own `timeout` (a watchdog interrupts instead, and
//! `rlimit` bounds work deterministically).

mod confirm;
mod deadlock;
mod encode;
#[cfg(test)]
mod encoding_tests;
mod induction;
mod invariants;
mod net;
mod prover;
mod semiflows;
mod solver;
mod term;
mod traps;

use std::time::Instant;

use bip_model::{PropertyKind as ModelKind, System, Trace};

use crate::error::VerifyError;
use crate::memory;
use crate::options::Options;
use crate::progress::Progress;
use crate::properties::{checked_properties, RANGE_ERRORS};
use crate::report::{
    CheckKind, Method, PropertyResult, PropertyVerdict, Report, RunStats, Stop, SymbolicStats,
};
use induction::Goal;
use prover::Prover;

/// Verifies every property of `system` symbolically. Reads `options.symbolic`, the time
/// limit and, for the explicit confirmation of deadlock candidates, the workers. Takes a
/// progress callback as every method does, and never calls it: [`Progress`] counts the
/// states of an exploration.
pub(crate) fn verify(
    system: &System,
    options: &Options,
    _progress: &(dyn Fn(&Progress) + Sync),
) -> Result<Report, VerifyError> {
    // z3's context is per thread, and deep terms recurse: one thread with a large stack
    std::thread::scope(|scope| {
        std::thread::Builder::new()
            .name("bip-symbolic".into())
            .stack_size(256 << 20)
            .spawn_scoped(scope, || run(system, options))
            .map_err(|e| VerifyError::Threads(e.to_string()))?
            .join()
            .map_err(|_| VerifyError::Internal("the symbolic verifier panicked".into()))
    })
}

/// One property's outcome.
struct Outcome {
    verdict: PropertyVerdict,
    method: Method,
    note: Option<String>,
}

impl Outcome {
    fn symbolic(verdict: PropertyVerdict, note: Option<String>) -> Outcome {
        Outcome {
            verdict,
            method: Method::Symbolic,
            note,
        }
    }

    fn unknown(reason: String) -> Outcome {
        Outcome::symbolic(PropertyVerdict::Inconclusive { reason }, None)
    }
}

fn after(trace: &Trace) -> String {
    let n = trace.steps.len();
    format!("after {n} step{}", if n == 1 { "" } else { "s" })
}

fn run(system: &System, options: &Options) -> Report {
    let started = Instant::now();
    let mut p = Prover::new(system, options.clone());
    let invariant_seconds = started.elapsed().as_secs_f64();
    let props = checked_properties(system);
    // range errors first: deadlock freedom with time steps relies on their absence
    let range = {
        let _span = tracing::info_span!("property", name = RANGE_ERRORS).entered();
        safety(&mut p, Goal::RangeError)
    };
    let range_proved = range.verdict.holds();
    let mut properties = Vec::with_capacity(props.len() + 1);
    for prop in &props {
        let _span = tracing::info_span!("property", name = %prop.name).entered();
        let t0 = Instant::now();
        let (kind, outcome) = match &prop.kind {
            ModelKind::DeadlockFree { .. } => (
                CheckKind::DeadlockFree,
                deadlock(&mut p, prop, range_proved),
            ),
            ModelKind::Invariant(e) => (
                CheckKind::Invariant,
                safety(&mut p, Goal::Invariant(e, &prop.name)),
            ),
            ModelKind::Reachable(e) => (
                CheckKind::Reachable,
                safety(&mut p, Goal::Reach(e, &prop.name)),
            ),
        };
        tracing::info!(seconds = t0.elapsed().as_secs_f64(), verdict = ?outcome.verdict, "decided");
        properties.push(PropertyResult {
            name: prop.name.clone(),
            kind,
            expr: prop.text.clone(),
            verdict: outcome.verdict,
            method: outcome.method,
            note: outcome.note,
        });
    }
    properties.push(PropertyResult {
        name: RANGE_ERRORS.into(),
        kind: CheckKind::RangeErrors,
        expr: String::new(),
        verdict: range.verdict,
        method: range.method,
        note: range.note,
    });
    let seconds = started.elapsed().as_secs_f64();
    let stopped = p.budget.expired().then(|| Stop::Timeout {
        seconds: options.timeout.map_or(0.0, |t| t.as_secs_f64()),
    });
    Report {
        model: system.name.clone(),
        method: Method::Symbolic,
        properties,
        stats: RunStats {
            seconds,
            peak_memory_bytes: memory::peak_resident_bytes(),
            jobs: 1,
            ..RunStats::default()
        },
        stopped,
        symbolic: Some(SymbolicStats {
            components: system.components.len(),
            approximate_components: p.ci.approximate,
            places: p.net.places(),
            net_groups: p.net.groups.len(),
            semiflows: p.semiflows.len(),
            traps: p.traps.len(),
            solver_calls: p.calls.count,
            solver_seconds: p.calls.time.as_secs_f64(),
            invariant_seconds,
            seconds,
        }),
    }
}

fn deadlock(p: &mut Prover<'_>, prop: &bip_model::Property, range_proved: bool) -> Outcome {
    use deadlock::Finding;
    match deadlock::deadlock_free(p, prop, range_proved) {
        Finding::Proved { candidates } => Outcome::symbolic(
            PropertyVerdict::Holds { witness: None },
            Some(if candidates == 0 {
                "invariants ∧ deadlock predicate unsatisfiable".into()
            } else {
                format!("invariants ∧ deadlock predicate unsatisfiable after {candidates} candidates ruled out")
            }),
        ),
        Finding::Deadlock(trace) => Outcome::symbolic(
            PropertyVerdict::Fails {
                reason: format!("deadlock {} (confirmed by explicit search)", after(&trace)),
                trace: Some(trace),
            },
            None,
        ),
        Finding::Explicit(verdict, states) => Outcome {
            note: Some(if verdict.holds() {
                format!("a candidate could not be ruled out symbolically; all {states} reachable states explored")
            } else {
                "found by the bounded explicit search that confirms candidates".into()
            }),
            verdict,
            method: Method::Explicit,
        },
        Finding::Possible(state) => Outcome::unknown(format!(
            "possible deadlock, not confirmed: a state satisfying every invariant found has no progress step: {}",
            p.describe(&state)
        )),
        Finding::Unknown(why) => Outcome::unknown(why),
    }
}

fn safety(p: &mut Prover<'_>, goal: Goal<'_>) -> Outcome {
    use induction::Finding;
    let reach = matches!(goal, Goal::Reach(..));
    match induction::prove(p, goal) {
        Finding::Holds { how } if reach => Outcome::symbolic(
            PropertyVerdict::Fails {
                reason: format!("no reachable state satisfies it (proved: {how})"),
                trace: None,
            },
            Some(how),
        ),
        Finding::Holds { how } => {
            Outcome::symbolic(PropertyVerdict::Holds { witness: None }, Some(how))
        }
        Finding::Bad(trace) => {
            let verdict = match &trace.verdict {
                bip_model::Verdict::Witness(_) => PropertyVerdict::Holds {
                    witness: Some(trace),
                },
                bip_model::Verdict::Violation(_) => PropertyVerdict::Fails {
                    reason: format!("violated {}", after(&trace)),
                    trace: Some(trace),
                },
                bip_model::Verdict::RangeError(m) => PropertyVerdict::Fails {
                    reason: format!("range error: {m} {}", after(&trace)),
                    trace: Some(trace),
                },
                _ => PropertyVerdict::Inconclusive {
                    reason: "internal error: unexpected trace".into(),
                },
            };
            Outcome::symbolic(verdict, Some("bounded model checking".into()))
        }
        Finding::Unknown(why) => Outcome::unknown(why),
    }
}
