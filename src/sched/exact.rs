//! `bip sched --exact`: the model explored as a timed model (its codels hold its CPUs'
//! cores for their durations, docs/model.md "Timed semantics"), each task's exact worst
//! response beside the response-time analysis where the analysis applies, and the
//! analysis' pessimism; the exit code is the exploration's answer.

use std::fmt::Write as _;
use std::path::PathBuf;

use bip_lang::source::ConstValue;
use bip_lang::syntax::{CpuDef, Policy, Preemption};
use bip_model::System;
use bip_sched::{show_micros as show, ResponseTime};
use bip_verifier::{
    CheckKind, DemandChoice, Method, Options, PropertyResult, PropertyVerdict, Report,
    Schedulability, Stop,
};
use serde_json::{json, Value};

use super::{draw, response_text, Args};
use crate::verify::{save_traces, Format};
use crate::{exit, interrupt, memory_guard, report};

/// Why the response-time analysis (fixed priorities on one preemptive core) does not
/// describe a CPU, in a word; `None` where it does.
fn not_applicable(cpu: &CpuDef, tasks_on_it: usize) -> Option<&'static str> {
    let cores = match cpu.cores.as_ref().map(|c| &c.value) {
        None => Some(1),
        Some(ConstValue::Int(n)) => Some(*n),
        Some(_) => None,
    };
    if cores != Some(1) {
        return Some("multi-core");
    }
    if cpu.policy() == Policy::Edf {
        return Some("EDF");
    }
    // a task alone on its core is never preempted, whatever the CPU allows
    if cpu.preemption() != Preemption::Preemptive && tasks_on_it > 1 {
        return Some("non-preemptive");
    }
    None
}

/// One task's row.
struct Row {
    name: String,
    cpu: usize,
    period: u64,
    deadline: u64,
    /// The analysis' response, or why it does not apply.
    analysis: Result<ResponseTime, &'static str>,
    /// The exact worst response (`Ok`), or a lower bound (`Err(Some)`), or none.
    exact: Result<u64, Option<u64>>,
    /// `Some(true)` if a job misses its deadline, `None` if undecided.
    misses: Option<bool>,
    /// Why the exact figure is not given, when it is not.
    why: Option<String>,
}

/// Analysis − exact: a figure where both are, or where the exploration stopped with a
/// run already past the analysis' response, a bound (the analysis is below a run).
#[derive(Clone, Copy)]
enum Pessimism {
    Exact(i64),
    AtMost(i64),
}

impl Row {
    fn pessimism(&self) -> Option<Pessimism> {
        match (self.analysis, self.exact) {
            (Ok(ResponseTime::Exact(a)), Ok(e)) => Some(Pessimism::Exact(a as i64 - e as i64)),
            (Ok(ResponseTime::Exact(a)), Err(Some(e))) if e > a => {
                Some(Pessimism::AtMost(a as i64 - e as i64))
            }
            _ => None,
        }
    }
}

pub fn run(args: &Args) -> u8 {
    memory_guard::guard(args.max_memory, "loading the model", exit::ERROR);
    let loaded = bip_lang::load_file_timed(&args.file).and_then(|system| {
        let text = bip_lang::read_model_file(&args.file)?;
        let def = bip_lang::parse_str(&args.file.display().to_string(), &text)?;
        Ok((system, def.cpus))
    });
    memory_guard::release();
    let (system, cpu_defs) = match loaded {
        Ok(loaded) => loaded,
        Err(e) => {
            report::load_error(&e);
            return exit::ERROR;
        }
    };
    if let Some(dir) = &args.trace_dir {
        if let Err(e) = std::fs::create_dir_all(dir) {
            eprintln!(
                "error: cannot create the trace directory {}: {e}",
                dir.display()
            );
            return exit::ERROR;
        }
    }
    let options = Options {
        max_states: args.max_states,
        max_memory: args.max_memory,
        timeout: args.timeout,
        interrupt: Some(interrupt::stop_flag()),
        ..Options::default()
    };
    let assignment = super::assignment(args.assign);
    // the analysis of the timed model's task set: its demands bounded from the codel
    // automata (an exact demand counts the work between two ticks of an untimed model)
    let budgets = "give codels a `wcet` and the model a `tick_ms`";
    let sched = match super::analysed(
        &args.file,
        &system,
        &options,
        assignment,
        DemandChoice::Bound,
        budgets,
    ) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let report = match bip_verifier::verify(&system, Method::Explicit, &options, &|_| {}) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {}: {e}", args.file.display());
            return exit::ERROR;
        }
    };
    let rows = rows(&sched, &cpu_defs, &report);
    let mut saved = Vec::new();
    let mut unsaved = None;
    if let Some(dir) = &args.trace_dir {
        // the worst cases and the misses
        let wanted = Report {
            properties: report
                .properties
                .iter()
                .filter(|p| {
                    p.kind == CheckKind::WorstResponse
                        || (p.kind == CheckKind::Invariant
                            && rows.iter().any(|r| is_deadline_of(p, &r.name)))
                })
                .cloned()
                .collect(),
            ..report.clone()
        };
        unsaved = save_traces(dir, &wanted, &mut saved)
            .and_then(|()| crate::trace::save_charts(&system, &wanted, &saved))
            .err();
    }
    let title = format!("{}: system `{}`", args.file.display(), system.name);
    let verdict = verdict(&rows, &report);
    match args.format {
        Format::Text => print!(
            "{}",
            text(&title, &sched, &cpu_defs, &rows, &report, &verdict, &saved)
        ),
        Format::Json => println!(
            "{}",
            json_doc(args, &system, &sched, &rows, &report, &verdict, &saved)
        ),
    }
    if let Some(path) = &args.svg {
        if let Err(code) = draw(path, &title, &sched, assignment) {
            return code;
        }
    }
    if let Some(why) = unsaved {
        eprintln!("error: {why}");
        return exit::ERROR;
    }
    match verdict.schedulable {
        Some(true) => exit::OK,
        Some(false) => exit::FAILED,
        None => exit::INCONCLUSIVE,
    }
}

/// The generated deadline invariant of task `task` (`m.t meets its D deadline`).
fn is_deadline_of(p: &PropertyResult, task: &str) -> bool {
    p.kind == CheckKind::Invariant
        && p.name
            .strip_prefix(task)
            .and_then(|rest| rest.strip_prefix(" meets its "))
            .is_some_and(|rest| rest.ends_with(" deadline"))
}

fn rows(sched: &Schedulability, cpu_defs: &[CpuDef], report: &Report) -> Vec<Row> {
    let set = &sched.set;
    (0..set.tasks.len())
        .map(|i| {
            let t = &set.tasks[i];
            let on_cpu = set.tasks.iter().filter(|u| u.cpu == t.cpu).count();
            // a model without CPUs has one, named by the analysis
            let named = CpuDef::default();
            let cpu = cpu_defs.get(t.cpu).unwrap_or(&named);
            let analysis = match not_applicable(cpu, on_cpu) {
                Some(why) => Err(why),
                None => Ok(sched
                    .analysis
                    .as_ref()
                    .map_or(ResponseTime::Unbounded, |a| a.tasks[i].response)),
            };
            let worst_name = format!("{} worst response", t.name);
            let worst = report
                .properties
                .iter()
                .find(|p| p.kind == CheckKind::WorstResponse && p.name == worst_name);
            let deadline = report
                .properties
                .iter()
                .find(|p| is_deadline_of(p, &t.name));
            let (exact, why) = match worst {
                Some(p) => match &p.verdict {
                    PropertyVerdict::Holds { .. } => (p.worst_us.ok_or(None), p.note.clone()),
                    PropertyVerdict::Inconclusive { reason } => {
                        (Err(p.worst_us), Some(reason.clone()))
                    }
                    PropertyVerdict::Fails { reason, .. } => (Err(None), Some(reason.clone())),
                },
                None => (Err(None), Some("the task runs no codel".into())),
            };
            let misses = deadline.and_then(|d| match &d.verdict {
                PropertyVerdict::Holds { .. } => Some(false),
                PropertyVerdict::Fails { .. } => Some(true),
                PropertyVerdict::Inconclusive { .. } => None,
            });
            Row {
                name: t.name.clone(),
                cpu: t.cpu,
                period: t.period,
                deadline: t.deadline,
                analysis,
                exact,
                misses,
                why,
            }
        })
        .collect()
}

/// The exploration's answer.
struct Verdict {
    /// `None`: undecided (a limit was reached, or time can stop).
    schedulable: Option<bool>,
    words: String,
}

fn verdict(rows: &[Row], report: &Report) -> Verdict {
    let missing: Vec<String> = rows
        .iter()
        .filter(|r| r.misses == Some(true))
        .map(|r| {
            let worst = match r.exact {
                Ok(us) => format!("worst response {}", show(us)),
                Err(Some(us)) => format!("worst response at least {}", show(us)),
                Err(None) => "worst response not known".into(),
            };
            format!(
                "{} misses its {} deadline ({worst})",
                r.name,
                show(r.deadline)
            )
        })
        .collect();
    if !missing.is_empty() {
        return Verdict {
            schedulable: Some(false),
            words: format!("not schedulable: {}", missing.join("; ")),
        };
    }
    if rows.iter().all(|r| r.misses == Some(false)) {
        return Verdict {
            schedulable: Some(true),
            words: "schedulable: every task meets its deadline in every run".into(),
        };
    }
    let why = match &report.stopped {
        Some(stop) => stop.to_string(),
        None => "a deadline is undecided (time can stop, TimeProgress fails)".into(),
    };
    Verdict {
        schedulable: None,
        words: format!("inconclusive: {why}; no miss found in the states explored"),
    }
}

fn exact_text(r: &Row) -> String {
    let figure = match r.exact {
        Ok(us) => show(us),
        Err(Some(us)) => format!("≥ {}", show(us)),
        Err(None) => "-".into(),
    };
    match (r.misses, r.exact) {
        (Some(true), Err(None)) => "misses".into(),
        (Some(true), _) => format!("{figure} misses"),
        _ => figure,
    }
}

fn analysis_text(r: &Row) -> String {
    match r.analysis {
        Ok(ResponseTime::Exact(us)) if us > r.deadline => format!("{} misses", show(us)),
        Ok(a) => response_text(a),
        Err(why) => format!("n/a ({why})"),
    }
}

fn pessimism_text(r: &Row) -> String {
    let signed = |p: i64| match p {
        p if p < 0 => format!("-{}", show(p.unsigned_abs())),
        p => show(p as u64),
    };
    match r.pessimism() {
        Some(Pessimism::Exact(p)) => signed(p),
        Some(Pessimism::AtMost(p)) => format!("≤ {}", signed(p)),
        None => "-".into(),
    }
}

fn cpu_line(name: &str, cpu: Option<&CpuDef>) -> String {
    let Some(cpu) = cpu else {
        return format!("CPU {name}");
    };
    let cores = match cpu.cores.as_ref().map(|c| &c.value) {
        None | Some(ConstValue::Int(1)) => "1 core".to_string(),
        Some(n) => format!("{n} cores"),
    };
    let policy = match cpu.policy() {
        Policy::FixedPriority => "fixed priorities",
        Policy::Edf => "EDF",
    };
    let preemption = match cpu.preemption() {
        Preemption::Job => "jobs run to their end",
        Preemption::Codel => "preemption between codels",
        Preemption::Preemptive => "preemptive",
    };
    format!("CPU {name}: {cores}, {policy}, {preemption}")
}

fn text(
    title: &str,
    sched: &Schedulability,
    cpu_defs: &[CpuDef],
    rows: &[Row],
    report: &Report,
    verdict: &Verdict,
    saved: &[(String, PathBuf)],
) -> String {
    let mut out = String::new();
    let st = &report.stats;
    let _ = writeln!(out, "{title}");
    let _ = writeln!(
        out,
        "  exact: explored as a timed model ({} states, {} transitions{})",
        st.states,
        st.transitions,
        if st.complete { "" } else { ", stopped early" }
    );
    let _ = writeln!(
        out,
        "  analysis: fixed-priority preemptive response times, demands bounded from the codel automata"
    );
    let header = [
        "task",
        "period",
        "deadline",
        "analysis",
        "exact",
        "pessimism",
    ];
    let cells: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                r.name.clone(),
                show(r.period),
                show(r.deadline),
                analysis_text(r),
                exact_text(r),
                pessimism_text(r),
            ]
        })
        .collect();
    let line = super::table_line(&header, &cells);
    for (cpu, name) in sched.cpus.iter().enumerate() {
        let _ = writeln!(out, "  {}", cpu_line(name, cpu_defs.get(cpu)));
        let _ = writeln!(out, "{}", line(&header.map(String::from)));
        for (_, c) in rows.iter().zip(&cells).filter(|(r, _)| r.cpu == cpu) {
            let _ = writeln!(out, "{}", line(c));
        }
    }
    // a stopped run's figures are all bounds for the same reason, said once below
    for r in rows {
        if let (Err(_), Some(why)) = (r.exact, &r.why) {
            if report.stopped.is_none() || why.starts_with("at least 2 periods") {
                let _ = writeln!(out, "  note: {}: {why}", r.name);
            }
        }
    }
    for r in rows {
        if let Some(Pessimism::Exact(p) | Pessimism::AtMost(p)) = r.pessimism() {
            if p < 0 {
                let _ = writeln!(
                    out,
                    "  note: {}: a run of the model takes longer than the analysis' response, \
                     which does not count a wait for a codel lock held on another CPU; \
                     `--trace-dir` saves the run",
                    r.name
                );
            }
        }
    }
    if let Some(stop) = &report.stopped {
        let _ = writeln!(out, "  note: the exploration stopped: {stop}");
    }
    for (name, path) in saved {
        let _ = writeln!(out, "  {name}: saved as {}", path.display());
    }
    let _ = writeln!(out, "result: {}", verdict.words);
    out
}

fn json_doc(
    args: &Args,
    system: &System,
    sched: &Schedulability,
    rows: &[Row],
    report: &Report,
    verdict: &Verdict,
    saved: &[(String, PathBuf)],
) -> String {
    let response = super::response_json;
    let tasks: Vec<Value> = rows
        .iter()
        .map(|r| {
            let trace = |name: String| {
                saved
                    .iter()
                    .find(|(n, _)| *n == name)
                    .map(|(_, p)| p.display().to_string())
            };
            json!({
                "name": r.name,
                "cpu": sched.cpus[r.cpu],
                "period_us": r.period,
                "deadline_us": r.deadline,
                "analysis": match r.analysis {
                    Ok(a) => response(a),
                    Err(why) => json!({"not_applicable": why}),
                },
                "exact": match r.exact {
                    Ok(us) => json!({"us": us}),
                    Err(Some(us)) => json!({"at_least_us": us, "why": r.why}),
                    Err(None) => json!({"unknown": r.why}),
                },
                "misses": r.misses,
                "pessimism_us": match r.pessimism() {
                    Some(Pessimism::Exact(p)) => json!(p),
                    _ => Value::Null,
                },
                "pessimism_at_most_us": match r.pessimism() {
                    Some(Pessimism::AtMost(p)) => json!(p),
                    _ => Value::Null,
                },
                "worst_trace": trace(format!("{} worst response", r.name)),
            })
        })
        .collect();
    let doc = json!({
        "file": args.file.display().to_string(),
        "system": system.name,
        "exploration": {
            "states": report.stats.states,
            "transitions": report.stats.transitions,
            "complete": report.stats.complete,
            "stopped": report.stopped.as_ref().map(Stop::to_string),
            "seconds": report.seconds,
        },
        "analysis_demand": "bound",
        "tasks": tasks,
        "miss_traces": saved
            .iter()
            .filter(|(n, _)| !n.ends_with(" worst response"))
            .map(|(n, p)| json!({"property": n, "trace": p.display().to_string()}))
            .collect::<Vec<_>>(),
        "schedulable": verdict.schedulable,
        "result": verdict.words,
    });
    serde_json::to_string_pretty(&doc).unwrap_or_default()
}
