//! A timed model's tasks and clock as its states hold them (docs/genom.md, "Timed
//! models"): each task's atom holds its job's stage, which of its codels holds the core
//! and that codel's elapsed units, and whether a period boundary passed while its job was
//! unfinished; the clock holds the time modulo the common cycle of the periods, and
//! whether the instant's release is due. The schedule drawing and the explorer both
//! read them here.

use bip_model::genom::{GenomMap, TimedTaskMap};
use bip_model::{State, System};

/// The GenoM clock: the trigger of the tick.
pub(super) fn clock_component(system: &System, map: &GenomMap) -> Option<u32> {
    let tick = system.interactions.get(map.tick as usize)?;
    let trigger = tick.trigger? as usize;
    Some(tick.ports.get(trigger)?.component)
}

/// The task atom's variables and the clock's (bip-lang's `genom/names.rs`).
const STAGE: &str = "stage";
const RUNNING_CODEL: &str = "codel";
const LATE: &str = "late";
const PHASE: &str = "n";
const DUE: &str = "due";
/// The ports of the task atom's steps other than a codel's, and the clock's release.
const DISPATCH: &str = "dispatch";
const DONE: &str = "done";
const YIELD: &str = "yield";
const PREEMPT: &str = "preempt";
const PREEMPTED: &str = "preempted";
const RELEASE: &str = "release";

/// A job's stage in its task's atom.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// No job: nothing released, or its work done.
    Idle,
    /// Released, waiting for a core (or, with a codel started, preempted).
    Ready,
    /// Holding a core.
    Running,
}

impl Stage {
    fn of(value: i64) -> Stage {
        match value {
            0 => Stage::Idle,
            1 => Stage::Ready,
            _ => Stage::Running,
        }
    }

    /// Its value in the atom's `stage`.
    pub fn value(self) -> i64 {
        match self {
            Stage::Idle => 0,
            Stage::Ready => 1,
            Stage::Running => 2,
        }
    }

    /// `idle`, `ready`, `running`.
    pub fn word(self) -> &'static str {
        match self {
            Stage::Idle => "idle",
            Stage::Ready => "ready",
            Stage::Running => "running",
        }
    }
}

/// A variable of a task's atom that a trace tells in words (its `x` is the time, which
/// the time steps tell).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TaskVar {
    Stage,
    Codel,
    Late,
}

/// A step of the expansion's scheduling (docs/genom.md, "Timed models"), by the task
/// atoms it takes (their components).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TaskStep {
    /// A ready job takes a core.
    Dispatch(u32),
    /// A job ends its period's work and frees its core.
    Done(u32),
    /// A job gives its core to a more urgent one between two codels.
    Yield(u32),
    /// `by` takes the core of `task`'s running codel.
    Preempts { by: u32, task: u32 },
    /// The release at the instant's period boundaries.
    Release,
}

/// A codel of a task, as its atom's `codel` numbers them (from 1, in this order).
pub struct TaskCodel {
    /// `Service.state`.
    pub name: String,
    /// Its start: it takes the task's core.
    pub start: u32,
    /// Its WCET in units.
    pub wcet: u64,
}

/// A task of a timed model that runs codels.
pub struct TimedTask {
    /// `m.t`.
    pub name: String,
    pub component: u32,
    stage: u32,
    codel: u32,
    late: Option<u32>,
    elapsed_slot: u32,
    pub cpu: u32,
    pub core: Option<u32>,
    pub codels: Vec<TaskCodel>,
    /// The index of its deadline invariant among the system's properties.
    pub deadline_property: Option<u32>,
    /// Its period, the offset of its boundaries and its deadline, in units.
    period: u64,
    delay: u64,
    pub deadline: u64,
}

/// A task in a state.
pub struct TaskNow<'t> {
    pub stage: Stage,
    /// The codel started and not finished, and its elapsed units.
    pub codel: Option<(&'t TaskCodel, u64)>,
    /// The units since its job's release; `None` when idle.
    pub job: Option<u64>,
    /// A period boundary passed while its job was unfinished: its release waits for the
    /// job's end.
    pub late: bool,
}

/// A timed model's clock and tasks.
pub struct TimedLayer {
    /// The time unit in microseconds.
    pub unit_us: u64,
    /// The clock counts units modulo this: the periods' least common multiple.
    pub cycle: u64,
    clock: Option<u32>,
    phase: Option<u32>,
    due: Option<u32>,
    pub tasks: Vec<TimedTask>,
}

impl TimedLayer {
    /// The model's timed layer; `None` for an untimed model.
    pub fn of(system: &System) -> Option<TimedLayer> {
        let map = system.genom.as_ref()?;
        let unit_us = map.time_unit_us?.max(1);
        let clock = clock_component(system, map);
        let clock_var = |name: &str| {
            let c = clock?;
            let var = system.atom_of(c).var_index(name)?;
            Some((c, var))
        };
        let phase = clock_var(PHASE);
        let cycle = phase.map_or(1, |(c, var)| {
            let (_, hi) = system.atom_of(c).vars[var as usize].ty.range();
            hi.max(0) as u64 + 1
        });
        let slot =
            |v: Option<(u32, u32)>| v.map(|(c, var)| system.components[c as usize].var_slot(var));
        Some(TimedLayer {
            unit_us,
            cycle,
            clock,
            phase: slot(phase),
            due: slot(clock_var(DUE)),
            tasks: tasks(system, map, unit_us),
        })
    }

    /// Whether `name` is one of the tasks' (`m.t`).
    pub fn has_task_named(&self, name: &str) -> bool {
        self.tasks.iter().any(|t| t.name == name)
    }

    /// What interaction `i` does, if it is a step of the scheduling.
    pub fn step_of(&self, system: &System, i: u32) -> Option<TaskStep> {
        let ports = &system.interactions.get(i as usize)?.ports;
        let port = |name: &str, of_task: bool| {
            ports.iter().find_map(|p| {
                let here = match of_task {
                    true => self.task_of(p.component).is_some(),
                    false => Some(p.component) == self.clock,
                };
                (here && system.atom_of(p.component).ports[p.port as usize] == name)
                    .then_some(p.component)
            })
        };
        if port(RELEASE, false).is_some() {
            return Some(TaskStep::Release);
        }
        if let (Some(by), Some(task)) = (port(PREEMPT, true), port(PREEMPTED, true)) {
            return Some(TaskStep::Preempts { by, task });
        }
        port(DISPATCH, true)
            .map(TaskStep::Dispatch)
            .or_else(|| port(DONE, true).map(TaskStep::Done))
            .or_else(|| port(YIELD, true).map(TaskStep::Yield))
    }

    /// The task whose atom is `component`.
    pub fn task_of(&self, component: u32) -> Option<&TimedTask> {
        self.tasks.iter().find(|t| t.component == component)
    }

    /// The tasks whose period boundary is the instant of `state` (the ones its release
    /// releases).
    pub fn at_boundary(&self, state: &State) -> impl Iterator<Item = &TimedTask> {
        let n = self.now(state);
        self.tasks
            .iter()
            .filter(move |t| t.period <= 1 || n % t.period == t.delay)
    }

    /// The time step of `units` from `state`: `time passes 500 µs: 4 ms → 4.5 ms` (the
    /// clock modulo its cycle, as the state holds it).
    pub fn time_passes(&self, state: &State, units: u64) -> String {
        let now = self.now(state);
        let then = (now + units) % self.cycle.max(1);
        format!(
            "time passes {}: {} → {}",
            self.show(units),
            self.show(now),
            self.show(then)
        )
    }

    /// The time in units, modulo [`TimedLayer::cycle`].
    pub fn now(&self, state: &State) -> u64 {
        self.phase
            .map_or(0, |slot| state.slots()[slot as usize].max(0) as u64)
    }

    /// A duration of `units`, in the model's real units (`1.5 ms`).
    pub fn show(&self, units: u64) -> String {
        match units {
            0 => "0".into(),
            _ => bip_sched::show_micros(units.saturating_mul(self.unit_us)),
        }
    }

    /// Task `task` in `state`.
    pub fn task<'t>(&self, system: &System, task: &'t TimedTask, state: &State) -> TaskNow<'t> {
        let stage = Stage::of(system.value(state, task.component, task.stage));
        let elapsed = state.slots()[task.elapsed_slot as usize].max(0) as u64;
        let codel = task
            .running_codel(system, state)
            .map(|k| (&task.codels[k], elapsed));
        let late = task
            .late
            .is_some_and(|v| system.value(state, task.component, v) != 0);
        TaskNow {
            stage,
            codel,
            job: (stage != Stage::Idle).then(|| self.job_elapsed(task, state, late)),
            late,
        }
    }

    /// The units since the release of the task's job, as the expansion derives them from
    /// the clock (bip-lang's `genom/build/timed/mod.rs`, `job_elapsed`): a period for a
    /// boundary that passed while the job ran, one for the instant's boundary while its
    /// release is due, and the units since the last boundary.
    fn job_elapsed(&self, task: &TimedTask, state: &State, late: bool) -> u64 {
        let (p, d) = (task.period.max(1), task.delay);
        let n = self.now(state);
        let due = self.due.is_some_and(|s| state.slots()[s as usize] != 0);
        let boundary = p == 1 || n % p == d;
        let since_boundary = match self.cycle > 1 {
            true => (n + (p - d % p) % p) % p,
            false => 0,
        };
        u64::from(late) * p + u64::from(due && boundary) * p + since_boundary
    }
}

impl TimedTask {
    /// The job's stage in `state`.
    pub fn stage(&self, system: &System, state: &State) -> Stage {
        Stage::of(system.value(state, self.component, self.stage))
    }

    /// The slots of the variables of its atom a trace tells in words.
    pub fn told_slots(&self, system: &System) -> Vec<(u32, TaskVar)> {
        let slot = |var: u32| system.components[self.component as usize].var_slot(var);
        let mut out = vec![
            (slot(self.stage), TaskVar::Stage),
            (slot(self.codel), TaskVar::Codel),
        ];
        out.extend(self.late.map(|v| (slot(v), TaskVar::Late)));
        out
    }

    /// The slot of its `var`.
    pub fn slot(&self, system: &System, var: TaskVar) -> Option<u32> {
        self.told_slots(system)
            .into_iter()
            .find(|&(_, v)| v == var)
            .map(|(slot, _)| slot)
    }

    /// Its `var` at `value` in words: `running`, `runs Plan.compute`, `late`.
    pub fn tell(&self, var: TaskVar, value: i64) -> String {
        match var {
            TaskVar::Stage => Stage::of(value).word().to_string(),
            TaskVar::Codel => match self.codel_named(value) {
                Some(c) => format!("runs {}", c.name),
                None => "runs no codel".to_string(),
            },
            TaskVar::Late => match value != 0 {
                true => "late".to_string(),
                false => "on time".to_string(),
            },
        }
    }

    /// The codel its atom's `codel` numbers `k` (from 1).
    fn codel_named(&self, k: i64) -> Option<&TaskCodel> {
        self.codel_index(k).map(|k| &self.codels[k])
    }

    fn codel_index(&self, k: i64) -> Option<usize> {
        usize::try_from(k)
            .ok()
            .and_then(|k| k.checked_sub(1))
            .filter(|&k| k < self.codels.len())
    }

    /// The index into [`TimedTask::codels`] of the codel started and not finished.
    pub fn running_codel(&self, system: &System, state: &State) -> Option<usize> {
        self.codel_index(system.value(state, self.component, self.codel))
    }
}

/// The tasks that run codels, in declaration order, each with its codels in the order its
/// atom numbers them: its module's activities on it in declaration order, each one's
/// codels in order.
fn tasks(system: &System, map: &GenomMap, unit_us: u64) -> Vec<TimedTask> {
    let tick_units = map.tick_ms.map_or(1, |ms| (ms * 1000 / unit_us).max(1));
    let units = |us: u64| us / unit_us;
    let mut out = Vec::new();
    for m in &map.modules {
        for (ti, t) in m.tasks.iter().enumerate() {
            let Some(TimedTaskMap {
                component,
                elapsed_slot,
                deadline: deadline_property,
            }) = t.timed
            else {
                continue;
            };
            let atom = system.atom_of(component);
            let (Some(stage), Some(codel)) = (atom.var_index(STAGE), atom.var_index(RUNNING_CODEL))
            else {
                continue;
            };
            let codels = m
                .services
                .iter()
                .filter(|s| s.task == Some(ti) && s.kind == bip_model::genom::ServiceKind::Activity)
                .flat_map(|s| {
                    s.codels.iter().filter_map(|c| {
                        Some(TaskCodel {
                            name: format!("{}.{}", s.name, c.state),
                            start: c.timed?.start,
                            wcet: c.wcet_us.map_or(0, units),
                        })
                    })
                })
                .collect();
            let period = u64::from(t.period.unwrap_or(1)) * tick_units;
            out.push(TimedTask {
                name: format!("{}.{}", m.name, t.name),
                component,
                stage,
                codel,
                late: atom.var_index(LATE),
                elapsed_slot,
                cpu: t.cpu,
                core: t.core,
                codels,
                deadline_property,
                period,
                delay: u64::from(t.delay) * tick_units,
                deadline: t.deadline_us.map_or(period, units),
            });
        }
    }
    out
}
