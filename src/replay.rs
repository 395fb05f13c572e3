//! `bip replay FILE TRACE`: re-executes a counterexample, a witness or a recording through
//! the engine, step by step, showing that the engine allowed each step (a codel ran as a
//! codel, a request was served as a request, a tick was a tick) and where the property
//! fails. Exit codes: 0 a recording replayed in full; 1 the trace's failure is reached
//! (deadlock, violation, range error) or its witness holds; 2 the trace does not fit
//! the model (a step is not allowed, or its verdict does not show), or bad input.

use std::collections::HashMap;
use std::path::PathBuf;

use bip_engine::replay::{replay, End};
use bip_engine::Stepped;
use bip_model::TraceValue;

use crate::{exit, load};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The model file (RON).
    pub file: PathBuf,
    /// The trace file (RON), as `bip verify --trace-dir` or `bip simulate --trace` write it.
    pub trace: PathBuf,
}

pub fn run(args: &Args) -> u8 {
    let Some(system) = load::system(&args.file) else {
        return exit::ERROR;
    };
    let text = match std::fs::read_to_string(&args.trace) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: cannot read {}: {e}", args.trace.display());
            return exit::ERROR;
        }
    };
    let trace = match bip_lang::trace_file::from_ron(&text) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {}: not a trace: {e}", args.trace.display());
            return exit::ERROR;
        }
    };
    if trace.system != system.name {
        eprintln!(
            "warning: the trace is of system `{}`, the model is `{}`",
            trace.system, system.name
        );
    }
    // the values before each step, for `old → new`
    let mut current: HashMap<String, TraceValue> = HashMap::new();
    let init = system.initial_state();
    for slot in 0..system.slot_count() as u32 {
        current.insert(system.slot_name(slot), system.trace_value(&init, slot));
    }
    let result = match replay(system, &trace) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return exit::ERROR;
        }
    };
    println!(
        "{}: replaying {} ({} steps) through the engine",
        args.file.display(),
        args.trace.display(),
        trace.steps.len()
    );
    let width = trace
        .steps
        .iter()
        .map(|s| s.step.len())
        .max()
        .unwrap_or(0)
        .min(32);
    let num = trace.steps.len().to_string().len();
    for (k, (done, ts)) in result.steps.iter().zip(&trace.steps).enumerate() {
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
        let mut changes = Vec::new();
        for (name, v) in ts.state.iter() {
            match current.insert(name.clone(), v.clone()) {
                Some(old) if old != *v => changes.push(format!("{name}: {old} → {v}")),
                _ => changes.push(format!("{name} = {v}")),
            }
        }
        println!(
            "  {:>num$}  {:<width$}  allowed: {what:<36}  {}",
            k + 1,
            done.name,
            changes.join(", ")
        );
    }
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
    match &result.end {
        Some(End::Recording) | None => {
            println!("result: every step was allowed; the engine ends in the recorded state");
            exit::OK
        }
        Some(End::Deadlock { held }) => {
            println!(
                "deadlock reached after {} steps: no progress step is enabled now or after any number of ticks",
                result.steps.len()
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
