//! `bip verify FILE`: check every property of a model, print the verdicts, save the traces.

use std::fmt::Write as _;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Duration;

use bip_model::System;
use bip_picture::xml::escape as xml;
use bip_verifier::{
    human_bytes, CheckKind, Method, Progress, PropertyVerdict, Report, VerifyOutcome,
};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::{exit, interrupt, load, memory_guard};

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    Text,
    Json,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// Explore every reachable state (shortest counterexamples).
    Explicit,
    /// Prove with z3 without enumerating states (compositional deadlock freedom,
    /// k-induction, bounded model checking).
    Symbolic,
    /// Explicit within a budget (1,000,000 states and 256 MiB of stored states, or a
    /// smaller --max-states), then symbolic for what is left open.
    Auto,
}

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The model file (RON).
    pub file: PathBuf,
    /// How to verify: explicit exploration, symbolic proofs (z3), or explicit within a
    /// budget (1,000,000 states and 256 MiB of stored states) and symbolic for what it
    /// leaves open.
    #[arg(long, value_enum, default_value = "auto")]
    pub method: MethodArg,
    /// Worker threads (default: one per core; at most 1024).
    #[arg(short, long, value_name = "N", value_parser = parse_jobs)]
    pub jobs: Option<usize>,
    /// Stop, inconclusive, once N states are stored (with --method auto, the explicit
    /// phase stores at most 1,000,000 states and 256 MiB of them anyway).
    #[arg(long, value_name = "N")]
    pub max_states: Option<u64>,
    /// Stop, inconclusive, before the process uses more memory than SIZE, z3 included
    /// (like 512M or 4G, at least 16M; default: 3/4 of the memory available at start).
    #[arg(long, value_name = "SIZE", value_parser = parse_memory)]
    pub max_memory: Option<u64>,
    /// Stop, inconclusive, after SECS seconds (Ctrl-C stops the same way).
    #[arg(long, value_name = "SECS", value_parser = parse_seconds)]
    pub timeout: Option<Duration>,
    /// Stop at the first property that fails.
    #[arg(long)]
    pub stop_at_first: bool,
    /// Output format on stdout.
    #[arg(long, value_enum, default_value = "text")]
    pub format: Format,
    /// Also write a JUnit XML report (one test case per property) to FILE.
    #[arg(long, value_name = "FILE")]
    pub junit: Option<PathBuf>,
    /// Save each counterexample and witness as a RON trace file in DIR.
    #[arg(long, value_name = "DIR")]
    pub trace_dir: Option<PathBuf>,
    /// No progress line and no statistics on stderr.
    #[arg(short, long)]
    pub quiet: bool,
    /// Show every variable in counterexamples, the GenoM expansion's bookkeeping (`req`,
    /// `paused`) included.
    #[arg(long)]
    pub all_variables: bool,
    /// Symbolic method: wall-clock limit of one solver call; a call that reaches it makes
    /// its property inconclusive.
    #[arg(long, value_name = "SECS", value_parser = parse_seconds, default_value = "120")]
    pub solver_timeout: Duration,
    /// Symbolic method: deepest bounded model check and largest k of k-induction.
    #[arg(long, value_name = "N", default_value_t = 20)]
    pub max_depth: u32,
    /// Symbolic method: states the explicit search confirming a candidate deadlock may
    /// explore (0: no confirmation).
    #[arg(long, value_name = "N", default_value_t = 200_000)]
    pub confirm_states: u64,
    /// Symbolic method: z3's deterministic resource limit per solver call (reproducible
    /// budgets, for tests).
    #[arg(long, value_name = "N", hide = true)]
    pub rlimit: Option<u32>,
}

/// Less memory than this cannot hold a run; a bare number below it is most likely a
/// forgotten unit (`--max-memory 10` meaning 10 GiB, not 10 bytes).
const MIN_MEMORY: u64 = 16 << 20;

pub(crate) fn parse_memory(s: &str) -> Result<u64, String> {
    let bytes = bip_verifier::parse_size(s)?;
    if bytes < MIN_MEMORY {
        return Err(format!(
            "`{s}` is {}, too little for a run (at least 16M); give a unit, like {}G",
            human_bytes(bytes),
            s.trim()
        ));
    }
    Ok(bytes)
}

/// More workers than this is a typing error (and spawning them would take minutes).
const MAX_JOBS: usize = 1024;

fn parse_jobs(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(n) if (1..=MAX_JOBS).contains(&n) => Ok(n),
        _ => Err(format!(
            "`{s}`: give a number of workers from 1 to {MAX_JOBS}"
        )),
    }
}

pub(crate) fn parse_seconds(s: &str) -> Result<Duration, String> {
    let v: f64 = s
        .parse()
        .map_err(|_| format!("`{s}` is not a number of seconds"))?;
    Duration::try_from_secs_f64(v).map_err(|_| format!("`{s}` is not a number of seconds"))
}

pub fn run(args: &Args) -> u8 {
    memory_guard::guard(args.max_memory, "loading the model", exit::INCONCLUSIVE);
    let loaded = match args.format {
        Format::Text => load::system(&args.file),
        Format::Json => load::system_or_json(&args.file),
    };
    // the verifier watches its own memory from here (a report, inconclusive)
    memory_guard::release();
    let Some(system) = loaded else {
        return exit::ERROR;
    };
    if let Err(message) = check_outputs(args) {
        eprintln!("error: {message}");
        return exit::ERROR;
    }
    let options = bip_verifier::Options {
        jobs: args.jobs.unwrap_or(0),
        max_states: args.max_states,
        max_memory: args.max_memory,
        timeout: args.timeout,
        interrupt: Some(interrupt::stop_flag()),
        stop_at_first: args.stop_at_first,
        liveness_bound: 0,
        symbolic: bip_verifier::SymbolicOptions {
            solver_timeout: Some(args.solver_timeout),
            rlimit: args.rlimit,
            max_depth: args.max_depth,
            confirm_states: args.confirm_states,
            ..bip_verifier::SymbolicOptions::default()
        },
    };
    let show_progress =
        !args.quiet && args.format == Format::Text && std::io::stderr().is_terminal();
    let bar: Mutex<Option<ProgressBar>> = Mutex::new(None);
    // without a terminal, progress goes to the log (`-v`)
    let logged: Mutex<(Option<Duration>, String)> = Mutex::new((None, String::new()));
    let on_progress = |p: &Progress| {
        if show_progress && p.elapsed() >= Duration::from_secs(1) {
            let mut bar = bar.lock().unwrap_or_else(|e| e.into_inner());
            let bar = bar.get_or_insert_with(new_bar);
            bar.set_message(progress_line(p));
        } else if !show_progress {
            // at once for each new property, else every few seconds
            let property = match p {
                Progress::Proving { property, .. } => property.as_str(),
                Progress::Exploring { .. } => "",
            };
            let mut last = logged.lock().unwrap_or_else(|e| e.into_inner());
            let (when, about) = &mut *last;
            if when.is_none_or(|l| p.elapsed() >= l + LOG_EVERY) || about != property {
                *when = Some(p.elapsed());
                property.clone_into(about);
                tracing::info!("progress: {}", progress_line(p));
            }
        }
    };
    let method = match args.method {
        MethodArg::Explicit => Method::Explicit,
        MethodArg::Symbolic => Method::Symbolic,
        MethodArg::Auto => Method::Auto,
    };
    let result = bip_verifier::verify(&system, method, &options, &on_progress);
    if let Some(bar) = bar.lock().unwrap_or_else(|e| e.into_inner()).take() {
        bar.finish_and_clear();
    }
    let report = match result {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return exit::ERROR;
        }
    };
    match write_outputs(args, &system, &report) {
        Ok(()) => match report.outcome() {
            VerifyOutcome::AllHold => exit::OK,
            VerifyOutcome::SomeFail => exit::FAILED,
            VerifyOutcome::Inconclusive => exit::INCONCLUSIVE,
        },
        Err(message) => {
            eprintln!("error: {message}");
            exit::ERROR
        }
    }
}

/// How often progress is logged when there is no terminal to show it on.
const LOG_EVERY: Duration = Duration::from_secs(5);

fn progress_line(p: &Progress) -> String {
    match p {
        Progress::Exploring {
            states,
            transitions,
            depth,
            level_states,
            level_done,
            store_bytes,
            ..
        } => format!(
            "{states} states, {transitions} transitions, depth {depth} ({level_done}/{level_states} of the level), {}",
            human_bytes(*store_bytes)
        ),
        Progress::Proving {
            property,
            step,
            solver_calls,
            ..
        } if property.is_empty() => format!("symbolic: {step} ({})", count(*solver_calls, "solver call")),
        Progress::Proving {
            property,
            step,
            solver_calls,
            ..
        } => format!("symbolic: {property}: {step} ({})", count(*solver_calls, "solver call")),
    }
}

/// `1 step`, `2 steps`, `3 properties`.
fn count(n: u64, what: &str) -> String {
    match (n, what.strip_suffix('y')) {
        (1, _) => format!("1 {what}"),
        (_, Some(stem)) => format!("{n} {stem}ies"),
        (_, None) => format!("{n} {what}s"),
    }
}

/// Checks before the run that its outputs can be written: a report found after an hour
/// must not be lost to a mistyped path.
fn check_outputs(args: &Args) -> Result<(), String> {
    if let Some(dir) = &args.trace_dir {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create the trace directory {}: {e}", dir.display()))?;
    }
    if let Some(path) = &args.junit {
        let existed = path.exists();
        std::fs::OpenOptions::new()
            .append(true)
            .create(true)
            .open(path)
            .map_err(|e| format!("cannot write the JUnit report {}: {e}", path.display()))?;
        if !existed {
            let _ = std::fs::remove_file(path);
        }
    }
    Ok(())
}

fn new_bar() -> ProgressBar {
    let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr_with_hz(1));
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed}] {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    bar
}

fn write_outputs(args: &Args, system: &System, report: &Report) -> Result<(), String> {
    // a trace that cannot be saved (a full disk) is reported after the verdicts, which
    // are printed all the same
    let mut saved = Vec::new();
    let mut unsaved = None;
    if let Some(dir) = &args.trace_dir {
        unsaved = save_traces(dir, report, &mut saved)
            .and_then(|()| crate::trace::save_charts(system, report, &saved))
            .err();
    }
    let text = match args.format {
        Format::Text => text_report(args, system, report, &saved),
        Format::Json => json_report(args, system, report)?,
    };
    let mut stdout = std::io::stdout().lock();
    stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
        .map_err(|e| format!("cannot write the report: {e}"))?;
    if let Some(path) = &args.junit {
        std::fs::write(path, junit_report(args, system, report))
            .map_err(|e| format!("cannot write the JUnit report {}: {e}", path.display()))?;
    }
    unsaved.map_or(Ok(()), Err)
}

/// Writes `<file name>.trace.ron` for each property with a trace, adding each to `saved`
/// as it goes (the property's name and the path).
pub(crate) fn save_traces(
    dir: &Path,
    report: &Report,
    saved: &mut Vec<(String, PathBuf)>,
) -> Result<(), String> {
    let mut taken = std::collections::HashSet::new();
    for p in &report.properties {
        let Some(trace) = p.verdict.trace() else {
            continue;
        };
        let path = dir.join(format!(
            "{}.trace.ron",
            unique_file_name(&p.name, &mut taken)
        ));
        std::fs::write(&path, bip_lang::trace_file::to_ron(trace) + "\n")
            .map_err(|e| format!("cannot write the trace {}: {e}", path.display()))?;
        saved.push((p.name.clone(), path));
    }
    Ok(())
}

/// The longest property name kept whole in a file name: with the hash and the longest
/// suffix (`.trace.ron`), a file name stays far below the 255 bytes file systems allow.
const FILE_NAME_KEPT: usize = 64;

/// A property name as a file name: anything but ASCII letters, digits, `-` and `_`
/// becomes `_`; a name longer than [`FILE_NAME_KEPT`] is cut there and ends in `-` and
/// the hash of the whole name.
fn file_name(name: &str) -> String {
    let safe: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if safe.len() <= FILE_NAME_KEPT {
        return safe;
    }
    format!("{}-{:016x}", &safe[..FILE_NAME_KEPT], name_hash(name))
}

/// [`file_name`], told apart from the names already `taken` (case ignored, for file
/// systems that ignore it): a name that would give a taken file (`p!` and `p?`, `P` and
/// `p`) ends in `-` and its hash instead; `-2`, `-3`, ... if even that is taken.
fn unique_file_name(name: &str, taken: &mut std::collections::HashSet<String>) -> String {
    let base = file_name(name);
    if taken.insert(base.to_lowercase()) {
        return base;
    }
    let hashed = format!(
        "{}-{:016x}",
        &base[..base.len().min(FILE_NAME_KEPT)],
        name_hash(name)
    );
    let mut candidate = hashed.clone();
    let mut n = 1;
    while !taken.insert(candidate.to_lowercase()) {
        n += 1;
        candidate = format!("{hashed}-{n}");
    }
    candidate
}

/// FNV-1a of the name: the same on every machine and in every version, so a property's
/// file keeps its name from run to run.
fn name_hash(name: &str) -> u64 {
    name.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

fn method_name(method: Method) -> &'static str {
    match method {
        Method::Explicit => "explicit",
        Method::Symbolic => "symbolic",
        Method::Auto => "auto",
    }
}

fn kind_name(kind: CheckKind) -> &'static str {
    match kind {
        CheckKind::DeadlockFree => "deadlock freedom",
        CheckKind::Invariant => "invariant",
        CheckKind::Reachable => "reachability",
        CheckKind::Response => "bounded response",
        CheckKind::LeadsTo => "response",
        CheckKind::TimeProgress => "time progress",
        CheckKind::RangeErrors => "range errors",
        CheckKind::Schedulable => "schedulability",
        CheckKind::WorstResponse => "worst response time",
    }
}

fn text_report(
    args: &Args,
    system: &System,
    report: &Report,
    saved: &[(String, PathBuf)],
) -> String {
    let mut s = String::new();
    let st = &report.stats;
    let explicit = format!(
        "explicit-state exploration, {}",
        count(st.jobs as u64, "worker")
    );
    let how = match report.method {
        Method::Explicit => explicit,
        Method::Symbolic => "symbolic proofs (z3)".to_string(),
        Method::Auto if report.symbolic.is_some() => {
            format!(
                "auto: {explicit} within a budget, then symbolic proofs (z3) for what it left open"
            )
        }
        Method::Auto if report.stopped.is_some() => {
            format!("auto: {explicit}, stopped before any symbolic proof")
        }
        Method::Auto => format!("auto: {explicit}; it decided every property"),
    };
    let _ = writeln!(
        s,
        "{}: system `{}`, {how}",
        args.file.display(),
        report.model
    );
    let width = report
        .properties
        .iter()
        .map(|p| p.name.len())
        .max()
        .unwrap_or(0);
    for p in &report.properties {
        let (word, mut detail) = match &p.verdict {
            PropertyVerdict::Holds { witness: Some(t) } if p.kind == CheckKind::WorstResponse => (
                "holds",
                format!(
                    "{}, reached after {}",
                    p.note.clone().unwrap_or_default(),
                    count(t.steps.len() as u64, "step")
                ),
            ),
            PropertyVerdict::Holds { witness: Some(t) } => (
                "holds",
                format!("witness after {}", count(t.steps.len() as u64, "step")),
            ),
            PropertyVerdict::Holds { witness: None } => {
                ("holds", p.note.clone().unwrap_or_default())
            }
            PropertyVerdict::Fails { reason, .. } => ("FAILS", reason.clone()),
            PropertyVerdict::Inconclusive { reason } => ("inconclusive", reason.clone()),
        };
        if report.method == Method::Auto {
            detail = format!("[{}] {detail}", method_name(p.method));
        }
        let line = format!("  {:<width$}  {:<12}  {detail}", p.name, word);
        let _ = writeln!(s, "{}", line.trim_end());
    }
    for p in &report.properties {
        if p.verdict.holds() && p.note.as_deref().is_some_and(|n| n.starts_with("vacuous")) {
            let _ = writeln!(
                s,
                "warning: {} holds vacuously: its trigger never happens in a reachable state or step",
                p.name
            );
        }
    }
    for p in &report.properties {
        let Some(trace) = p.verdict.trace() else {
            continue;
        };
        let what = if p.verdict.holds() {
            "witness"
        } else {
            "counterexample"
        };
        let shown = match crate::trace::timed_text(system, trace, args.all_variables) {
            Some(text) => text,
            None => trace
                .display(Some(system))
                .all_variables(args.all_variables)
                .to_string(),
        };
        let _ = write!(s, "\n{} ({}), {what}: {shown}", p.name, kind_name(p.kind));
        if let Some(step) = &p.error_step {
            // the failing step has no successor, so the trace cannot list it: it is next
            let _ = writeln!(
                s,
                "  {}  {step}  ✗ firing it makes the range error",
                trace.steps.len() + 1
            );
        }
        if p.verdict.fails() {
            crate::trace::why::write_why(&mut s, system, trace);
        }
        if let Some((_, path)) = saved.iter().find(|(n, _)| *n == p.name) {
            let _ = writeln!(s, "  saved as {}", path.display());
        }
    }
    if report
        .properties
        .iter()
        .any(|p| p.kind == CheckKind::RangeErrors && p.verdict.fails())
    {
        let _ = writeln!(
            s,
            "\nnote: steps that make range errors have no successor; the other verdicts are about the states reachable without them"
        );
    }
    if let Some(unit) = system.genom.as_ref().and_then(|g| g.time_unit_us) {
        let _ = writeln!(
            s,
            "\nnote: time counted in whole units of {}, which the verdicts on deadlines and worst responses need no finer (docs/model.md, \"Why whole units are enough\")",
            bip_sched::show_micros(unit)
        );
    }
    if !args.quiet {
        write_figures(&mut s, report);
    }
    if let Some(stop) = &report.stopped {
        let _ = writeln!(s, "stopped: {stop}");
    }
    let fails = report
        .properties
        .iter()
        .filter(|p| p.verdict.fails())
        .count();
    let undecided = report
        .properties
        .iter()
        .filter(|p| matches!(p.verdict, PropertyVerdict::Inconclusive { .. }))
        .count();
    let all = report.properties.len() as u64;
    let _ = match report.outcome() {
        VerifyOutcome::AllHold if all == 1 => writeln!(s, "result: the 1 property holds"),
        VerifyOutcome::AllHold => writeln!(s, "result: all {all} properties hold"),
        VerifyOutcome::SomeFail => {
            writeln!(s, "result: {fails} of {} fail", count(all, "property"))
        }
        VerifyOutcome::Inconclusive => writeln!(
            s,
            "result: inconclusive ({} undecided)",
            count(undecided as u64, "property")
        ),
    };
    s
}

/// The figures of each phase that ran, then the whole run's time and the process's peak
/// memory (z3's included).
fn write_figures(s: &mut String, report: &Report) {
    let st = &report.stats;
    let y = report.symbolic.as_ref();
    let _ = writeln!(s);
    if report.method != Method::Symbolic {
        let _ = writeln!(
            s,
            "{}{} states, {} transitions, depth {}, {:.2} s ({:.0} states/s), {:.1} bytes/state ({} B packed), store {}",
            if report.method == Method::Auto { "explicit: " } else { "" },
            st.states,
            st.transitions,
            st.depth,
            st.seconds,
            st.states_per_second,
            st.bytes_per_state,
            st.state_bytes,
            human_bytes(st.store_bytes),
        );
    }
    if let Some(y) = y {
        let _ = writeln!(
            s,
            "symbolic: {} ({} with approximate values), {} places, {}, {} learned, {} ({:.2} s), invariants in {:.2} s, {:.2} s",
            count(y.components as u64, "component"),
            y.approximate_components,
            y.places,
            count(y.semiflows as u64, "semiflow"),
            count(y.traps as u64, "trap"),
            count(y.solver_calls, "solver call"),
            y.solver_seconds,
            y.invariant_seconds,
            y.seconds,
        );
    }
    let _ = writeln!(
        s,
        "{:.2} s in all, peak memory {}",
        report.seconds,
        report
            .peak_memory_bytes
            .map_or("unknown".into(), human_bytes)
    );
}

/// Why a failing trace of a GenoM model ends as it does (`trace::why`), one line each;
/// empty for other properties and models.
fn why_lines(system: &System, p: &bip_verifier::PropertyResult) -> Vec<String> {
    let PropertyVerdict::Fails { trace: Some(t), .. } = &p.verdict else {
        return Vec::new();
    };
    crate::trace::why::why(system, t)
        .into_iter()
        .map(|(_, line)| line)
        .collect()
}

fn json_report(args: &Args, system: &System, report: &Report) -> Result<String, String> {
    #[derive(serde::Serialize)]
    struct Doc<'a> {
        file: String,
        outcome: VerifyOutcome,
        #[serde(flatten)]
        report: &'a Report,
    }
    let doc = Doc {
        file: args.file.display().to_string(),
        outcome: report.outcome(),
        report,
    };
    let mut doc =
        serde_json::to_value(&doc).map_err(|e| format!("cannot write the JSON report: {e}"))?;
    if let Some(props) = doc["properties"].as_array_mut() {
        for (json, p) in props.iter_mut().zip(&report.properties) {
            let why = why_lines(system, p);
            if !why.is_empty() {
                json["why"] = why.into();
            }
        }
    }
    serde_json::to_string_pretty(&doc)
        .map(|s| s + "\n")
        .map_err(|e| format!("cannot write the JSON report: {e}"))
}

fn junit_report(args: &Args, system: &System, report: &Report) -> String {
    let props = &report.properties;
    let failures = props.iter().filter(|p| p.verdict.fails()).count();
    let errors = props
        .iter()
        .filter(|p| matches!(p.verdict, PropertyVerdict::Inconclusive { .. }))
        .count();
    let suite = format!("bip verify {}", args.file.display());
    let mut s = String::new();
    let _ = writeln!(s, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        s,
        r#"<testsuites name="{}" tests="{}" failures="{failures}" errors="{errors}" time="{:.3}">"#,
        xml(&suite),
        props.len(),
        report.seconds
    );
    let _ = writeln!(
        s,
        r#"  <testsuite name="{}" tests="{}" failures="{failures}" errors="{errors}" skipped="0" time="{:.3}">"#,
        xml(&report.model),
        props.len(),
        report.seconds
    );
    for p in props {
        let _ = write!(
            s,
            r#"    <testcase classname="{}" name="{}" time="{:.3}""#,
            xml(&report.model),
            xml(&p.name),
            report.seconds
        );
        match &p.verdict {
            PropertyVerdict::Holds { .. } => {
                let _ = writeln!(s, "/>");
            }
            PropertyVerdict::Fails { reason, trace } => {
                let mut body = trace
                    .as_ref()
                    .map(|t| t.display(None).to_string())
                    .unwrap_or_default();
                if let (Some(step), Some(t)) = (&p.error_step, trace) {
                    let _ = writeln!(
                        body,
                        "  {}  {step}  (firing it makes the range error)",
                        t.steps.len() + 1
                    );
                }
                let why = why_lines(system, p);
                if !why.is_empty() {
                    body.push_str("why:\n");
                    for line in why {
                        let _ = writeln!(body, "  {line}");
                    }
                }
                let _ = writeln!(
                    s,
                    ">\n      <failure message=\"{}\" type=\"{}\">{}</failure>\n    </testcase>",
                    xml(reason),
                    kind_name(p.kind),
                    xml(&body)
                );
            }
            PropertyVerdict::Inconclusive { reason } => {
                // an undecided property is not a pass: report it as an error, not as skipped
                let _ = writeln!(
                    s,
                    ">\n      <error message=\"{}\" type=\"inconclusive\"/>\n    </testcase>",
                    xml(reason)
                );
            }
        }
    }
    let _ = writeln!(s, "  </testsuite>\n</testsuites>");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn property_names_become_file_names() {
        assert_eq!(file_name("no/way out"), "no_way_out");
        assert_eq!(file_name("DeadlockFree"), "DeadlockFree");
    }

    #[test]
    fn long_and_clashing_names_become_short_distinct_file_names() {
        let long_a = "a".repeat(300);
        let long_b = format!("{}b", "a".repeat(299));
        let mut taken = std::collections::HashSet::new();
        let a = unique_file_name(&long_a, &mut taken);
        let b = unique_file_name(&long_b, &mut taken);
        assert_ne!(a, b);
        for f in [&a, &b] {
            assert!(f.len() <= FILE_NAME_KEPT + 17, "{f}");
            assert!(f.starts_with(&"a".repeat(FILE_NAME_KEPT)), "{f}");
        }
        // the same names give the same files, run after run
        assert_eq!(file_name(&long_a), a);
        let p = unique_file_name("p!", &mut taken);
        let q = unique_file_name("p?", &mut taken);
        let upper = unique_file_name("P_", &mut taken);
        assert_eq!(p, "p_");
        assert!(q.starts_with("p_-") && q.len() == 2 + 17, "{q}");
        assert!(upper.starts_with("P_-") && upper != q, "{upper}");
    }
}
