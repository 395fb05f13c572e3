//! Whether the tasks of a model meet their deadlines (docs/sched.md).
//!
//! The verifier's tick semantics assumes that every GenoM task's work of one period ends
//! within its period. With WCETs declared this checks it: each task's demand per
//! period, exact from the model's states (`exact`) or, when they are too many, bounded
//! from its codel automata (`bound`), then `bip-sched`'s response-time analysis per
//! CPU, together with the components that stand for periodic tasks (their demand is
//! declared). `tasks` says which interaction is whose codel run.

mod bound;
mod exact;
mod tasks;

use bip_model::System;
use bip_sched::{
    analyse, show_micros as show, Analysis, Assignment, ResponseTime, SchedError, Task, TaskSet,
};

pub use tasks::{LayerTask, TaskKind};

use crate::memory;
use crate::options::Options;
use crate::report::{CheckKind, Method, PropertyResult, PropertyVerdict};

/// The name of the result that reports schedulability.
pub const SCHEDULABLE: &str = "Schedulable";

/// How a demand was found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DemandMethod {
    /// From every reachable state: the most a run can ask in one period.
    Exact { states: u64, transitions: u64 },
    /// From the codel automata: never below what a run can ask; `why` the states were not
    /// explored.
    Bound { why: String },
    /// Every task's demand is declared (components standing for tasks, no codels to
    /// look at).
    Declared,
}

/// Which demand to compute.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum DemandChoice {
    /// Exact within the options' limits, else the bound.
    #[default]
    Exact,
    /// The bound only (no exploration).
    Bound,
}

/// The schedulability of a layer: its tasks, their demands, and the analysis.
#[derive(Clone, Debug)]
pub struct Schedulability {
    pub tasks: Vec<LayerTask>,
    /// Per task, microseconds per period; `None` if its activities can loop forever in one
    /// period (a chain of codels that never pauses).
    pub demands: Vec<Option<u64>>,
    pub method: DemandMethod,
    /// The CPUs' names (one, `cpu`, if the model declares none).
    pub cpus: Vec<String>,
    /// The task set analysed (tasks in the order of [`Schedulability::tasks`]).
    pub set: TaskSet,
    /// `None` if some demand is unbounded: the layer is then not schedulable.
    pub analysis: Option<Analysis>,
    /// The GenoM layer's aperiodic tasks (`module.task`), left out: they have no period,
    /// and their codels no WCET, so they take no time in the analysis.
    pub aperiodic: Vec<String>,
}

impl Schedulability {
    /// Every task meets its deadline.
    pub fn schedulable(&self) -> bool {
        self.analysis
            .as_ref()
            .is_some_and(|a| a.schedulable(&self.set))
    }

    /// The verdict in words: schedulable, or which tasks miss their deadline and by how
    /// much.
    pub fn verdict(&self) -> String {
        let set = &self.set;
        let Some(a) = &self.analysis else {
            let looping: Vec<&str> = (0..set.tasks.len())
                .filter(|&i| self.demands[i].is_none())
                .map(|i| set.tasks[i].name.as_str())
                .collect();
            return format!(
                "not schedulable: {} can run without end in one period",
                looping.join(", ")
            );
        };
        let misses: Vec<String> = a
            .misses(set)
            .map(|i| {
                let t = &set.tasks[i];
                match a.tasks[i].response {
                    ResponseTime::Exact(r) => format!(
                        "{} misses its deadline by {} (responds in {}, deadline {})",
                        t.name,
                        show(r - t.deadline),
                        show(r),
                        show(t.deadline)
                    ),
                    ResponseTime::Unbounded => format!(
                        "{} never catches up: it and the tasks above it need more than the CPU",
                        t.name
                    ),
                    ResponseTime::AtLeast(r) => format!(
                        "{} responds in at least {}, past its deadline {}",
                        t.name,
                        show(r),
                        show(t.deadline)
                    ),
                }
            })
            .collect();
        if misses.is_empty() {
            "schedulable: every task meets its deadline".into()
        } else {
            format!("not schedulable: {}", misses.join("; "))
        }
    }
}

/// True if `system` declares time budgets that a verification checks as `Schedulable`
/// (a timed model checks its deadlines as invariants instead).
pub fn has_time_budgets(system: &System) -> bool {
    !system.is_timed() && tasks::TaskTable::new(system).is_some()
}

/// `Schedulable` as a property of a verification: `None` if the model declares no WCET.
/// The demands bounded from the codel automata settle it when they fit; else the exact
/// demands decide, within the run's limits, and a bound that misses with exact demands out
/// of reach is inconclusive, never "fails".
pub(crate) fn as_property(
    system: &System,
    options: &Options,
    method: Method,
) -> Option<PropertyResult> {
    // a timed model decides it by exploration: its expansion states each task's
    // deadline as an invariant (docs/verify.md, "Timed models")
    if system.is_timed() {
        return None;
    }
    let result = |verdict, method, note: String| PropertyResult {
        name: SCHEDULABLE.into(),
        kind: CheckKind::Schedulable,
        expr: String::new(),
        verdict,
        method,
        note: Some(note),
        error_step: None,
        worst_us: None,
    };
    let failed = |e: SchedError| {
        result(
            PropertyVerdict::Inconclusive {
                reason: format!("the task set cannot be analysed: {e}"),
            },
            method,
            String::new(),
        )
    };
    let bound = match schedulability(system, options, Assignment::Given, DemandChoice::Bound) {
        Ok(s) => s?,
        Err(e) => return Some(failed(e)),
    };
    let settled = |s: &Schedulability| {
        if s.schedulable() {
            PropertyVerdict::Holds { witness: None }
        } else {
            PropertyVerdict::Fails {
                reason: s.verdict(),
                trace: None,
            }
        }
    };
    let declared = || "response-time analysis of the declared WCETs".to_string();
    if bound.method == DemandMethod::Declared {
        return Some(result(settled(&bound), method, declared()));
    }
    if bound.schedulable() {
        return Some(result(
            PropertyVerdict::Holds { witness: None },
            method,
            "response-time analysis, demands bounded from the codel automata".into(),
        ));
    }
    let exact = match schedulability(system, options, Assignment::Given, DemandChoice::Exact) {
        Ok(s) => s?,
        Err(e) => return Some(failed(e)),
    };
    Some(match &exact.method {
        DemandMethod::Exact { states, .. } => {
            let note = format!("response-time analysis, exact demands ({states} states)");
            result(settled(&exact), Method::Explicit, note)
        }
        DemandMethod::Declared => result(settled(&exact), method, declared()),
        DemandMethod::Bound { why } => result(
            PropertyVerdict::Inconclusive {
                reason: format!(
                    "with demands bounded from the codel automata, {}; the exact demands were not computed ({why})",
                    bound.verdict().trim_start_matches("not schedulable: ")
                ),
            },
            method,
            String::new(),
        ),
    })
}

/// The schedulability of `system`'s tasks; `Ok(None)` if it has none to analyse (no WCET
/// in its GenoM layer, or no `tick_ms` to measure periods with, and no component standing
/// for a task). An error is a task set the analysis cannot take, which the model's checks
/// should have refused.
pub fn schedulability(
    system: &System,
    options: &Options,
    assignment: Assignment,
    choice: DemandChoice,
) -> Result<Option<Schedulability>, SchedError> {
    let Some(table) = tasks::TaskTable::new(system) else {
        return Ok(None);
    };
    if let Some((task, _)) = table.aperiodic.iter().find(|(_, budgeted)| *budgeted) {
        return Err(SchedError::Task {
            task: task.clone(),
            what: "it has no period, and its codels declare WCETs: the work it may do between two releases of the other tasks has no bound (every request or event can run its codels again), so no response time can be given; give it a period, or leave its WCETs out".into(),
        });
    }
    let (demands, method) = match choice {
        _ if !table.has_codel_tasks() => (bounds(system, &table), DemandMethod::Declared),
        DemandChoice::Bound => (
            bounds(system, &table),
            DemandMethod::Bound {
                why: "asked for".into(),
            },
        ),
        DemandChoice::Exact => {
            let limits = Options {
                max_states: Some(options.max_states.unwrap_or(20_000_000)),
                max_memory: Some(
                    options
                        .max_memory
                        .or_else(memory::default_limit)
                        .unwrap_or(4 << 30),
                ),
                ..options.clone()
            };
            match exact::exact_demands(system, &table, &limits) {
                Ok(found) => (
                    found.demands,
                    DemandMethod::Exact {
                        states: found.states,
                        transitions: found.transitions,
                    },
                ),
                Err(why) => (
                    bounds(system, &table),
                    DemandMethod::Bound {
                        why: format!("the states were not all explored: {why}"),
                    },
                ),
            }
        }
    };
    let cpus = if system.budgets.cpus.is_empty() {
        vec!["cpu".to_string()]
    } else {
        system.budgets.cpus.clone()
    };
    let set = TaskSet {
        cpus: cpus.clone(),
        tasks: table
            .tasks
            .iter()
            .zip(&demands)
            .map(|(t, d)| Task {
                name: t.name.clone(),
                cpu: t.cpu as usize,
                period: t.period_us,
                demand: d.unwrap_or(0),
                deadline: t.deadline_us.unwrap_or(t.period_us),
                priority: t.priority,
            })
            .collect(),
    };
    let analysis = if demands.iter().all(Option::is_some) {
        Some(analyse(&set, assignment)?)
    } else {
        set.validate()?;
        None
    };
    Ok(Some(Schedulability {
        aperiodic: table.aperiodic.into_iter().map(|(name, _)| name).collect(),
        tasks: table.tasks,
        demands,
        method,
        cpus,
        set,
        analysis,
    }))
}

/// Each task's demand bounded without exploring: from the codel automata, or declared.
fn bounds(system: &System, table: &tasks::TaskTable) -> Vec<Option<u64>> {
    table
        .tasks
        .iter()
        .map(|t| match (t.kind, system.genom.as_ref()) {
            (TaskKind::Component { wcet_us, .. }, _) => Some(wcet_us),
            (TaskKind::Genom { module, task }, Some(map)) => bound::demand_bound(map, module, task),
            (TaskKind::Genom { .. }, None) => None,
        })
        .collect()
}
