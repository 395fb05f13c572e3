//! `bip trace show FILE TRACE`: a trace (a counterexample, a witness, a recording) in the
//! user's terms, as text and, with `--svg`, as a sequence chart; `bip verify --trace-dir`
//! draws the same chart beside each trace it saves. `--timeline` (and `bip simulate
//! --svg`) draws a run along its steps, one lane per activity; `--schedule` draws a timed
//! model's run along time, one lane per core and per task, which `bip verify
//! --trace-dir` also draws beside each trace of a timed model.

mod schedule;
pub(crate) mod timed;
mod timeline;
pub(crate) mod view;
pub(crate) mod why;

use std::path::{Path, PathBuf};

use bip_model::{State, System, Trace, Verdict};
use bip_picture::chart::{Chart, Mark, Note, Row, Step};

use crate::{exit, load};

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub action: Action,
}

#[derive(clap::Subcommand, Debug)]
pub enum Action {
    /// Print a trace in the model's terms (modules, services, codels, the user's
    /// components), and draw it as a sequence chart with --svg.
    Show(ShowArgs),
}

#[derive(clap::Args, Debug)]
pub struct ShowArgs {
    /// The model file (RON) the trace is of.
    pub file: PathBuf,
    /// The trace file (RON), as `bip verify --trace-dir` or `bip simulate --trace` write it.
    pub trace: PathBuf,
    /// Also draw the trace as a sequence chart into FILE (SVG).
    #[arg(long, value_name = "FILE")]
    pub svg: Option<PathBuf>,
    /// Also draw the trace as a timeline into FILE (SVG): one lane per activity.
    #[arg(long, value_name = "FILE")]
    pub timeline: Option<PathBuf>,
    /// Also draw a timed model's trace as a schedule into FILE (SVG): time across, one
    /// lane per core and per task.
    #[arg(long, value_name = "FILE")]
    pub schedule: Option<PathBuf>,
    /// Show the GenoM expansion's bookkeeping variables (`req`, `paused`, the clock) too.
    #[arg(long)]
    pub all_variables: bool,
}

pub fn run(args: &Args) -> u8 {
    match &args.action {
        Action::Show(show) => run_show(show),
    }
}

fn run_show(args: &ShowArgs) -> u8 {
    let Some((system, trace)) = model_and_trace(&args.file, &args.trace) else {
        return exit::ERROR;
    };
    let user = match view::user_trace(&system, &trace, args.all_variables) {
        Ok(u) => u,
        Err(e) => {
            eprintln!("error: {}: {e}", args.trace.display());
            return exit::ERROR;
        }
    };
    print!("{}", text(&system, &trace, &user));
    if let Some(path) = &args.svg {
        let svg = bip_picture::chart::to_svg(&chart(&system, &trace, &user));
        if let Err(e) = std::fs::write(path, svg) {
            eprintln!("error: cannot write {}: {e}", path.display());
            return exit::ERROR;
        }
    }
    if let Some(path) = &args.timeline {
        if let Err(e) = write_timeline(&system, &trace, path) {
            eprintln!("error: {e}");
            return exit::ERROR;
        }
    }
    if let Some(path) = &args.schedule {
        if let Err(e) = write_schedule(&system, &trace, path) {
            eprintln!("error: {e}");
            return exit::ERROR;
        }
    }
    exit::OK
}

fn write_schedule(system: &System, trace: &Trace, svg: &Path) -> Result<(), String> {
    let picture = bip_picture::timeline::to_svg(&schedule::schedule(system, trace)?);
    std::fs::write(svg, picture).map_err(|e| format!("cannot write {}: {e}", svg.display()))
}

/// Draws the run saved in `trace` as a timeline into `svg` (`bip simulate --svg`).
pub fn save_timeline(system: &System, trace: &Path, svg: &Path) -> Result<(), String> {
    write_timeline(system, &read(trace)?, svg)
}

fn write_timeline(system: &System, trace: &Trace, svg: &Path) -> Result<(), String> {
    let picture = bip_picture::timeline::to_svg(&timeline::timeline(system, trace)?);
    std::fs::write(svg, picture).map_err(|e| format!("cannot write {}: {e}", svg.display()))
}

/// The trace in `trace_file` and the model in `file` it runs, loaded as the trace says:
/// as a timed model for a run of the timed semantics (`timed: true`, which `bip sched
/// --exact` and `bip simulate --codel-time` write for a model without `time: Exact`),
/// as written otherwise. `None` once the diagnostic is printed; a trace of another system
/// gets a warning. Every command that reads a trace against a model reads it here.
pub(crate) fn model_and_trace(file: &Path, trace_file: &Path) -> Option<(System, Trace)> {
    let trace = read(trace_file).map_err(|e| eprintln!("error: {e}")).ok()?;
    let system = if trace.timed {
        load::timed_system(file)?
    } else {
        load::system(file)?
    };
    if trace.system != system.name {
        eprintln!(
            "warning: the trace is of system `{}`, the model is `{}`",
            trace.system, system.name
        );
    }
    Some((system, trace))
}

pub(crate) fn read(path: &Path) -> Result<Trace, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    bip_lang::trace_file::from_ron(&text)
        .map_err(|e| format!("{}: not a trace: {e}", path.display()))
}

/// The trace as a sequence chart (SVG), as `bip trace show --svg` draws it.
pub(crate) fn chart_svg(system: &System, trace: &Trace) -> Result<String, String> {
    let user = view::user_trace(system, trace, false)?;
    Ok(bip_picture::chart::to_svg(&chart(system, trace, &user)))
}

/// Beside each trace `bip verify` saved (`NAME.trace.ron`), its sequence chart
/// (`NAME.svg`) and, in a timed model, its schedule (`NAME.schedule.svg`).
pub fn save_charts(
    system: &System,
    report: &bip_verifier::Report,
    saved: &[(String, PathBuf)],
) -> Result<(), String> {
    for (name, path) in saved {
        let Some(trace) = report
            .properties
            .iter()
            .find(|p| &p.name == name)
            .and_then(|p| p.verdict.trace())
        else {
            continue;
        };
        let user = view::user_trace(system, trace, false)?;
        let svg = bip_picture::chart::to_svg(&chart(system, trace, &user));
        let file = path.to_string_lossy();
        let stem = file.strip_suffix(".trace.ron").unwrap_or(&file);
        let beside = PathBuf::from(format!("{stem}.svg"));
        std::fs::write(&beside, svg)
            .map_err(|e| format!("cannot write the chart {}: {e}", beside.display()))?;
        if system.is_timed() {
            write_schedule(
                system,
                trace,
                &PathBuf::from(format!("{stem}.schedule.svg")),
            )?;
        }
    }
    Ok(())
}

/// The trace as text: one line per step, its participants and its changes.
/// A timed model's trace as `bip trace show` prints it, in the user's names (the task
/// atoms' steps and variables read as dispatches, starts and job ends); `None` for an
/// untimed model, whose traces print as the model's.
pub(crate) fn timed_text(system: &System, trace: &Trace, all: bool) -> Option<String> {
    system.genom.as_ref()?.time_unit_us?;
    let user = view::user_trace(system, trace, all).ok()?;
    Some(text(system, trace, &user))
}

fn text(system: &System, trace: &Trace, user: &view::UserTrace) -> String {
    use std::fmt::Write;
    let n = user.steps.len();
    let mut s = format!(
        "{} after {n} step{} ({})\n",
        view::verdict(trace),
        if n == 1 { "" } else { "s" },
        system.name
    );
    let width = user
        .steps
        .iter()
        .map(|st| st.label.chars().count())
        .max()
        .unwrap_or(0)
        .min(48);
    let digits = n.to_string().len();
    for step in &user.steps {
        if trace.loop_start.map(|stem| stem + 1) == Some(step.number) {
            let _ = writeln!(
                s,
                "  {:>digits$}  ┌ the cycle: the steps below repeat forever",
                ""
            );
        }
        let mut line = format!("  {:>digits$}  {:<width$}", step.number, step.label);
        let who: Vec<&str> = step
            .lifelines
            .iter()
            .map(|&k| user.lifelines[k].as_str())
            .collect();
        if !who.is_empty() && matches!(step.kind, view::Kind::Step) {
            let _ = write!(line, "  [{}]", who.join(", "));
        }
        if !step.changes.is_empty() {
            let _ = write!(line, "  {}", step.changes.join(", "));
        }
        let _ = writeln!(s, "{}", line.trim_end());
    }
    if let Some(note) = end_note(system, trace, &user.last) {
        let _ = writeln!(s, "{}", note.title);
        for line in &note.lines {
            let _ = writeln!(s, "  {line}");
        }
    }
    s
}

fn chart(system: &System, trace: &Trace, user: &view::UserTrace) -> Chart {
    let n = user.steps.len();
    let last_mark = match trace.verdict {
        Verdict::Violation(_) => Mark::Failing,
        Verdict::Witness(_) => Mark::Reached,
        _ => Mark::Plain,
    };
    let mut end = end_note(system, trace, &user.last);
    if let Some(note) = end.as_mut() {
        note.lifelines = held(system, trace, user);
    }
    // the lifelines drawn: those that take part in a step or that the end is about
    let mut shown = vec![false; user.lifelines.len()];
    for step in &user.steps {
        for &k in &step.lifelines {
            shown[k] = true;
        }
    }
    if let Some(note) = &end {
        for &k in &note.lifelines {
            shown[k] = true;
        }
        for (k, name) in user.lifelines.iter().enumerate() {
            if std::iter::once(&note.title)
                .chain(&note.lines)
                .any(|l| crate::names::mentions(l, name))
            {
                shown[k] = true;
            }
        }
    }
    let mut index = vec![0; user.lifelines.len()];
    let mut lifelines = Vec::new();
    let mut idle = Vec::new();
    for (k, name) in user.lifelines.iter().enumerate() {
        if shown[k] {
            index[k] = lifelines.len();
            lifelines.push(name.clone());
        } else {
            idle.push(name.clone());
        }
    }
    if let Some(note) = end.as_mut() {
        note.lifelines = note.lifelines.iter().map(|&k| index[k]).collect();
    }
    let rows = user
        .steps
        .iter()
        .map(|st| match st.kind {
            view::Kind::Tick => Row::Tick {
                number: st.number,
                label: format!("{}  {}", st.number, st.label),
            },
            view::Kind::Step => Row::Step(Step {
                number: st.number,
                label: st.label.clone(),
                lifelines: st.lifelines.iter().map(|&k| index[k]).collect(),
                notes: st.changes.clone(),
                mark: if st.number == n {
                    last_mark
                } else {
                    Mark::Plain
                },
            }),
        })
        .collect::<Vec<_>>();
    // the loop runs from the step after the stem's `loop_start` steps
    let loop_from = trace.loop_start.and_then(|stem| {
        rows.iter().position(|row| match row {
            Row::Tick { number, .. } => *number == stem + 1,
            Row::Step(step) => step.number == stem + 1,
        })
    });
    Chart {
        title: format!(
            "{}: {} after {n} step{}",
            system.name,
            view::verdict(trace),
            if n == 1 { "" } else { "s" }
        ),
        lifelines,
        rows,
        loop_from,
        end,
        idle,
    }
}

/// At a deadlock of a GenoM layer, the lifelines of the modules whose codels are held.
fn held(system: &System, trace: &Trace, user: &view::UserTrace) -> Vec<usize> {
    let (Verdict::Deadlock, Some(map)) = (&trace.verdict, &system.genom) else {
        return Vec::new();
    };
    let Ok(stuck) = map.stuck(system, &user.last) else {
        return Vec::new();
    };
    let mut out: Vec<usize> = stuck
        .iter()
        .filter_map(|st| user.lifelines.iter().position(|l| l == st.module))
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// What the end of the trace shows: the deadlock and why, the failed or witnessed
/// property, the range error.
fn end_note(system: &System, trace: &Trace, last: &State) -> Option<Note> {
    match &trace.verdict {
        Verdict::Deadlock => {
            let mut lines = why_lines(system, trace);
            if lines.is_empty() {
                lines.push(
                    "no step of the system itself can be taken, now or after time passes".into(),
                );
            }
            Some(Note {
                title: "deadlock: the system can make no progress".into(),
                lines,
                mark: Mark::Failing,
                lifelines: Vec::new(),
            })
        }
        Verdict::Violation(p) => Some(Note {
            title: format!("{p} fails after the last step"),
            lines: [property_text(system, p, last), why_lines(system, trace)].concat(),
            mark: Mark::Failing,
            lifelines: Vec::new(),
        }),
        Verdict::Witness(p) => Some(Note {
            title: format!("{p} is reached after the last step"),
            lines: property_text(system, p, last),
            mark: Mark::Reached,
            lifelines: Vec::new(),
        }),
        Verdict::RangeError(m) => Some(Note {
            title: "range error".into(),
            lines: vec![m.clone()],
            mark: Mark::Failing,
            lifelines: Vec::new(),
        }),
        Verdict::None => None,
    }
}

/// Why the trace ends as it does (`trace::why`), indented by depth.
fn why_lines(system: &System, trace: &Trace) -> Vec<String> {
    why::why(system, trace)
        .into_iter()
        .map(|(depth, line)| format!("{}{line}", "  ".repeat(depth)))
        .collect()
}

/// The property as written; a timed model's deadline invariant, which the expansion
/// writes, as the job's time against its deadline in `last`.
fn property_text(system: &System, name: &str, last: &State) -> Vec<String> {
    let Some((k, property)) = system
        .properties
        .iter()
        .enumerate()
        .find(|(_, p)| p.name == name)
    else {
        return Vec::new();
    };
    let deadline = timed::TimedLayer::of(system).and_then(|layer| {
        let task = layer
            .tasks
            .iter()
            .find(|t| t.deadline_property == Some(k as u32))?;
        let elapsed = layer.task(system, task, last).job?;
        Some(format!(
            "{}'s job is unfinished {} after its release, past its {} deadline",
            task.name,
            layer.show(elapsed),
            layer.show(task.deadline)
        ))
    });
    vec![deadline.unwrap_or_else(|| property.text.clone())]
}
