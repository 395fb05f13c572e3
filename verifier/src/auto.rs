//! `--method auto`: the explicit method when the model is small enough, the symbolic one
//! for what it leaves open.
//!
//! The explicit exploration runs first within a budget (at most [`AUTO_STATES`] states and
//! [`AUTO_BYTES`] of stored states, or the user's smaller limits). Every verdict it reaches
//! stands: a failure with its shortest trace, a witness, and, when it explored every
//! reachable state, every "holds". The properties it leaves undecided go to the symbolic
//! method. Each property's result says which method decided it.

use std::time::Instant;

use bip_model::System;

use crate::error::VerifyError;
use crate::options::Options;
use crate::progress::Progress;
use crate::report::{CheckKind, Method, PropertyVerdict, Report, Stop};
use crate::{explore, symbolic};

/// States the explicit phase may store.
const AUTO_STATES: u64 = 1_000_000;
/// Bytes of stored states the explicit phase may use.
const AUTO_BYTES: u64 = 256 << 20;

pub(crate) fn verify(
    system: &System,
    options: &Options,
    progress: &(dyn Fn(&Progress) + Sync),
) -> Result<Report, VerifyError> {
    let started = Instant::now();
    // a stored state costs its packed bytes, a parent link and about as much again of table
    let per_state = system.layout.bytes() as u64 * 2 + 12;
    let budget = AUTO_STATES.min(AUTO_BYTES / per_state).max(1);
    let explicit_options = Options {
        max_states: Some(options.max_states.map_or(budget, |m| m.min(budget))),
        ..options.clone()
    };
    let explicit = explore::verify(system, &explicit_options, progress)?;
    // a timed model's worst responses are the explicit method's alone: the symbolic one
    // has nothing to add to them
    let open = explicit.properties.iter().any(|p| {
        matches!(p.verdict, PropertyVerdict::Inconclusive { .. })
            && p.kind != CheckKind::WorstResponse
    });
    // the user's interrupt and time limit end the whole run, not just the explicit phase
    let ended = matches!(
        explicit.stopped,
        Some(Stop::Interrupted | Stop::Timeout { .. })
    );
    if !open
        || ended
        || explicit.properties.iter().any(|p| p.verdict.fails()) && options.stop_at_first
    {
        return Ok(Report {
            method: Method::Auto,
            ..explicit
        });
    }
    // the symbolic method gets the time that remains
    let symbolic_options = Options {
        timeout: options.timeout.map(|t| t.saturating_sub(started.elapsed())),
        ..options.clone()
    };
    let mut symbolic = symbolic::verify(system, &symbolic_options, progress)?;
    // the symbolic phase's time limit is what remained of the user's: say the user's
    if let (Some(Stop::Timeout { seconds }), Some(t)) = (&mut symbolic.stopped, options.timeout) {
        let theirs = Stop::Timeout { seconds: *seconds }.to_string();
        *seconds = t.as_secs_f64();
        let mine = Stop::Timeout { seconds: *seconds }.to_string();
        for p in &mut symbolic.properties {
            if let PropertyVerdict::Inconclusive { reason } = &mut p.verdict {
                *reason = reason.replace(&theirs, &mine);
            }
        }
    }
    let mut report = explicit;
    for (mine, theirs) in report.properties.iter_mut().zip(symbolic.properties) {
        if matches!(mine.verdict, PropertyVerdict::Inconclusive { .. }) {
            *mine = theirs;
        }
    }
    let undecided = report
        .properties
        .iter()
        .any(|p| matches!(p.verdict, PropertyVerdict::Inconclusive { .. }));
    // what stopped the run: the symbolic phase's limit if it reached one, else the
    // explicit phase's budget
    if !undecided {
        report.stopped = None;
    } else if symbolic.stopped.is_some() {
        report.stopped = symbolic.stopped;
    }
    report.method = Method::Auto;
    report.symbolic = symbolic.symbolic;
    Ok(report)
}
