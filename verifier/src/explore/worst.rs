//! A timed model's worst response time per task (docs/verify.md, "Timed models"): the
//! largest elapsed time of the task's job in a reachable state where its job end
//! (`m_t_done`) is a step, with the run that reaches it: the shortest run to the first
//! such state in exploration order, then the job end. The elapsed time is derived from
//! the state as the expansion defines it (`late · period + (n − delay) mod period`, plus
//! a period while the instant's boundary is due, in time units, docs/genom.md, "Timed
//! models"). `late` is one bit: the boundaries that pass while a job is active count as
//! one, so the elapsed time is exact as long as no job of the task is still active when
//! a second boundary is released (the release a step in a state where the task's job is
//! active, late, and its boundary due). Misses of deadlines do not matter: a job that
//! ends within two periods has its exact figure. A task whose job can run past a second
//! release gets a lower bound, two periods, never a figure that could be too small; so
//! does every task of an exploration that stopped early, with the most it saw.

use bip_model::{Label, OwnedStep, State, Steps, System, Verdict as TraceVerdict};
use bip_sched::show_micros;

use crate::error::VerifyError;
use crate::report::{PropertyResult, PropertyVerdict};
use crate::visited::{StateId, Visited};

use super::trace::trace_to;

/// The expansion's release of the instant's period boundaries.
const RELEASE: &str = "release";

/// What the worst response of a task reads from a state.
struct TaskClock {
    /// `m.t`.
    name: String,
    done: u32,
    task: u32,
    stage: u32,
    late: u32,
    period: i64,
    delay: i64,
}

/// The tasks of a timed model whose worst responses a run gives, and the release of the
/// period boundaries.
pub(super) struct Tasks {
    clocks: Vec<TaskClock>,
    release: Option<u32>,
}

impl Tasks {
    /// The tasks of `system`, as the expansion generated them; none for a model that is
    /// not timed.
    pub(super) fn of(system: &System) -> Tasks {
        Tasks {
            clocks: task_clocks(system),
            release: system.interaction_index(RELEASE),
        }
    }

    pub(super) fn is_empty(&self) -> bool {
        self.clocks.is_empty()
    }
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
            let atom = system.atom_of(task);
            let (Some(stage), Some(late)) = (atom.var_index("stage"), atom.var_index("late"))
            else {
                continue;
            };
            out.push(TaskClock {
                name: format!("{}.{}", m.name, t.name),
                done,
                task,
                stage,
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

/// What the states show of one task.
#[derive(Debug, Default, PartialEq)]
pub(super) struct Seen {
    /// The largest elapsed time at a job end, in the first state (in exploration order)
    /// that shows it, with the job end.
    worst: Option<(i64, StateId, OwnedStep)>,
    /// A release of the task's boundary can come while its job, already late, is active.
    coalesced: bool,
}

/// Each task's worst response, in the order of the model's tasks; nothing for a model
/// that is not timed. `complete`: every reachable state was explored; `look`: read the
/// states stored (false when the user interrupted the run: no figure is given then);
/// `gathered`: what the exploration saw of every state as it expanded them, if it did
/// (else the stored states are read again).
pub(super) fn worst_responses(
    system: &System,
    visited: &Visited,
    tasks: &Tasks,
    complete: bool,
    look: bool,
    gathered: Result<Vec<Seen>, String>,
) -> Result<Vec<PropertyResult>, VerifyError> {
    if tasks.is_empty() {
        return Ok(Vec::new());
    }
    let unit_us = system
        .genom
        .as_ref()
        .and_then(|g| g.time_unit_us)
        .unwrap_or(1);
    let micros = |units: i64| units.max(0) as u64 * unit_us;
    let result = |t: &TaskClock, verdict, note, worst_us| {
        PropertyResult::worst_response(&t.name, verdict, note, worst_us)
    };
    // a complete exploration expanded every stored state once, in the order read_states
    // reads them; a stopped one stored states it did not expand, whose job ends are not
    // among what it gathered: its figures are lower bounds either way, and reading every
    // stored state again would take a time no limit bounds (the limit that stopped the
    // run may be the time)
    let seen = match (look, complete, gathered) {
        (false, _, _) => tasks.unseen(),
        (true, _, Ok(seen)) => seen,
        (true, true, Err(e)) => return Err(in_error(&e)),
        (true, false, Err(_)) => read_states(system, visited, tasks)?,
    };
    let mut out = Vec::with_capacity(tasks.clocks.len());
    for (t, seen) in tasks.clocks.iter().zip(seen) {
        let inconclusive = |reason: String, worst_us| {
            result(t, PropertyVerdict::Inconclusive { reason }, None, worst_us)
        };
        out.push(match seen {
            Seen {
                coalesced: true, ..
            } => {
                let bound = micros(2 * t.period);
                inconclusive(
                    format!(
                        "at least 2 periods ({}): its job runs past a second release, which the model coalesces",
                        show_micros(bound)
                    ),
                    Some(bound),
                )
            }
            _ if !look => inconclusive("not given: the run was interrupted".into(), None),
            Seen { worst: None, .. } if !complete => inconclusive(
                "not given: the exploration stopped before every state was seen, and no job of it ended in those it saw".into(),
                None,
            ),
            Seen {
                worst: Some((elapsed, _, _)),
                ..
            } if !complete => {
                let us = micros(elapsed);
                inconclusive(
                    format!(
                        "at least {}: the exploration stopped before every state was seen",
                        show_micros(us)
                    ),
                    Some(us),
                )
            }
            Seen { worst: None, .. } => result(
                t,
                PropertyVerdict::Holds { witness: None },
                Some("no job of it ever ends".into()),
                None,
            ),
            Seen {
                worst: Some((elapsed, id, step)),
                ..
            } => {
                let us = micros(elapsed);
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
                    Some(us),
                )
            }
        });
    }
    Ok(out)
}

/// Per task, what the stored states show: its largest elapsed time at a job end, and
/// whether a second boundary can be released while its job is active.
pub(super) fn read_states(
    system: &System,
    visited: &Visited,
    tasks: &Tasks,
) -> Result<Vec<Seen>, VerifyError> {
    let mut seen = tasks.unseen();
    let layout = &system.layout;
    let mut steps = Steps::new();
    for level in 0..visited.levels() {
        for chunk in visited.chunks(level, u32::MAX) {
            for local in chunk.start..chunk.end {
                let id = visited.id(chunk.shard, local);
                let state = layout.unpack(visited.state(id));
                system
                    .enabled_steps(&state, &mut steps)
                    .map_err(|e| in_error(&e.to_string()))?;
                tasks.see(system, &state, &steps, id, &mut seen);
            }
        }
    }
    Ok(seen)
}

/// The error of a reachable state whose steps cannot be computed: the worst responses
/// read every state's.
fn in_error(e: &str) -> VerifyError {
    VerifyError::Internal(format!("a reachable state has a range error: {e}"))
}

impl Tasks {
    /// What no state has shown yet, per task.
    pub(super) fn unseen(&self) -> Vec<Seen> {
        self.clocks.iter().map(|_| Seen::default()).collect()
    }

    /// Adds what stored state `id`, whose steps are `steps`, shows of each task to `seen`.
    pub(super) fn see(
        &self,
        system: &System,
        state: &State,
        steps: &Steps,
        id: StateId,
        seen: &mut [Seen],
    ) {
        let (n, due) = clock(system, state);
        let releases = due
            && self
                .release
                .is_some_and(|r| steps.iter().any(|s| s.label == Label::Interaction(r)));
        for (t, seen) in self.clocks.iter().zip(seen) {
            let since = (n - t.delay).rem_euclid(t.period);
            let boundary_due = due && since == 0;
            let late = system.value(state, t.task, t.late);
            let active = system.value(state, t.task, t.stage) != 0;
            if releases && boundary_due && active && late != 0 {
                seen.coalesced = true;
            }
            let Some(step) = steps.iter().find(|s| s.label == Label::Interaction(t.done)) else {
                continue;
            };
            let elapsed = (late + i64::from(boundary_due)) * t.period + since;
            if seen.worst.as_ref().is_none_or(|b| elapsed > b.0) {
                seen.worst = Some((elapsed, id, step.to_owned()));
            }
        }
    }
}

/// Adds what the states after those of `seen` showed (`later`, in the exploration's
/// order): a largest time stays with the first state that shows it.
pub(super) fn merge(seen: &mut [Seen], later: &mut [Seen]) {
    for (mine, theirs) in seen.iter_mut().zip(later) {
        mine.coalesced |= theirs.coalesced;
        if let Some(w) = theirs.worst.take() {
            if mine.worst.as_ref().is_none_or(|b| w.0 > b.0) {
                mine.worst = Some(w);
            }
        }
        theirs.coalesced = false;
    }
}
