//! Symbolic verification with z3: proofs that do not enumerate the global states.
//!
//! - `encode/`, `term/`: the z3 encoding of states, guards, actions, priorities and
//!   steps, a second description of `bip-model`'s step relation (cross-checked against it
//!   by a property test);
//! - `invariants.rs`: component invariants (each component explored alone);
//! - `net.rs`, `traps.rs`, `semiflows.rs`: interaction invariants, from the Petri net the
//!   components and connectors form: traps (at least one of these locations is occupied)
//!   and semiflows (these locations' weighted occupation is constant);
//! - `deadlock.rs`: deadlock freedom as "invariants ∧ deadlock predicate is unsatisfiable",
//!   candidates examined with the step relation and confirmed by explicit search;
//! - `kinduction.rs`: bounded model checking and k-induction side by side, on an
//!   unrolling of the step relation that `induction.rs` and `response.rs` give;
//! - `induction.rs`: invariants, reachability and range errors by bounded model checking
//!   and k-induction strengthened with the same invariants;
//! - `response.rs`: bounded response by the same two methods on the product with the
//!   tick-counting observer (unbounded response is left inconclusive);
//! - `progress.rs`: time progress by a sufficient condition (a tick in every state
//!   satisfying the invariants, or found from it);
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
mod kinduction;
mod net;
mod progress;
mod prover;
mod response;
mod semiflows;
mod solver;
mod term;
mod traps;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Arc;

use bip_model::{PropertyKind as ModelKind, System, Trace};

use crate::error::VerifyError;
use crate::memory;
use crate::options::Options;
use crate::progress::Progress;
use crate::properties::{
    check_kind, checked_properties, checks_time_progress, error_step, RANGE_ERRORS, TIME_PROGRESS,
};
use crate::report::{
    CheckKind, Method, PropertyResult, PropertyVerdict, Report, RunStats, SymbolicStats,
};
use crate::watch::Watch;
use induction::Goal;
use prover::Prover;

/// Verifies every property of `system` symbolically. Reads `options.symbolic`, the limits
/// of time and memory, the interrupt flag and, for the explicit confirmation of deadlock
/// candidates, the workers. Reports progress at every step of a proof.
pub(crate) fn verify(
    system: &System,
    options: &Options,
    progress: &(dyn Fn(&Progress) + Sync),
) -> Result<Report, VerifyError> {
    let watch = Arc::new(Watch::new(
        options,
        options.max_memory.or_else(memory::default_limit),
    ));
    let z3_mib = limit_z3_memory(&watch);
    // z3's context is per thread, and deep terms recurse: one thread with a large stack
    std::thread::scope(|scope| {
        std::thread::Builder::new()
            .name(THREAD.into())
            .stack_size(256 << 20)
            .spawn_scoped(scope, || {
                quiet_panics();
                // z3 fails by panics of the z3 crate (creating the context too, when
                // memory is short): each is caught and makes the rest undecided
                let ctx = catch_unwind(z3::Context::thread_local).ok();
                let Some(ctx) = ctx else {
                    let why = match z3_mib {
                        Some(mib) => {
                            out_of_memory(&watch);
                            format!(
                                "z3 could not start in the {mib} MiB the memory limit leaves it"
                            )
                        }
                        None => "z3 could not start".into(),
                    };
                    return undecided(system, &why, &watch);
                };
                let handle = ctx.handle();
                watch.around(
                    || handle.interrupt(),
                    || run(system, options, watch.clone(), progress, &ctx),
                )
            })
            .map_err(|e| VerifyError::Threads(e.to_string()))?
            .join()
            .map_err(|_| VerifyError::Internal("the symbolic verifier panicked".into()))
    })
}

/// Gives z3 what remains of the memory limit (in MiB, returned), so that it fails (and the
/// property is inconclusive) rather than the process. z3 counts its own allocations, for
/// the whole process; the watchdog watches the rest.
fn limit_z3_memory(watch: &Watch) -> Option<u64> {
    let limit = watch.max_memory()?;
    let left = limit.saturating_sub(memory::resident_bytes().unwrap_or(0));
    let mib = (left >> 20).max(1);
    z3::set_global_param("memory_max_size", &mib.to_string());
    Some(mib)
}

/// z3 ran out of the memory it was given: the run has reached its memory limit.
fn out_of_memory(watch: &Watch) {
    if let Some(limit) = watch.max_memory() {
        watch.raise(crate::report::Stop::MaxMemory { limit });
    }
}

/// Keeps the panics of the symbolic thread off stderr (they are z3's failures, reported as
/// inconclusive verdicts with their reason); any other thread's go to the previous hook.
fn quiet_panics() {
    static INSTALL: std::sync::Once = std::sync::Once::new();
    INSTALL.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if std::thread::current().name() != Some(THREAD) {
                previous(info);
            }
        }));
    });
}

/// The name of the thread that calls z3.
const THREAD: &str = "bip-symbolic";

/// Why a z3 call failed (the z3 crate panics on a failed call), or why the run stopped.
fn failure(watch: &Watch, ctx: Option<&z3::Context>) -> String {
    if let Some(stop) = watch.look() {
        return stop.to_string();
    }
    let Some(ctx) = ctx else {
        return "z3 failed to start (out of memory?)".into();
    };
    // SAFETY: the context is this thread's, alive while `ctx` is; z3 returns a static
    // string for an error code, or null.
    let message = unsafe {
        let raw = ctx.get_z3_context();
        let code = z3_sys::Z3_get_error_code(raw);
        if code == z3_sys::ErrorCode::Ok {
            None
        } else {
            z3_sys::Z3_get_error_msg(raw, code)
                .as_ref()
                .map(|m| std::ffi::CStr::from_ptr(m).to_string_lossy().into_owned())
        }
    };
    match message {
        Some(m) if m.contains("memory") || m.contains("memout") => {
            out_of_memory(watch);
            "z3 ran out of the memory the memory limit leaves it".into()
        }
        Some(m) => format!("z3 failed ({m})"),
        None => "the symbolic verifier failed (an internal error)".into(),
    }
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

fn run(
    system: &System,
    options: &Options,
    watch: Arc<Watch>,
    progress: &(dyn Fn(&Progress) + Sync),
    ctx: &z3::Context,
) -> Report {
    let started = watch.started();
    let props = checked_properties(system);
    let mut p = match catch_unwind(AssertUnwindSafe(|| {
        Prover::new(system, options.clone(), watch.clone(), progress)
    })) {
        Ok(Ok(p)) => p,
        Ok(Err(stop)) => return undecided(system, &stop.to_string(), &watch),
        Err(_) => {
            let why = failure(&watch, Some(ctx));
            return undecided(system, &why, &watch);
        }
    };
    let invariant_seconds = started.elapsed().as_secs_f64();
    let mut failed: Option<String> = None;
    let decide = &mut |p: &mut Prover<'_>, name: &str, f: &dyn Fn(&mut Prover<'_>) -> Outcome| {
        decide(p, &mut failed, ctx, name, f)
    };
    // range errors first: deadlock freedom with time steps relies on their absence
    let range = decide(&mut p, RANGE_ERRORS, &|p| safety(p, Goal::RangeError));
    let range_proved = range.verdict.holds();
    // before the properties: a bounded response proved on the runs where time diverges
    // says nothing where time stops
    let progress = checks_time_progress(system)
        .then(|| decide(&mut p, TIME_PROGRESS, &|p| time_progress(p, range_proved)));
    let time_diverges = progress.as_ref().is_none_or(|o| o.verdict.holds());
    let mut properties = Vec::with_capacity(props.len() + 2);
    for prop in &props {
        let (kind, outcome) = match &prop.kind {
            ModelKind::DeadlockFree { .. } => (
                CheckKind::DeadlockFree,
                decide(&mut p, &prop.name, &|p| deadlock(p, prop, range_proved)),
            ),
            ModelKind::Invariant(e) => (
                CheckKind::Invariant,
                decide(&mut p, &prop.name, &|p| {
                    safety(p, Goal::Invariant(e, &prop.name))
                }),
            ),
            ModelKind::Reachable(e) => (
                CheckKind::Reachable,
                decide(&mut p, &prop.name, &|p| {
                    safety(p, Goal::Reach(e, &prop.name))
                }),
            ),
            ModelKind::Response { within: Some(_), .. } => (
                check_kind(&prop.kind),
                match decide(&mut p, &prop.name, &|p| bounded_response(p, prop)) {
                    o if o.verdict.holds() && !time_diverges => Outcome::unknown(format!(
                        "no run on which time diverges misses the bound ({}), but time progress is not proved: where time stops, the response may never come",
                        o.note.as_deref().unwrap_or("proved")
                    )),
                    o => o,
                },
            ),
            // no proof method for them yet: never a verdict without one
            ModelKind::Response { within: None, .. } => (
                check_kind(&prop.kind),
                Outcome::unknown(
                    "the symbolic method decides bounded response only (`within`); unbounded ones (LeadsTo, Replies without a bound, Terminates) need a liveness proof it does not have: `--method explicit` decides them"
                        .into(),
                ),
            ),
        };
        properties.push(PropertyResult {
            name: prop.name.clone(),
            kind,
            expr: prop.text.clone(),
            error_step: outcome.verdict.trace().and_then(|t| error_step(system, t)),
            verdict: outcome.verdict,
            method: outcome.method,
            note: outcome.note,
            worst_us: None,
        });
    }
    if let Some(outcome) = progress {
        properties.push(PropertyResult {
            name: TIME_PROGRESS.into(),
            kind: CheckKind::TimeProgress,
            expr: String::new(),
            error_step: None,
            verdict: outcome.verdict,
            method: outcome.method,
            note: outcome.note,
            worst_us: None,
        });
    }
    properties.push(PropertyResult {
        name: RANGE_ERRORS.into(),
        kind: CheckKind::RangeErrors,
        expr: String::new(),
        error_step: range.verdict.trace().and_then(|t| error_step(system, t)),
        verdict: range.verdict,
        method: range.method,
        note: range.note,
        worst_us: None,
    });
    let seconds = started.elapsed().as_secs_f64();
    Report {
        model: system.name.clone(),
        method: Method::Symbolic,
        properties,
        stats: RunStats::default(),
        stopped: watch.stopped().cloned(),
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
        seconds,
        peak_memory_bytes: None,
    }
}

/// Decides one property with `f`, unless the run has stopped or z3 has failed before (its
/// context cannot be trusted then: the rest is undecided).
fn decide(
    p: &mut Prover<'_>,
    failed: &mut Option<String>,
    ctx: &z3::Context,
    name: &str,
    f: &dyn Fn(&mut Prover<'_>) -> Outcome,
) -> Outcome {
    if let Some(why) = failed {
        return Outcome::unknown(why.clone());
    }
    if let Some(stop) = p.budget.watch.look() {
        return Outcome::unknown(stop.to_string());
    }
    let _span = tracing::info_span!("property", name).entered();
    p.start(name);
    let t0 = std::time::Instant::now();
    let outcome = match catch_unwind(AssertUnwindSafe(|| f(p))) {
        Ok(o) => o,
        Err(_) => {
            let why = failure(&p.budget.watch, Some(ctx));
            *failed = Some(why.clone());
            Outcome::unknown(why)
        }
    };
    tracing::info!(seconds = t0.elapsed().as_secs_f64(), verdict = ?outcome.verdict, "decided");
    outcome
}

/// The report of a run that could not start its proofs: every property undecided.
fn undecided(system: &System, why: &str, watch: &Watch) -> Report {
    let seconds = watch.started().elapsed().as_secs_f64();
    let mut properties: Vec<PropertyResult> = checked_properties(system)
        .iter()
        .map(|prop| PropertyResult {
            name: prop.name.clone(),
            kind: check_kind(&prop.kind),
            expr: prop.text.clone(),
            verdict: PropertyVerdict::Inconclusive { reason: why.into() },
            method: Method::Symbolic,
            note: None,
            error_step: None,
            worst_us: None,
        })
        .collect();
    if checks_time_progress(system) {
        properties.push(PropertyResult {
            name: TIME_PROGRESS.into(),
            kind: CheckKind::TimeProgress,
            expr: String::new(),
            verdict: PropertyVerdict::Inconclusive { reason: why.into() },
            method: Method::Symbolic,
            note: None,
            error_step: None,
            worst_us: None,
        });
    }
    properties.push(PropertyResult {
        name: RANGE_ERRORS.into(),
        kind: CheckKind::RangeErrors,
        expr: String::new(),
        verdict: PropertyVerdict::Inconclusive { reason: why.into() },
        method: Method::Symbolic,
        note: None,
        error_step: None,
        worst_us: None,
    });
    Report {
        model: system.name.clone(),
        method: Method::Symbolic,
        properties,
        stats: RunStats::default(),
        stopped: watch.stopped().cloned(),
        symbolic: Some(SymbolicStats {
            components: system.components.len(),
            seconds,
            ..SymbolicStats::default()
        }),
        seconds,
        peak_memory_bytes: None,
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
                format!(
                    "invariants ∧ deadlock predicate unsatisfiable after {candidates} candidate{} ruled out",
                    if candidates == 1 { "" } else { "s" }
                )
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

fn time_progress(p: &mut Prover<'_>, range_proved: bool) -> Outcome {
    use progress::Finding;
    match progress::time_progress(p, range_proved) {
        // `progress::time_progress` follows cleared candidates with the bound on paths
        // without a tick, so a proof here has every state with a tick enabled
        Finding::Proved { .. } => Outcome::symbolic(
            PropertyVerdict::Holds { witness: None },
            Some("invariants ∧ no tick enabled unsatisfiable".into()),
        ),
        Finding::Bounded { steps } => Outcome::symbolic(
            PropertyVerdict::Holds { witness: None },
            Some(format!(
                "invariants ∧ {steps} steps without a tick unsatisfiable, and no state without a step"
            )),
        ),
        Finding::Candidate(state) => Outcome::unknown(format!(
            "the symbolic method proves time progress only when every state satisfying the invariants reaches a tick within a small search or a bounded number of steps, and this one does not: {} (`--method explicit` decides it)",
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

fn bounded_response(p: &mut Prover<'_>, prop: &bip_model::Property) -> Outcome {
    let Some(spec) = prop.kind.response_spec() else {
        return Outcome::unknown("internal error: not a response property".into());
    };
    match response::bounded(p, spec, &prop.name) {
        response::Finding::Holds { how } => {
            Outcome::symbolic(PropertyVerdict::Holds { witness: None }, Some(how))
        }
        response::Finding::Bad((trace, reason)) => Outcome::symbolic(
            PropertyVerdict::Fails {
                reason,
                trace: Some(trace),
            },
            Some("bounded model checking with the observer, confirmed by the step relation".into()),
        ),
        response::Finding::Unknown(why) => Outcome::unknown(why),
    }
}
