//! A timed model's worst response time per task (docs/verify.md, "Timed models"): the
//! largest elapsed time of the task's job in a reachable state where its job end
//! (`m_t_done`) is a step, with the run that reaches it: the shortest run to the first
//! such state in exploration order, then the job end. The elapsed time is derived from
//! the state as the expansion defines it (`late · period + (n − delay) mod period`, plus
//! a period while the instant's boundary is due, in time units, docs/genom.md, "Timed
//! models"); it is exact while no deadline is missed,
//! so the figures are given only when every deadline holds.

use bip_model::{Label, OwnedStep, State, Steps, System, Verdict as TraceVerdict};
use bip_sched::show_micros;

use crate::error::VerifyError;
use crate::report::{CheckKind, Method, PropertyResult, PropertyVerdict};
use crate::visited::{StateId, Visited};

use super::trace::trace_to;

/// What the worst response of a task reads from a state.
struct TaskClock {
    /// `m.t`.
    name: String,
    done: u32,
    task: u32,
    late: u32,
    period: i64,
    delay: i64,
}

/// The tasks of a timed model, as the expansion generated them; empty for another model.
fn task_clocks(system: &System) -> Vec<TaskClock> {
    let Some(map) = system.genom.as_ref() else {
        return Vec::new();
    };
    let (Some(unit_us), Some(tick_ms)) = (map.time_unit_us, map.tick_ms) else {
        return Vec::new();
    };
    let units = |ticks: u32| i64::from(ticks) * (tick_ms as i64) * 1000 / unit_us as i64;
    let mut out = Vec::new();
    for m in &map.modules {
        for t in &m.tasks {
            // a task without codels has no atom: it never runs
            let (Some(done), Some(task), Some(period)) = (
                system.interaction_index(&format!("{}_{}_done", m.name, t.name)),
                system.component_index(&format!("{}_{}_task", m.name, t.name)),
                t.period,
            ) else {
                continue;
            };
            let Some(late) = system.atom_of(task).var_index("late") else {
                continue;
            };
            out.push(TaskClock {
                name: format!("{}.{}", m.name, t.name),
                done,
                task,
                late,
                period: units(period),
                delay: units(t.delay),
            });
        }
    }
    out
}

/// The clock's phase in units (0 when every period is one unit: the clock has none),
/// and whether the release of the instant's period boundaries is due.
fn clock(system: &System, s: &State) -> (i64, bool) {
    let Some(clock) = system.component_index("clock") else {
        return (0, false);
    };
    let atom = system.atom_of(clock);
    let read = |v: &str| atom.var_index(v).map_or(0, |v| system.value(s, clock, v));
    (read("n"), read("due") != 0)
}

/// Each task's worst response, in the order of the model's tasks; nothing for a model
/// that is not timed. `complete`: every reachable state was explored; `deadlines_hold`:
/// no invariant (the generated deadlines among them) fails.
pub(super) fn worst_responses(
    system: &System,
    visited: &Visited,
    complete: bool,
    deadlines_hold: bool,
) -> Result<Vec<PropertyResult>, VerifyError> {
    let tasks = task_clocks(system);
    if tasks.is_empty() {
        return Ok(Vec::new());
    }
    let unit_us = system
        .genom
        .as_ref()
        .and_then(|g| g.time_unit_us)
        .unwrap_or(1);
    let result = |t: &TaskClock, verdict, note| PropertyResult {
        name: format!("{} worst response", t.name),
        kind: CheckKind::WorstResponse,
        expr: String::new(),
        verdict,
        method: Method::Explicit,
        note,
        error_step: None,
    };
    let why_not = if !complete {
        Some("not given: the exploration stopped before every state was seen")
    } else if !deadlines_hold {
        Some("not given: an invariant fails (a deadline is missed, or another), and past a miss a job's elapsed time is not tracked exactly")
    } else {
        None
    };
    if let Some(why) = why_not {
        return Ok(tasks
            .iter()
            .map(|t| {
                let reason = why.to_string();
                result(t, PropertyVerdict::Inconclusive { reason }, None)
            })
            .collect());
    }
    // per task, the largest elapsed time at a job end, in the first state (in exploration
    // order) that shows it
    let mut best: Vec<Option<(i64, StateId, OwnedStep)>> = tasks.iter().map(|_| None).collect();
    let layout = &system.layout;
    let mut steps = Steps::new();
    for level in 0..visited.levels() {
        for chunk in visited.chunks(level, u32::MAX) {
            for local in chunk.start..chunk.end {
                let id = visited.id(chunk.shard, local);
                let state = layout.unpack(visited.state(id));
                system.enabled_steps(&state, &mut steps).map_err(|e| {
                    VerifyError::Internal(format!("a reachable state has a range error: {e}"))
                })?;
                let (n, due) = clock(system, &state);
                for (t, best) in tasks.iter().zip(&mut best) {
                    let Some(step) = steps.iter().find(|s| s.label == Label::Interaction(t.done))
                    else {
                        continue;
                    };
                    let since = (n - t.delay).rem_euclid(t.period);
                    let due_here = i64::from(due && since == 0);
                    let elapsed =
                        (system.value(&state, t.task, t.late) + due_here) * t.period + since;
                    if best.as_ref().is_none_or(|b| elapsed > b.0) {
                        *best = Some((elapsed, id, step.to_owned()));
                    }
                }
            }
        }
    }
    let mut out = Vec::with_capacity(tasks.len());
    for (t, best) in tasks.iter().zip(best) {
        out.push(match best {
            None => result(
                t,
                PropertyVerdict::Holds { witness: None },
                Some("no job of it ever ends".into()),
            ),
            Some((elapsed, id, step)) => {
                let us = elapsed as u64 * unit_us;
                let trace = trace_to(
                    system,
                    visited,
                    id,
                    Some(step),
                    TraceVerdict::Witness(format!("{} worst response", t.name)),
                )?;
                result(
                    t,
                    PropertyVerdict::Holds {
                        witness: Some(trace),
                    },
                    Some(show_micros(us)),
                )
            }
        });
    }
    Ok(out)
}
