//! Simulation: the engine on a model with default codels (random declared outcomes and
//! ids values) and random requests from the environment, on a virtual clock, checking
//! every invariant (and deadlock freedom, if the model asks for it) after every step
//! (docs/engine.md, "`bip simulate` and `bip replay`"). A run is the same for a seed.
//!
//! In a timed model, [`CodelTime`] chooses when each codel finishes (its BCET, its WCET,
//! or in between), and a deadline invariant that fails ends the run; an untimed model's
//! codels may take a simulated time on CPUs scheduled as `bip sched` assumes
//! (docs/engine.md, "Codel times"). A run reports each codel's times and the first
//! overruns and misses it saw.
//!
//! A run of any length takes constant memory: the engine records only the last steps (a
//! window, for the report of a failure), and [`Hooks::on_steps`] receives the run in
//! segments as it goes, to stream the whole trace to a file.

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::eval::Expr;
use bip_model::{
    Label, Liveness, LivenessChecker, OwnedStep, PropertyKind, Rng, Role, Steps, System, Trace,
    Verdict,
};

use crate::budgets::{CodelTime, CodelTimes};
use crate::codel::DefaultCodels;
use crate::engine::{Engine, Stats, Stepped};
use crate::error::{BuildError, StepAsError};
use crate::event::Event;
use crate::policy::Policy;
use crate::record::Window;

/// Steps per recorded segment: the window of a failure's report holds the last one to two
/// segments.
pub const SEGMENT: usize = 1000;

/// What to simulate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SimulationOptions {
    /// Steps to take (ticks, codels, requests, other steps).
    pub steps: u64,
    /// Seed of the random requests, codel outcomes and choices.
    pub seed: u64,
    /// When codels finish in a timed model, how long they take on simulated CPUs in an
    /// untimed one (default: as early as the model allows, no time).
    pub codel_time: CodelTime,
}

/// The first overruns and misses a run keeps (the engine counts them all in its stats).
pub const KEPT_BUDGET_EVENTS: usize = 20;

/// One codel's run times in a simulation.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CodelReport {
    /// `(module, service, codel state)`.
    pub codel: (String, String, String),
    pub wcet_us: Option<u64>,
    pub times: CodelTimes,
}

/// A codel run past its WCET, or a task's period work past its deadline.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BudgetEvent {
    /// The engine's time when it was seen.
    pub at_us: u64,
    /// `(module, service, codel state)` of the codel that ran (for a miss: the one of
    /// the late task that ran last, if any).
    pub codel: Option<(String, String, String)>,
    pub kind: BudgetEventKind,
}

/// A bounded response property not answered in time ([`Event::ResponseLate`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LateResponse {
    /// The engine's time and step count when the tick that passed the bound was taken.
    pub at_us: u64,
    pub step: u64,
    pub property: String,
    pub within: u64,
    pub elapsed_ticks: u64,
    /// The request accepted on the trigger's step, if any.
    pub ticket: Option<u64>,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BudgetEventKind {
    WcetExceeded {
        took_us: u64,
        wcet_us: u64,
    },
    /// Task `task` (`module.task`) was late.
    DeadlineMissed {
        task: String,
        elapsed_us: u64,
        deadline_us: u64,
    },
}

/// What a simulation reports to its caller while it runs.
#[derive(Default)]
pub struct Hooks<'a> {
    /// Asked between steps: true ends the run early, as [`SimulationEnd::Interrupted`]
    /// (Ctrl-C).
    pub stop: Option<&'a dyn Fn() -> bool>,
    /// Given the run's steps in order, a segment at a time, each from the state the last
    /// one ended in (the whole run when joined; its verdict is [`Simulation::end`]).
    pub on_steps: Option<&'a mut dyn FnMut(&Trace)>,
}

/// How a simulation ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SimulationEnd {
    /// Every check held for all the steps asked.
    Completed,
    /// Stopped from outside ([`Hooks::stop`]); every check held until then.
    Interrupted,
    /// No step is possible and nothing can arrive; every check held until then.
    Stuck,
    /// This invariant fails in the last state.
    Violation(String),
    /// The last state is a deadlock the model does not excuse.
    Deadlock,
    /// A range error, in a step or in a check.
    RangeError(String),
}

impl SimulationEnd {
    /// True if a check failed.
    pub fn fails(&self) -> bool {
        !matches!(
            self,
            SimulationEnd::Completed | SimulationEnd::Stuck | SimulationEnd::Interrupted
        )
    }
}

/// What a simulation did.
#[derive(Clone, Debug)]
pub struct Simulation {
    pub end: SimulationEnd,
    /// The engine's counters at the end.
    pub stats: Stats,
    /// Requests sent by the environment (the engine accepted or refused them).
    pub requests_sent: u64,
    /// How many invariants were checked at every step, and whether deadlock freedom was.
    pub invariants: usize,
    pub deadlock_checked: bool,
    /// The run's last steps (all of them for a run of at most [`SEGMENT`] steps), from the
    /// state they start in, as a trace whose verdict is the failure (if any).
    pub last_steps: Window,
    /// Every codel's run times, in the GenoM map's order (empty without a GenoM layer).
    pub codels: Vec<CodelReport>,
    /// The first [`KEPT_BUDGET_EVENTS`] overruns of a WCET and misses of a deadline
    /// (`stats` counts them all).
    pub budget_events: Vec<BudgetEvent>,
    /// How many bounded response properties were watched at every step.
    pub responses_monitored: usize,
    /// The first [`KEPT_BUDGET_EVENTS`] response deadline misses (`stats.responses_late`
    /// counts them all).
    pub late_responses: Vec<LateResponse>,
}

/// Simulates `system` (see the module documentation).
pub fn simulate(system: System, options: SimulationOptions) -> Result<Simulation, BuildError> {
    simulate_with(system, options, Hooks::default())
}

/// [`simulate`], with a way to stop it and to receive its steps as it goes.
pub fn simulate_with(
    system: System,
    options: SimulationOptions,
    mut hooks: Hooks<'_>,
) -> Result<Simulation, BuildError> {
    let services: Vec<(String, String)> = system
        .requestable()
        .map(|(m, s)| (m.to_string(), s.to_string()))
        .collect();
    let deadlock_free = system.properties.iter().find_map(|p| match &p.kind {
        PropertyKind::DeadlockFree { terminal } => Some(terminal.clone()),
        _ => None,
    });
    let invariants = system
        .properties
        .iter()
        .filter(|p| matches!(p.kind, PropertyKind::Invariant(_)))
        .count();
    let responses_monitored = system
        .properties
        .iter()
        .filter(|p| p.kind.response_spec().is_some_and(|s| s.within.is_some()))
        .count();
    let mut engine = Engine::builder(system)
        .default_codels(DefaultCodels::Random(options.seed))
        .policy(Policy::Seeded(options.seed))
        .record_window(SEGMENT)
        .event_capacity(EVENT_QUEUE)
        .codel_time(options.codel_time)
        .build()?;
    let mut budget_events = Vec::new();
    let mut late_responses = Vec::new();
    let mut checks = Checks {
        deadlock_free,
        steps: Steps::new(),
        checker: LivenessChecker::default(),
    };
    let mut rng = Rng(options.seed ^ 0x5eed);
    let mut requests_sent = 0u64;
    let mut end = checks.check(&engine);
    // the segment last given to `on_steps`, kept for the report's window
    let mut given: Option<Window> = None;
    while end.is_none() && engine.inspect().stats().steps < options.steps {
        if let Some(on_steps) = hooks.on_steps.as_mut() {
            if engine.inspect().recorded_steps() >= SEGMENT {
                let segment = engine.take_record();
                on_steps(&segment.trace);
                given = Some(segment);
            }
        }
        if hooks.stop.is_some_and(|stop| stop()) {
            end = Some(SimulationEnd::Interrupted);
            break;
        }
        // a request now and then, from the environment
        if rng.below(4) == 0 {
            if !services.is_empty() {
                let (m, s) = &services[rng.below(services.len())];
                if engine.request(m, s, ()).is_ok() {
                    requests_sent += 1;
                }
            } else if let Some(step) = environment_step(&engine, &mut rng) {
                end = match engine.step_as(step.as_step()) {
                    Err(StepAsError::TakenThenStopped(error)) => {
                        Some(SimulationEnd::RangeError(error.to_string()))
                    }
                    Err(e) => Some(SimulationEnd::RangeError(e.to_string())),
                    Ok(_) => checks.check(&engine),
                };
                keep_events(&mut engine, &mut budget_events, &mut late_responses);
                continue;
            }
        }
        let before = engine.inspect().stats().steps;
        match engine.step() {
            Err(e) => end = Some(SimulationEnd::RangeError(e.to_string())),
            Ok(Stepped::Idle { next_tick_us }) => match next_tick_us {
                Some(t) => engine.wait_until(t),
                None if services.is_empty() && environment_step(&engine, &mut rng).is_none() => {
                    end = Some(SimulationEnd::Stuck)
                }
                None => {}
            },
            Ok(_) => {}
        }
        if end.is_none() && engine.inspect().stats().steps != before {
            end = checks.check(&engine);
        }
        keep_events(&mut engine, &mut budget_events, &mut late_responses);
    }
    let end = end.unwrap_or(SimulationEnd::Completed);
    let verdict = match &end {
        SimulationEnd::Completed | SimulationEnd::Stuck | SimulationEnd::Interrupted => {
            Verdict::None
        }
        SimulationEnd::Violation(p) => Verdict::Violation(p.clone()),
        SimulationEnd::Deadlock => Verdict::Deadlock,
        SimulationEnd::RangeError(m) => Verdict::RangeError(m.clone()),
    };
    let mut last_steps = match hooks.on_steps.as_mut() {
        Some(on_steps) => {
            let rest = engine.take_record();
            on_steps(&rest.trace);
            match given {
                // the report shows the last segment given and the rest
                Some(mut window) if rest.trace.steps.len() < SEGMENT => {
                    window.trace.steps.extend(rest.trace.steps);
                    window
                }
                _ => rest,
            }
        }
        None => engine.record_window(),
    };
    last_steps.trace.verdict = verdict;
    Ok(Simulation {
        end,
        stats: engine.inspect().stats(),
        requests_sent,
        invariants,
        deadlock_checked: checks.deadlock_free.is_some(),
        last_steps,
        codels: codel_reports(&engine),
        budget_events,
        responses_monitored,
        late_responses,
    })
}

/// Events the engine queues between two drains: a step emits a few.
const EVENT_QUEUE: usize = 64;

/// Takes the engine's events, keeping the first overruns, misses and late responses.
fn keep_events(engine: &mut Engine, kept: &mut Vec<BudgetEvent>, late: &mut Vec<LateResponse>) {
    let at_us = engine.inspect().now_us();
    let step = engine.inspect().stats().steps;
    for event in engine.events() {
        let (codel, kind) = match event {
            Event::ResponseLate {
                property,
                within,
                elapsed_ticks,
                ticket,
            } => {
                if late.len() < KEPT_BUDGET_EVENTS {
                    late.push(LateResponse {
                        at_us,
                        step,
                        property: property.to_string(),
                        within,
                        elapsed_ticks,
                        ticket: ticket.map(|t| t.0),
                    });
                }
                continue;
            }
            Event::WcetExceeded {
                codel,
                took_us,
                wcet_us,
            } => (
                Some(codel),
                BudgetEventKind::WcetExceeded { took_us, wcet_us },
            ),
            Event::DeadlineMissed {
                task,
                codel,
                elapsed_us,
                deadline_us,
            } => (
                codel,
                BudgetEventKind::DeadlineMissed {
                    task: task.to_string(),
                    elapsed_us,
                    deadline_us,
                },
            ),
            _ => continue,
        };
        if kept.len() < KEPT_BUDGET_EVENTS {
            kept.push(BudgetEvent {
                at_us,
                codel: codel.map(|c| (c.module.clone(), c.service.clone(), c.state.clone())),
                kind,
            });
        }
    }
}

/// Every codel's run times, in the GenoM map's order.
fn codel_reports(engine: &Engine) -> Vec<CodelReport> {
    let view = engine.inspect();
    let Some(map) = view.system().genom.as_ref() else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for m in &map.modules {
        for s in &m.services {
            for c in &s.codels {
                if let Some(id) = view.codel_id(&m.name, &s.name, &c.state) {
                    out.push(CodelReport {
                        codel: (m.name.clone(), s.name.clone(), c.state.clone()),
                        wcet_us: c.wcet_us,
                        times: view.codel_times(id),
                    });
                }
            }
        }
    }
    out
}

/// A random enabled environment step of a model without a GenoM layer.
fn environment_step(engine: &Engine, rng: &mut Rng) -> Option<OwnedStep> {
    let view = engine.inspect();
    let env: Vec<OwnedStep> = view
        .enabled()
        .steps()
        .filter(|s| view.system().role(s.label) == Role::Environment)
        .filter(|s| matches!(s.label, Label::Interaction(_)))
        .map(|s| s.to_owned())
        .collect();
    (!env.is_empty()).then(|| env[rng.below(env.len())].clone())
}

/// The checks after each step, with their scratch.
struct Checks {
    /// The model's `DeadlockFree` property (its `terminal` condition), if it has one.
    deadlock_free: Option<Option<Expr>>,
    steps: Steps,
    checker: LivenessChecker,
}

impl Checks {
    /// Every invariant, and deadlock freedom if asked, in the engine's state.
    fn check(&mut self, engine: &Engine) -> Option<SimulationEnd> {
        let view = engine.inspect();
        if let Some(e) = view.stopped() {
            // a range error in the initial state: the engine never steps
            return Some(SimulationEnd::RangeError(e.to_string()));
        }
        let (system, state) = (view.system(), view.state());
        for p in &system.properties {
            if let PropertyKind::Invariant(e) = &p.kind {
                match system.holds(e, state, &p.name) {
                    Ok(true) => {}
                    Ok(false) => return Some(SimulationEnd::Violation(p.name.clone())),
                    Err(e) => return Some(SimulationEnd::RangeError(e.to_string())),
                }
            }
        }
        let terminal = self.deadlock_free.as_ref()?;
        view.enabled().copy_to(&mut self.steps);
        // as the verifier judges a state: a liveness that cannot be told (a range error
        // after ticks alone) is no finding here; the run goes on and meets it, or not
        match system.liveness(state, &self.steps, &mut self.checker) {
            Ok(Liveness::Deadlock) => match terminal {
                Some(t) => match system.holds(t, state, "terminal condition of DeadlockFree") {
                    Ok(true) => None,
                    Ok(false) => Some(SimulationEnd::Deadlock),
                    Err(e) => Some(SimulationEnd::RangeError(e.to_string())),
                },
                None => Some(SimulationEnd::Deadlock),
            },
            Ok(_) | Err(_) => None,
        }
    }
}
