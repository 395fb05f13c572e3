//! `bip replay FILE TRACE`: re-executes a counterexample, a witness or a recording through
//! the engine, step by step, showing that the engine allowed each step (a codel ran as a
//! codel, a request was served as a request, a tick was a tick) and where the property
//! fails. Exit codes: 0 a recording replayed in full; 1 the trace's failure is reached
//! (deadlock, violation, range error) or its witness holds; 2 the trace does not fit
//! the model (a step is not allowed, or its verdict does not show), or bad input.

use std::path::PathBuf;

use bip_engine::replay::{replay, End};
use bip_engine::Stepped;

use crate::{exit, trace};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The model file (RON).
    pub file: PathBuf,
    /// The trace file (RON), as `bip verify --trace-dir` or `bip simulate --trace` write it.
    pub trace: PathBuf,
    /// Show every variable in the steps, the GenoM expansion's bookkeeping (`req`,
    /// `paused`) included.
    #[arg(long)]
    pub all_variables: bool,
}

pub fn run(args: &Args) -> u8 {
    let Some((system, trace)) = trace::model_and_trace(&args.file, &args.trace) else {
        return exit::ERROR;
    };
    let result = match replay(system.clone(), &trace) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return exit::ERROR;
        }
    };
    let n = trace.steps.len() as u64;
    println!(
        "{}: replaying {} ({n} step{}) through the engine",
        args.file.display(),
        args.trace.display(),
        if n == 1 { "" } else { "s" }
    );
    let notes: Vec<String> = result
        .steps
        .iter()
        .map(|done| {
            let what = match done.stepped {
                Stepped::Tick => "tick".to_string(),
                Stepped::Codel { codel, failed } => {
                    let (m, s, c) = result.engine.inspect().codel_name(codel);
                    let path = if failed { ", error path" } else { "" };
                    format!("codel {m}.{s}.{c} ran{path}")
                }
                Stepped::Request { .. } => "request accepted".to_string(),
                Stepped::Other | Stepped::Idle { .. } => "step".to_string(),
            };
            format!("allowed: {what}")
        })
        .collect();
    print!(
        "{}",
        trace
            .display(Some(&system))
            .notes(&notes)
            .without_header()
            .all_variables(args.all_variables)
    );
    let width = trace
        .steps
        .iter()
        .map(|s| s.step.len())
        .max()
        .unwrap_or(0)
        .min(32);
    let num = trace.steps.len().to_string().len();
    if let Some(r) = &result.refused {
        println!(
            "  {:>num$}  {:<width$}  NOT ALLOWED: {}",
            r.step, r.name, r.message
        );
        for why in &r.reasons {
            println!("  {:>num$}  {:<width$}    because: {why}", "", "");
        }
        println!(
            "result: the trace is not a path of the model through the engine (step {})",
            r.step
        );
        return exit::ERROR;
    }
    for (step, late) in &result.late {
        println!("after step {step}, the engine's monitor: {late}");
    }
    match &result.end {
        Some(End::Recording) | None => {
            println!("result: every step was allowed; the engine ends in the recorded state");
            exit::OK
        }
        Some(End::Deadlock { held }) => {
            let n = result.steps.len();
            println!(
                "deadlock reached after {n} step{}: no progress step is enabled now or after any number of ticks",
                if n == 1 { "" } else { "s" }
            );
            for h in held {
                println!("  waiting: {h}");
            }
            println!("result: DeadlockFree fails");
            exit::FAILED
        }
        Some(End::Violation { property }) => {
            println!("invariant `{property}` fails in the last state");
            println!("result: {property} fails");
            exit::FAILED
        }
        Some(End::Witness { property }) => {
            println!("`{property}` holds in the last state");
            println!("result: witness for {property}");
            exit::FAILED
        }
        Some(End::WorstResponse { property }) => {
            println!("the run of `{property}`: its last step is where `bip verify` measured it");
            println!("result: witness for {property}");
            exit::FAILED
        }
        Some(End::Unanswered {
            property,
            loop_start,
        }) => {
            match loop_start {
                Some(k) => println!(
                    "the run repeats steps {}-{} forever ({}; the last step returns to the state after step {k}), and `{property}`'s response never comes on it",
                    k + 1,
                    trace.steps.len(),
                    cycle_names(&trace, *k)
                ),
                None => println!("`{property}`'s trigger goes unanswered at the end of the trace"),
            }
            println!("result: {property} fails");
            exit::FAILED
        }
        Some(End::Timelock { loop_start }) => {
            let n = result.steps.len();
            match loop_start {
                Some(k) => println!(
                    "time stops: after {k} step{}, the cycle of steps {}-{n} repeats forever and no run from it lets time pass",
                    if *k == 1 { "" } else { "s" },
                    k + 1
                ),
                None => println!(
                    "time stops after {n} step{}: no run from the last state lets time pass",
                    if n == 1 { "" } else { "s" }
                ),
            }
            println!("result: {} fails", bip_verifier::TIME_PROGRESS);
            exit::FAILED
        }
        Some(End::BusyLoop { loop_start }) => {
            let n = result.steps.len();
            println!(
                "time stands still: after {loop_start} step{}, the cycle of steps {}-{n} can repeat forever, and no state on it lets time pass (a busy loop)",
                if *loop_start == 1 { "" } else { "s" },
                loop_start + 1
            );
            println!("result: {} fails", bip_verifier::TIME_PROGRESS);
            exit::FAILED
        }
        Some(End::RangeError { message }) => {
            println!("range error from the last state: {message}");
            println!("result: RangeErrors fails");
            exit::FAILED
        }
        Some(End::NotConfirmed { verdict, why }) => {
            println!("result: every step was allowed, but the trace's verdict {verdict} does not show: {why}");
            exit::ERROR
        }
    }
}

/// The names of a lasso's cycle steps, from `loop_start` on: all of a short cycle, the
/// first and the count of a long one.
fn cycle_names(trace: &bip_model::Trace, loop_start: usize) -> String {
    const SHOWN: usize = 6;
    let cycle = trace.steps.get(loop_start..).unwrap_or_default();
    let names: Vec<&str> = cycle.iter().take(SHOWN).map(|s| s.step.as_str()).collect();
    let mut out = names.join(", ");
    if cycle.len() > SHOWN {
        out.push_str(&format!(", … {} more", cycle.len() - SHOWN));
    }
    out
}
