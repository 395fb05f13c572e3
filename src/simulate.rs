//! `bip simulate FILE --steps N --seed S [--trace OUT]`: prints a simulation of the model
//! ([`bip_engine::simulate`]: the engine with default codels and random requests,
//! checking every invariant, and deadlock freedom if the model asks for it, at every
//! step) and streams its trace to OUT as it runs. Memory stays constant for any number of
//! steps. Exit codes: 0 every check held, 1 one failed (the last steps are printed), 2
//! model or usage error, 3 interrupted (Ctrl-C; the report so far, the trace so far).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::sync::atomic::Ordering;

use bip_engine::simulate::{
    simulate_with, BudgetEventKind, Hooks, Simulation, SimulationEnd, SimulationOptions,
};
use bip_engine::{CodelTime, CODEL_TIME_BUCKETS};
use bip_lang::trace_file::TraceWriter;
use bip_model::{System, Trace};
use bip_sched::show_micros as show;

use crate::{exit, interrupt, load};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The model file (RON).
    pub file: PathBuf,
    /// Steps to take (ticks, codels, requests, other steps).
    #[arg(long, default_value_t = 1000)]
    pub steps: u64,
    /// Seed of the random requests and codel outcomes (the run is the same for a seed).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Save the run as a trace (RON) in OUT, written as it runs (some 100 bytes a step).
    #[arg(long, value_name = "OUT")]
    pub trace: Option<PathBuf>,
    /// Show every variable in printed steps, the GenoM expansion's bookkeeping (`req`,
    /// `paused`) included.
    #[arg(long)]
    pub all_variables: bool,
    /// Draw the run saved with --trace as a timeline in FILE (SVG): one lane per activity.
    #[arg(long, value_name = "FILE", requires = "trace")]
    pub svg: Option<PathBuf>,
    /// How long codels take on the virtual clock, on CPUs scheduled as `bip sched`
    /// assumes.
    #[arg(long, value_enum, default_value = "zero")]
    pub codel_time: CodelTimeArg,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CodelTimeArg {
    /// No time, as in the model.
    Zero,
    /// Each its WCET: the analysis' worst case.
    Wcet,
    /// Uniformly from 0 to its WCET (from the seed).
    Random,
}

pub fn run(args: &Args) -> u8 {
    let Some(system) = model(args) else {
        return exit::ERROR;
    };
    // the trace file is opened before the run, so that a bad path fails at once
    let mut writer = match &args.trace {
        None => None,
        Some(out) => match File::create(out)
            .and_then(|f| TraceWriter::new(BufWriter::new(f), &system.name, system.is_timed()))
        {
            Ok(w) => Some(w),
            Err(e) => {
                eprintln!("error: cannot write {}: {e}", out.display());
                return exit::ERROR;
            }
        },
    };
    let mut write_error: Option<std::io::Error> = None;
    let mut on_steps = |segment: &Trace| {
        if let (Some(w), None) = (writer.as_mut(), write_error.as_ref()) {
            write_error = w.steps(&segment.steps).err();
        }
    };
    let stop_flag = interrupt::stop_flag();
    let stop = || stop_flag.load(Ordering::Relaxed);
    let hooks = Hooks {
        stop: Some(&stop),
        on_steps: args
            .trace
            .is_some()
            .then_some(&mut on_steps as &mut dyn FnMut(&Trace)),
    };
    let options = SimulationOptions {
        steps: args.steps,
        seed: args.seed,
        codel_time: match args.codel_time {
            CodelTimeArg::Zero => CodelTime::Zero,
            CodelTimeArg::Wcet => CodelTime::Wcet,
            CodelTimeArg::Random => CodelTime::Random(args.seed),
        },
    };
    let sim = match simulate_with(system.clone(), options, hooks) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return exit::ERROR;
        }
    };
    let stats = sim.stats;
    let mut code = match sim.end {
        SimulationEnd::Interrupted => exit::INCONCLUSIVE,
        ref end if end.fails() => exit::FAILED,
        _ => exit::OK,
    };
    println!(
        "{}: system `{}`, simulation with seed {}",
        args.file.display(),
        system.name,
        args.seed
    );
    println!(
        "  {}: {}, {} ({}, {}), {} sent ({} accepted, {} refused)",
        count(stats.steps, "step"),
        count(stats.ticks, "tick"),
        count(stats.codels, "codel"),
        count(stats.exceptions, "exception"),
        count(stats.faults, "fault"),
        count(sim.requests_sent, "request"),
        stats.requests_accepted,
        stats.requests_refused
    );
    let invariants = count(sim.invariants as u64, "invariant");
    let and_deadlock = if sim.deadlock_checked {
        " and deadlock freedom"
    } else {
        ""
    };
    match &sim.end {
        SimulationEnd::Completed => {
            println!("  {invariants}{and_deadlock} held at every step")
        }
        SimulationEnd::Interrupted => println!(
            "  interrupted after {}: {invariants}{and_deadlock} held at every step until then",
            count(stats.steps, "step")
        ),
        SimulationEnd::Stuck => println!(
            "  stopped: no step is possible and nothing can arrive; {invariants} held until then"
        ),
        SimulationEnd::Violation(p) => {
            println!("  invariant `{p}` FAILS after step {}", stats.steps)
        }
        SimulationEnd::Deadlock => println!("  DEADLOCK after step {}", stats.steps),
        SimulationEnd::RangeError(m) => {
            println!("  RANGE ERROR after step {}: {m}", stats.steps)
        }
    }
    print!("{}", budgets(&sim, args.codel_time));
    print!("{}", late_responses(&sim));
    if code == exit::FAILED {
        let last = &sim.last_steps;
        print!(
            "{}",
            last.trace
                .display(Some(&system))
                .from(&last.start, last.skipped)
                .all_variables(args.all_variables)
        );
    }
    if let (Some(out), Some(w)) = (&args.trace, writer) {
        let done = match write_error {
            Some(e) => Err(e),
            None => w
                .finish(&sim.last_steps.trace.verdict)
                .and_then(|mut f| f.flush()),
        };
        match done {
            Ok(()) => println!("  trace saved in {}", out.display()),
            Err(e) => {
                eprintln!("error: cannot write {}: {e}", out.display());
                code = exit::ERROR;
            }
        }
    }
    if let (Some(svg), Some(out)) = (&args.svg, &args.trace) {
        if let Err(e) = crate::trace::save_timeline(&system, out, svg) {
            eprintln!("error: {e}");
            // a failed property's exit code says more than the missing picture
            if code == exit::OK {
                code = exit::ERROR;
            }
        }
    }
    code
}

/// The model to run; `None` once its diagnostic is printed. With `--codel-time wcet` or
/// `random`, an untimed GenoM layer is loaded as a timed one (`time: Exact`, its CPUs as
/// declared, a CPU written as its name alone one preemptive core), so that its codels take
/// their times in the model's own semantics (docs/engine.md, "Codel times"). A model that
/// cannot be timed yet (an aperiodic task, an `async` codel, an atom standing for a task, tasks
/// sharing a lock on a preemptive CPU) runs
/// untimed, its codel times on the engine's simulated CPUs, scheduled as `bip sched`
/// assumes.
fn model(args: &Args) -> Option<System> {
    if args.codel_time == CodelTimeArg::Zero {
        return load::system(&args.file);
    }
    match bip_lang::load_file_timed(&args.file) {
        Ok(timed) if timed.genom.is_some() => Some(timed),
        _ => load::system(&args.file),
    }
}

/// The codels' run times, and the overruns and misses the run saw.
fn budgets(sim: &Simulation, codel_time: CodelTimeArg) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    let ran: Vec<_> = sim.codels.iter().filter(|c| c.times.runs > 0).collect();
    if ran.is_empty() {
        return out;
    }
    let how = match codel_time {
        CodelTimeArg::Zero => "none simulated: codels are instants",
        CodelTimeArg::Wcet => "simulated: each its WCET",
        CodelTimeArg::Random => "simulated: random up to its WCET",
    };
    let _ = writeln!(out, "  codel times ({how}):");
    let rows: Vec<[String; 6]> = ran
        .iter()
        .map(|c| {
            let (m, s, k) = &c.codel;
            [
                format!("{m}.{s}.{k}"),
                c.times.runs.to_string(),
                show(c.times.max_us),
                show(c.times.mean_us().round() as u64),
                c.wcet_us.map_or("-".into(), show),
                histogram(&c.times.histogram),
            ]
        })
        .collect();
    let header = ["codel", "runs", "max", "mean", "wcet", "runs by time"].map(String::from);
    let widths: Vec<usize> = (0..6)
        .map(|i| {
            rows.iter()
                .chain([&header])
                .map(|r| r[i].chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    for row in [&header].into_iter().chain(&rows) {
        let mut line = format!("    {:<w$}", row[0], w = widths[0]);
        for i in 1..5 {
            let _ = write!(line, "  {:>w$}", row[i], w = widths[i]);
        }
        let _ = writeln!(out, "{line}  {}", row[5]);
    }
    let stats = &sim.stats;
    let _ = writeln!(
        out,
        "  {} past a WCET, {} past a deadline",
        count(stats.wcet_exceeded, "codel run"),
        count(stats.deadlines_missed, "period's work")
    );
    for e in &sim.budget_events {
        let codel = e.codel.as_ref().map(|(m, s, k)| format!("{m}.{s}.{k}"));
        let what = match &e.kind {
            BudgetEventKind::WcetExceeded { took_us, wcet_us } => format!(
                "{} took {}, its WCET is {}",
                codel.unwrap_or_default(),
                show(*took_us),
                show(*wcet_us)
            ),
            BudgetEventKind::DeadlineMissed {
                task,
                elapsed_us,
                deadline_us,
            } => format!(
                "task {task} was late: {} after its release, deadline {}{}",
                show(*elapsed_us),
                show(*deadline_us),
                codel.map_or(String::new(), |c| format!(" ({c} ran last)"))
            ),
        };
        let _ = writeln!(out, "    at {}: {what}", show(e.at_us));
    }
    let shown = sim.budget_events.len() as u64;
    let all = stats.wcet_exceeded + stats.deadlines_missed;
    if all > shown {
        let _ = writeln!(out, "    ... and {} more", all - shown);
    }
    out
}

/// The bounded response properties watched, and the deadline misses the run saw.
fn late_responses(sim: &Simulation) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    if sim.responses_monitored == 0 {
        return out;
    }
    let late = sim.stats.responses_late;
    let n = sim.responses_monitored;
    let properties = if n == 1 { "property" } else { "properties" };
    let _ = writeln!(
        out,
        "  {n} bounded response {properties} watched at every step: {late} late"
    );
    for e in &sim.late_responses {
        let request = e
            .ticket
            .map_or(String::new(), |t| format!(" (request #{t})"));
        let _ = writeln!(
            out,
            "    after step {}, at {}: {}: no response {} after its trigger{request}, past its bound of {}",
            e.step,
            show(e.at_us),
            e.property,
            count(e.elapsed_ticks, "tick"),
            e.within
        );
    }
    let shown = sim.late_responses.len() as u64;
    if late > shown {
        let _ = writeln!(out, "    ... and {} more", late - shown);
    }
    out
}

/// Runs by duration: `≤ 2 ms: 5, ≤ 4 ms: 1` (bucket `k` holds runs under 2^k µs).
fn histogram(buckets: &[u64; CODEL_TIME_BUCKETS]) -> String {
    let parts: Vec<String> = buckets
        .iter()
        .enumerate()
        .filter(|(_, &n)| n > 0)
        .map(|(k, n)| {
            if k + 1 == CODEL_TIME_BUCKETS {
                format!("longer: {n}")
            } else {
                format!("< {} µs: {n}", 1u64 << k)
            }
        })
        .collect();
    parts.join(", ")
}

/// "1 step", "2 steps".
fn count(n: u64, what: &str) -> String {
    format!("{n} {what}{}", if n == 1 { "" } else { "s" })
}
