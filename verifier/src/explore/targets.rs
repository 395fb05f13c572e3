//! What a run checks and what it concludes: the properties as targets, and the findings
//! made verdicts, with the trace to the state each was found in.

use crate::properties::time_words;
use std::borrow::Cow;

use bip_model::eval::Expr;
use bip_model::{Happens, Property, PropertyKind as ModelKind, System};

use crate::error::VerifyError;
use crate::properties::{
    check_kind, checked_properties, checks_time_progress, default_terminal, error_step,
    RANGE_ERRORS, TIME_PROGRESS,
};
use crate::report::{CheckKind, Method, PropertyResult, PropertyVerdict, Report, RunStats, Stop};

use super::graph::Keep;
use super::response::watched::{Flagged, Watched, Watching, MAX_WATCHED};
use super::response::{decide, gives_worst_waits, Decided, Question, WorstWait as WaitFigure};
use super::trace::trace_to;
use super::worst::worst_responses;
use super::{Explorer, Finding, Found};

/// What one property checks, with its compiled expression.
pub(super) enum Check<'a> {
    Deadlock {
        terminal: Option<&'a Expr>,
    },
    Invariant(&'a Expr),
    Reachable(&'a Expr),
    /// Decided on the state graph once the exploration is complete (`response`).
    Response {
        trigger: &'a Happens,
        response: &'a Happens,
        within: Option<u64>,
    },
    /// Decided on the state graph once the exploration is complete (`response::timelock`).
    TimeProgress,
    RangeErrors,
}

pub(super) struct Target<'a> {
    pub(super) name: String,
    kind: CheckKind,
    expr: String,
    pub(super) check: Check<'a>,
}

/// The properties a run checks: the model's (deadlock freedom if it has none), time
/// progress in a model with `Time` connectors, and range errors, which are always checked.
pub(super) fn targets(system: &System) -> Vec<Target<'_>> {
    let mut out: Vec<Target<'_>> = checked_properties(system)
        .into_iter()
        .map(|p| {
            let (kind, check) = match &p {
                Cow::Borrowed(Property { kind, .. }) => (
                    check_kind(kind),
                    match kind {
                        ModelKind::DeadlockFree { terminal } => Check::Deadlock {
                            terminal: terminal.as_ref(),
                        },
                        ModelKind::Invariant(e) => Check::Invariant(e),
                        ModelKind::Reachable(e) => Check::Reachable(e),
                        ModelKind::Response {
                            trigger,
                            response,
                            within,
                        } => Check::Response {
                            trigger,
                            response,
                            within: *within,
                        },
                    },
                ),
                // the default property, which borrows nothing from the system's list
                Cow::Owned(_) => (
                    CheckKind::DeadlockFree,
                    Check::Deadlock {
                        terminal: default_terminal(system),
                    },
                ),
            };
            Target {
                name: p.name.clone(),
                kind,
                expr: p.text.clone(),
                check,
            }
        })
        .collect();
    if checks_time_progress(system) {
        out.push(Target {
            name: TIME_PROGRESS.into(),
            kind: CheckKind::TimeProgress,
            expr: String::new(),
            check: Check::TimeProgress,
        });
    }
    out.push(range_errors());
    out
}

/// Whether a run of `targets` asks a question about paths (a response property, time
/// progress), which the state graph answers.
pub(super) fn asks_paths(targets: &[Target<'_>]) -> bool {
    targets
        .iter()
        .any(|t| matches!(t.check, Check::Response { .. } | Check::TimeProgress))
}

/// The response properties that the state graph watches: the first [`MAX_WATCHED`] of
/// `targets`, in order (`response::decide` finds the others inconclusive).
pub(super) fn watched<'a>(targets: &[Target<'a>]) -> Vec<Watched<'a>> {
    targets
        .iter()
        .filter_map(|t| match t.check {
            Check::Response {
                trigger, response, ..
            } => Some(Watched {
                context: format!("property {}", t.name),
                trigger,
                response,
            }),
            _ => None,
        })
        .take(MAX_WATCHED)
        .collect()
}

/// What the state graph of a run of `system` for `targets` keeps: the watched response
/// properties, and each tick's time units if one of them counts them.
pub(super) fn watching<'s, 'a>(
    system: &'s System,
    targets: &[Target<'a>],
    watched: &'s [Watched<'a>],
) -> Watching<'s, 'a> {
    Watching {
        advance: counts_units(system, targets),
        system,
        watched,
    }
}

/// Whether the state graph of a run of `system` for `targets` must note each tick's
/// time units: the system has an `advance`, and a bounded response property is watched,
/// or any response property where it gets its worst response (which sums them).
pub(super) fn counts_units(system: &System, targets: &[Target<'_>]) -> bool {
    let timed = gives_worst_waits(system);
    system.has_advance()
        && targets
            .iter()
            .filter(|t| matches!(t.check, Check::Response { .. }))
            .take(MAX_WATCHED)
            .any(|t| {
                timed
                    || matches!(
                        t.check,
                        Check::Response {
                            within: Some(_),
                            ..
                        }
                    )
            })
}

/// The range errors, which every run checks.
pub(super) fn range_errors<'a>() -> Target<'a> {
    Target {
        name: RANGE_ERRORS.into(),
        kind: CheckKind::RangeErrors,
        expr: String::new(),
        check: Check::RangeErrors,
    }
}

impl<K: Keep<Edge = u32, Notes = super::response::watched::Notes>> Explorer<'_, K> {
    /// Explores, then answers every property.
    pub(super) fn run(
        mut self,
        progress: &(dyn Fn(&crate::progress::Progress) + Sync),
    ) -> Result<Report, VerifyError> {
        let stopped = self.explore(progress)?;
        self.report(stopped)
    }

    pub(super) fn report(mut self, stopped: Option<Stop>) -> Result<Report, VerifyError> {
        let seconds = self.started.elapsed().as_secs_f64();
        let states = self.visited.len();
        // the deepest level with a stored state (the run may have stopped before expanding it)
        let depth = (0..self.visited.levels())
            .rev()
            .find(|&l| self.visited.level_len(l) > 0)
            .unwrap_or(0) as u32;
        let complete = stopped.is_none() && !self.stopped_decided;
        let stats = RunStats {
            states,
            complete,
            transitions: self.transitions,
            depth,
            seconds,
            states_per_second: if seconds > 0.0 {
                states as f64 / seconds
            } else {
                0.0
            },
            bytes_per_state: self.visited.used_bytes() as f64 / states.max(1) as f64,
            state_bytes: self.visited.width(),
            store_bytes: self.store_bytes(),
            jobs: self.jobs,
        };
        // the response properties need every state, and the run stops early only when
        // none is left open (`all_decided`), so `complete` is enough
        let mut responses: Vec<Option<Decided>> = self.targets.iter().map(|_| None).collect();
        let mut run_stopped = stopped.clone();
        if complete {
            let (which, questions): (Vec<usize>, Vec<Question<'_>>) = self
                .targets
                .iter()
                .enumerate()
                .filter_map(|(k, t)| match &t.check {
                    Check::Response { within, .. } => Some((
                        k,
                        Question {
                            name: &t.name,
                            within: *within,
                        },
                    )),
                    _ => None,
                })
                .unzip();
            let progress = self
                .targets
                .iter()
                .position(|t| matches!(t.check, Check::TimeProgress));
            self.watch.rebase();
            if self.graph_dropped {
                // as if the graph had been built after the exploration and did not fit
                self.watch.out_of_memory();
            }
            let started = std::time::Instant::now();
            let graph_bytes = self.graph_bytes();
            let graph: Option<Flagged> = self
                .recorder
                .take()
                .and_then(|r| r.finish(&self.visited, self.watch));
            let (decided, time_progress) = decide(
                self.system,
                &self.visited,
                &questions,
                progress.is_some(),
                graph,
                self.watch,
            )?;
            if !which.is_empty() || progress.is_some() {
                tracing::info!(
                    seconds = started.elapsed().as_secs_f64(),
                    graph_bytes,
                    "state graph searched"
                );
            }
            // a limit reached while the graph was searched stopped the run too (every
            // state was explored: `complete` stays true)
            if !which.is_empty() || progress.is_some() {
                run_stopped = self.watch.stopped().cloned();
            }
            for (k, d) in which.into_iter().zip(decided) {
                responses[k] = Some(d);
            }
            if let (Some(k), Some(d)) = (progress, time_progress) {
                responses[k] = Some(d);
            }
        }
        let mut properties = Vec::with_capacity(self.targets.len());
        let mut worst_waits = Vec::new();
        for (k, (t, f)) in self.targets.iter().zip(&self.findings).enumerate() {
            let mut decided = responses.get_mut(k).and_then(Option::take);
            let note = decided.as_ref().and_then(|d| d.note.clone());
            let wait = decided.as_mut().and_then(|d| d.worst.take());
            let verdict = match (f, decided) {
                (_, Some(d)) => d.verdict,
                (Some(f), None) => self.verdict_of(t, f)?,
                (None, None) => self.open_verdict(t, stopped.as_ref(), states),
            };
            if matches!(t.check, Check::Response { .. }) && gives_worst_waits(self.system) {
                worst_waits.push(worst_wait_result(self.system, t, wait, &verdict));
            }
            let error_step = verdict.trace().and_then(|tr| error_step(self.system, tr));
            properties.push(PropertyResult {
                name: t.name.clone(),
                kind: t.kind,
                expr: t.expr.clone(),
                verdict,
                method: Method::Explicit,
                note,
                error_step,
                worst_us: None,
            });
        }
        properties.extend(worst_waits);
        // a timed model's worst responses: exact when every state was seen, else the
        // most the stored states show (none once the user interrupted the run)
        let look = !matches!(run_stopped, Some(Stop::Interrupted));
        let started = std::time::Instant::now();
        let seen = std::mem::replace(&mut self.seen, Ok(Vec::new()));
        properties.extend(worst_responses(
            self.system,
            &self.visited,
            &self.tasks,
            complete,
            look,
            seen,
        )?);
        if !self.tasks.is_empty() {
            tracing::info!(seconds = started.elapsed().as_secs_f64(), "worst responses");
        }
        tracing::info!(
            states,
            transitions = self.transitions,
            depth,
            seconds,
            expand_seconds = self.expand_time.as_secs_f64(),
            insert_seconds = self.insert_time.as_secs_f64(),
            "explored"
        );
        Ok(Report {
            model: self.system.name.clone(),
            method: Method::Explicit,
            properties,
            stats,
            stopped: run_stopped,
            symbolic: None,
            seconds,
            peak_memory_bytes: None,
        })
    }

    fn verdict_of(&self, t: &Target<'_>, f: &Finding) -> Result<PropertyVerdict, VerifyError> {
        use bip_model::Verdict as TraceVerdict;
        let (trace_verdict, reason) = match &f.what {
            Found::Deadlock => (TraceVerdict::Deadlock, "deadlock".to_string()),
            Found::Violation => (
                TraceVerdict::Violation(t.name.clone()),
                "violated".to_string(),
            ),
            Found::Witness => (TraceVerdict::Witness(t.name.clone()), String::new()),
            Found::RangeError(m) => (
                TraceVerdict::RangeError(m.clone()),
                format!("range error: {m}"),
            ),
        };
        let trace = trace_to(self.system, &self.visited, f.state, None, trace_verdict)?;
        let n = trace.steps.len();
        let after = format!("after {n} step{}", if n == 1 { "" } else { "s" });
        Ok(match f.what {
            Found::Witness => PropertyVerdict::Holds {
                witness: Some(trace),
            },
            _ => PropertyVerdict::Fails {
                reason: format!("{reason} {after}"),
                trace: Some(trace),
            },
        })
    }

    /// The verdict of a property nothing was found about.
    fn open_verdict(&self, t: &Target<'_>, stopped: Option<&Stop>, states: u64) -> PropertyVerdict {
        if let Some(stop) = stopped {
            return PropertyVerdict::Inconclusive {
                reason: format!("{stop} after {states} states"),
            };
        }
        match t.check {
            // decided on the graph only: never "holds" without it
            Check::TimeProgress | Check::Response { .. } => PropertyVerdict::Inconclusive {
                reason: "the state graph was not searched".into(),
            },
            Check::Reachable(_) => PropertyVerdict::Fails {
                reason: format!("no reachable state satisfies it ({states} states explored)"),
                trace: None,
            },
            Check::Deadlock { .. } if self.liveness_unknown > 0 => PropertyVerdict::Inconclusive {
                reason: format!(
                    "in {} states without a progress step, the states reached by time steps alone exceed the liveness check's bound",
                    self.liveness_unknown
                ),
            },
            _ => PropertyVerdict::Holds { witness: None },
        }
    }
}

/// The row of response property `t`'s worst response (`wait`, if it was computed; the
/// property's verdict is `decided`): `NAME worst response`, in microseconds in a timed
/// model, in time units otherwise.
fn worst_wait_result(
    system: &System,
    t: &Target<'_>,
    wait: Option<WaitFigure>,
    decided: &PropertyVerdict,
) -> PropertyResult {
    let unit_us = system.genom.as_ref().and_then(|g| g.time_unit_us);
    let (verdict, units, note) = match wait {
        Some(w) => (w.verdict, w.units, w.note),
        None => (
            PropertyVerdict::Inconclusive {
                reason: match decided {
                    PropertyVerdict::Inconclusive { reason } => format!("not given: {reason}"),
                    _ => "not given: the state graph was not searched".into(),
                },
            },
            None,
            None,
        ),
    };
    // a model without a GenoM layer counts time units, which its `advance`s give
    let shown = |u: u64| match unit_us {
        Some(_) => time_words(system, u),
        None => format!("{u} time unit{}", if u == 1 { "" } else { "s" }),
    };
    let note = match (units, note) {
        (Some(u), Some(n)) => Some(format!("{}, {n}", shown(u))),
        (Some(u), None) => Some(shown(u)),
        (None, n) => n,
    };
    let worst_us = units.zip(unit_us).map(|(u, us)| u.saturating_mul(us));
    PropertyResult::worst_response(&t.name, verdict, note, worst_us)
}
