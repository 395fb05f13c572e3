//! `bip sched FILE`: whether the model's tasks meet their deadlines, from the codels'
//! WCETs and the atoms that stand for tasks: each task's demand per period, its worst
//! response by exact response-time analysis, per CPU; the schedule as a picture. With
//! `--exact` (`exact`), the model explored as a timed model beside the analysis.

mod exact;

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Duration;

use bip_sched::{
    hyperperiod, schedule_svg, show_micros as show, simulate, Assignment, ResponseTime,
};
use bip_verifier::{schedulability, DemandChoice, DemandMethod, Options, Schedulability};

use crate::verify::{parse_memory, parse_seconds, Format};
use crate::{exit, load, memory_guard};

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum AssignArg {
    /// The tasks' own priorities (rate-monotonic on a CPU where none is given).
    Given,
    /// Propose priorities by period, shorter first.
    Rm,
    /// Propose priorities by deadline, shorter first.
    Dm,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum DemandArg {
    /// The most work a run of the model packs into one period (explores the states;
    /// the bound if they exceed the limits).
    Exact,
    /// A bound from the codel automata alone (no exploration).
    Bound,
}

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The model file (RON).
    pub file: PathBuf,
    /// Which priorities to analyse.
    #[arg(long, value_enum, default_value = "given")]
    pub assign: AssignArg,
    /// How each task's work per period is found.
    #[arg(long, value_enum, default_value = "exact")]
    pub demand: DemandArg,
    /// Output format on stdout.
    #[arg(long, value_enum, default_value = "text")]
    pub format: Format,
    /// Also draw the schedule from the critical instant over a hyperperiod as SVG.
    #[arg(long, value_name = "FILE")]
    pub svg: Option<PathBuf>,
    /// Exact demand: use the bound beyond N states.
    #[arg(long, value_name = "N")]
    pub max_states: Option<u64>,
    /// Exact demand: use the bound before using more memory than SIZE.
    #[arg(long, value_name = "SIZE", value_parser = parse_memory)]
    pub max_memory: Option<u64>,
    /// Exact demand: use the bound after SECS seconds of exploration (with `--exact`:
    /// stop exploring, inconclusive).
    #[arg(long, value_name = "SECS", value_parser = parse_seconds)]
    pub timeout: Option<Duration>,
    /// Also explore the model as a timed model (its codels hold its cores for their
    /// durations): each task's exact worst response beside the analysis', and whether a
    /// deadline is missed, which decides the exit code.
    #[arg(long, conflicts_with = "demand")]
    pub exact: bool,
    /// With `--exact`: save each task's worst-case run and each deadline miss as a RON
    /// trace file in DIR, with its sequence chart and schedule.
    #[arg(long, value_name = "DIR", requires = "exact")]
    pub trace_dir: Option<PathBuf>,
}

/// Jobs the picture may draw.
const MAX_DRAWN_JOBS: u64 = 20_000;

pub fn run(args: &Args) -> u8 {
    if args.exact {
        return exact::run(args);
    }
    memory_guard::guard(args.max_memory, "loading the model", exit::ERROR);
    let Some(system) = load::system(&args.file) else {
        return exit::ERROR;
    };
    memory_guard::release();
    if system.is_timed() {
        eprintln!(
            "error: {}: a timed model (`time: Exact`): the response-time analysis assumes preemptive single-core CPUs; `bip sched --exact` explores it, beside the analysis where it applies",
            args.file.display()
        );
        return exit::ERROR;
    }
    let options = Options {
        max_states: args.max_states,
        max_memory: args.max_memory,
        timeout: args.timeout,
        interrupt: Some(crate::interrupt::stop_flag()),
        ..Options::default()
    };
    let assignment = assignment(args.assign);
    let choice = match args.demand {
        DemandArg::Exact => DemandChoice::Exact,
        DemandArg::Bound => DemandChoice::Bound,
    };
    let budgets = "give codels a `wcet` and the model a `tick_ms`, or an atom a `task`";
    let sched = match analysed(&args.file, &system, &options, assignment, choice, budgets) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let title = format!("{}: system `{}`", args.file.display(), system.name);
    match args.format {
        Format::Text => print!("{}", text(&title, &sched, assignment)),
        Format::Json => println!("{}", json(&args.file, &system.name, &sched, assignment)),
    }
    if let Some(path) = &args.svg {
        if let Err(code) = draw(path, &title, &sched, assignment) {
            return code;
        }
    }
    if sched.schedulable() {
        exit::OK
    } else {
        exit::FAILED
    }
}

/// The analysis of the model's task set; `Err` with the exit code once its error is
/// printed, `budgets` saying how to give a model without time budgets some.
fn analysed(
    file: &std::path::Path,
    system: &bip_model::System,
    options: &Options,
    assignment: Assignment,
    choice: DemandChoice,
    budgets: &str,
) -> Result<Schedulability, u8> {
    match schedulability(system, options, assignment, choice) {
        Ok(Some(s)) => Ok(s),
        Ok(None) => {
            eprintln!(
                "error: {}: no time budgets to analyse: {budgets} (docs/model.md, \"Time budgets\")",
                file.display()
            );
            Err(exit::ERROR)
        }
        Err(e) => {
            eprintln!("error: {}: {e}", file.display());
            Err(exit::ERROR)
        }
    }
}

/// A response time as the JSON reports write it.
fn response_json(r: ResponseTime) -> serde_json::Value {
    match r {
        ResponseTime::Exact(us) => serde_json::json!({"us": us}),
        ResponseTime::Unbounded => serde_json::json!({"unbounded": true}),
        ResponseTime::AtLeast(us) => serde_json::json!({"at_least_us": us}),
    }
}

fn assignment(arg: AssignArg) -> Assignment {
    match arg {
        AssignArg::Given => Assignment::Given,
        AssignArg::Rm => Assignment::RateMonotonic,
        AssignArg::Dm => Assignment::DeadlineMonotonic,
    }
}

fn demand_line(sched: &Schedulability) -> String {
    match &sched.method {
        DemandMethod::Exact {
            states,
            transitions,
        } => format!(
            "exact: the most a run packs into a period ({states} states, {transitions} transitions explored)"
        ),
        DemandMethod::Bound { why } => {
            format!("bounded from the codel automata ({why})")
        }
        DemandMethod::Declared => "declared: each task's WCET per period".into(),
    }
}

fn response_text(r: ResponseTime) -> String {
    match r {
        ResponseTime::Exact(us) => show(us),
        ResponseTime::Unbounded => "unbounded".into(),
        ResponseTime::AtLeast(us) => format!("≥ {}", show(us)),
    }
}

fn text(title: &str, sched: &Schedulability, assignment: Assignment) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "{title}");
    let _ = writeln!(out, "  demand per period: {}", demand_line(sched));
    let set = &sched.set;
    let rows: Vec<Vec<String>> = (0..set.tasks.len())
        .map(|i| {
            let t = &set.tasks[i];
            let a = sched.analysis.as_ref().map(|a| a.tasks[i]);
            vec![
                t.name.clone(),
                show(t.period),
                sched.demands[i].map_or("unbounded".into(), show),
                t.priority.map_or("-".into(), |p| p.to_string()),
                a.map_or("-".into(), |a| (a.rank + 1).to_string()),
                a.map_or("unbounded".into(), |a| response_text(a.response)),
                show(t.deadline),
                a.and_then(|a| a.slack(t.deadline))
                    .map_or("MISSES".into(), show),
            ]
        })
        .collect();
    let header = [
        "task", "period", "demand", "priority", "rank", "response", "deadline", "slack",
    ];
    let line = table_line(&header, &rows);
    for (cpu, name) in sched.cpus.iter().enumerate() {
        let on_cpu: Vec<usize> = (0..set.tasks.len())
            .filter(|&i| set.tasks[i].cpu == cpu)
            .collect();
        match &sched.analysis {
            Some(a) => {
                let c = &a.cpus[cpu];
                let _ = writeln!(
                    out,
                    "  CPU {name}: utilisation {:.3} (Liu-Layland bound for {} {}: {:.3})",
                    c.utilisation,
                    on_cpu.len(),
                    if on_cpu.len() == 1 { "task" } else { "tasks" },
                    c.liu_layland
                );
            }
            None => {
                let _ = writeln!(out, "  CPU {name}:");
            }
        }
        let _ = writeln!(out, "{}", line(&header.map(String::from)));
        let mut order = on_cpu.clone();
        if let Some(a) = &sched.analysis {
            order.sort_by_key(|&i| a.tasks[i].rank);
        }
        for i in order {
            let _ = writeln!(out, "{}", line(&rows[i]));
        }
    }
    for t in sched.tasks.iter().filter(|t| !t.unbudgeted.is_empty()) {
        let _ = writeln!(
            out,
            "  note: {} counts these codels as taking no time (no wcet): {}",
            t.name,
            t.unbudgeted.join(", ")
        );
    }
    if !sched.aperiodic.is_empty() {
        let _ = writeln!(
            out,
            "  note: left out, without a period and with no wcet on their codels (they take no time here): {}",
            sched.aperiodic.join(", ")
        );
    }
    if assignment != Assignment::Given {
        let kind = if assignment == Assignment::RateMonotonic {
            "rate-monotonic"
        } else {
            "deadline-monotonic"
        };
        let _ = writeln!(
            out,
            "  proposed priorities ({kind}): {}",
            proposed(sched)
                .iter()
                .map(|(t, p)| format!("{t}: {p}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let _ = writeln!(out, "result: {}", sched.verdict());
    out
}

/// A table's line maker: the first column left-aligned, the others right-aligned, each
/// as wide as its widest cell or header.
fn table_line(header: &[&str], rows: &[Vec<String>]) -> impl Fn(&[String]) -> String {
    let widths: Vec<usize> = (0..header.len())
        .map(|c| {
            rows.iter()
                .map(|r| r[c].chars().count())
                .chain([header[c].len()])
                .max()
                .unwrap_or(0)
        })
        .collect();
    move |cells: &[String]| {
        let mut l = String::from("    ");
        for (c, cell) in cells.iter().enumerate() {
            let pad = widths[c].saturating_sub(cell.chars().count());
            if c == 0 {
                l.push_str(cell);
                l.push_str(&" ".repeat(pad + 2));
            } else {
                l.push_str(&" ".repeat(pad));
                l.push_str(cell);
                l.push_str("  ");
            }
        }
        l.trim_end().to_string()
    }
}

/// Priorities as numbers for the analysed order: per CPU, the most urgent gets the
/// number of its CPU's tasks, the least urgent 1.
fn proposed(sched: &Schedulability) -> Vec<(String, usize)> {
    let Some(a) = &sched.analysis else {
        return Vec::new();
    };
    a.cpus
        .iter()
        .flat_map(|c| {
            let n = c.order.len();
            c.order
                .iter()
                .enumerate()
                .map(move |(rank, &i)| (sched.set.tasks[i].name.clone(), n - rank))
        })
        .collect()
}

fn json(
    file: &std::path::Path,
    system: &str,
    sched: &Schedulability,
    assignment: Assignment,
) -> String {
    use serde_json::{json, Value};
    let set = &sched.set;
    let demand = match &sched.method {
        DemandMethod::Exact {
            states,
            transitions,
        } => json!({"method": "exact", "states": states, "transitions": transitions}),
        DemandMethod::Bound { why } => json!({"method": "bound", "why": why}),
        DemandMethod::Declared => json!({"method": "declared"}),
    };
    let cpus: Vec<Value> = sched
        .cpus
        .iter()
        .enumerate()
        .map(|(cpu, name)| {
            let tasks: Vec<Value> = (0..set.tasks.len())
                .filter(|&i| set.tasks[i].cpu == cpu)
                .map(|i| {
                    let t = &set.tasks[i];
                    let a = sched.analysis.as_ref().map(|a| a.tasks[i]);
                    json!({
                        "name": t.name,
                        "period_us": t.period,
                        "demand_us": sched.demands[i],
                        "priority": t.priority,
                        "rank": a.map(|a| a.rank),
                        "response": a.map(|a| response_json(a.response)),
                        "deadline_us": t.deadline,
                        "slack_us": a.and_then(|a| a.slack(t.deadline)),
                        "unbudgeted_codels": sched.tasks[i].unbudgeted,
                    })
                })
                .collect();
            let load = sched.analysis.as_ref().map(|a| &a.cpus[cpu]);
            json!({
                "name": name,
                "utilisation": load.map(|c| c.utilisation),
                "liu_layland_bound": load.map(|c| c.liu_layland),
                "tasks": tasks,
            })
        })
        .collect();
    let doc = json!({
        "file": file.display().to_string(),
        "system": system,
        "assignment": format!("{assignment:?}"),
        "demand": demand,
        "cpus": cpus,
        "aperiodic_left_out": sched.aperiodic,
        "schedulable": sched.schedulable(),
        "result": sched.verdict(),
    });
    serde_json::to_string_pretty(&doc).unwrap_or_default()
}

/// Draws the analysis' schedule into `path`; on failure the error is printed and the
/// exit code returned.
fn draw(
    path: &std::path::Path,
    title: &str,
    sched: &Schedulability,
    assignment: Assignment,
) -> Result<(), u8> {
    drawn(path, title, sched, assignment).map_err(|why| {
        eprintln!(
            "error: cannot draw the schedule into {}: {why}",
            path.display()
        );
        exit::ERROR
    })
}

fn drawn(
    path: &std::path::Path,
    title: &str,
    sched: &Schedulability,
    assignment: Assignment,
) -> Result<(), String> {
    let set = &sched.set;
    // a hyperperiod, or as many periods of the slowest task as the picture can hold
    let slowest = set.tasks.iter().map(|t| t.period).max().unwrap_or(1);
    let horizon = hyperperiod(set)
        .filter(|&h| set.tasks.iter().map(|t| h / t.period).sum::<u64>() <= MAX_DRAWN_JOBS)
        .unwrap_or(slowest);
    let schedule = simulate(set, assignment, horizon, MAX_DRAWN_JOBS).map_err(|e| e.to_string())?;
    std::fs::write(path, schedule_svg(set, assignment, &schedule, title)).map_err(|e| e.to_string())
}
