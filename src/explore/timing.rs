//! A timed model in the explorer: the time and each task's job as the state holds them
//! (read by `trace::timed`, as the schedule drawing reads them), and how far the time
//! step goes (`trace::view` names it).

use bip_model::{OwnedStep, Role, State, System};
use serde_json::{json, Value};

use crate::trace::timed::{Stage, TimedLayer};

/// A duration as the page shows it and as scripts compute with it.
fn duration(layer: &TimedLayer, units: u64) -> Value {
    json!({"units": units, "time": layer.show(units)})
}

/// The time and the tasks in `state`; `since_start` is the time along the history that
/// leads there (the state holds it only modulo the cycle).
pub fn state(layer: &TimedLayer, system: &System, state: &State, since_start: u64) -> Value {
    let cpus = &system.budgets.cpus;
    let tasks: Vec<Value> = layer
        .tasks
        .iter()
        .map(|task| {
            let now = layer.task(system, task, state);
            let (stage, what) = match (now.stage, now.codel.is_some()) {
                (Stage::Idle, _) => ("idle", "no job: its work is done, or none was released"),
                (Stage::Ready, false) => ("ready", "released, waits for a core"),
                (Stage::Ready, true) => ("preempted", "its codel started, waits for a core"),
                (Stage::Running, true) => ("running", "holds a core, runs its codel"),
                (Stage::Running, false) => ("running", "holds a core between two codels"),
            };
            let codel = now.codel.map(|(c, elapsed)| {
                json!({
                    "name": c.name,
                    "elapsed": duration(layer, elapsed),
                    "wcet": layer.show(c.wcet),
                })
            });
            let job = now.job.map(|elapsed| {
                json!({
                    "elapsed": duration(layer, elapsed),
                    "deadline": layer.show(task.deadline),
                    "past_deadline": elapsed > task.deadline,
                })
            });
            json!({
                "name": task.name,
                // CPUs are named only where there are several
                "cpu": (cpus.len() > 1).then(|| cpus.get(task.cpu as usize)).flatten(),
                "core": task.core,
                "stage": stage,
                "stage_text": what,
                "codel": codel,
                "job": job,
                "late": now.late,
            })
        })
        .collect();
    json!({
        "unit": layer.show(1),
        "now": duration(layer, layer.now(state)),
        "cycle": duration(layer, layer.cycle),
        "since_start": duration(layer, since_start),
        "tasks": tasks,
    })
}

/// How far the time step `step` of `state` goes; `None` for another step, or one whose
/// advance is a range error.
pub fn advance(
    layer: &TimedLayer,
    system: &System,
    state: &State,
    step: &OwnedStep,
) -> Option<Value> {
    if system.role(step.label) != Role::Time {
        return None;
    }
    let units = system.time_advance(state, step.as_step()).ok()?;
    Some(duration(layer, units))
}

/// The units that pass along `steps`, each leaving the state of `befores` at its index.
pub fn elapsed(system: &System, steps: &[OwnedStep], befores: &[&State]) -> u64 {
    steps
        .iter()
        .zip(befores)
        .map(|(step, before)| system.time_advance(before, step.as_step()).unwrap_or(0))
        .sum()
}
