//! Replaying a trace through the engine: each step must be one the engine allows at that
//! moment (`Engine::step_as`: a codel step runs the codel, a request is served as a
//! request, a tick is a tick), and the trace's verdict is checked at its end: the deadlock
//! is reached (with the codels held and why), the invariant fails, the witness holds.

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::{
    Liveness, LivenessChecker, OwnedStep, PropertyKind, Role, State, Steps, System, Trace, Verdict,
};

use crate::codel::DefaultCodels;
use crate::engine::{Engine, Stepped};
use crate::error::{BuildError, EngineError, StepAsError};

/// What the replay of one step did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReplayedStep {
    /// The step's name in the trace.
    pub name: String,
    /// What the engine did with it.
    pub stepped: Stepped,
}

/// A trace step the engine did not take.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Refused {
    /// 1-based.
    pub step: usize,
    pub name: String,
    pub message: String,
    /// Why, when the step is a codel or a request of the GenoM layer: the conditions that
    /// fail now.
    pub reasons: Vec<String>,
}

/// How the trace's verdict looks at its end.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum End {
    /// A plain recording: nothing to check.
    Recording,
    /// The last state is a deadlock (no progress now or after ticks); `held` lists the
    /// activities with work outstanding, the codel each runs next, and the conditions
    /// that hold it.
    Deadlock { held: Vec<String> },
    /// The invariant fails in the last state.
    Violation { property: String },
    /// The reachability property holds in the last state.
    Witness { property: String },
    /// The run of a worst response (`bip verify`'s `m.t worst response`, or a response
    /// property's): its last step ends the job of the task, or is a step of the model
    /// where the property's wait ends; the figure is the verifier's.
    WorstResponse { property: String },
    /// The response property's trigger goes unanswered: on the cycle of a lasso (which
    /// starts after `loop_start` steps and returns to its first state), past the bound on
    /// the last step, or in a last state with no step.
    Unanswered {
        property: String,
        loop_start: Option<usize>,
    },
    /// Time cannot pass from the last state (`TimeProgress`'s trace): the trace ends in a
    /// state with no step, or on a cycle (which starts after `loop_start` steps and
    /// returns to its first state) that no run from it leaves for a tick.
    Timelock { loop_start: Option<usize> },
    /// Time cannot pass on the trace's cycle, which starts after `loop_start` steps and
    /// returns to its first state (`TimeProgress`'s trace of a busy loop): no state on it
    /// has a step of a `Time` connector, though a run may leave it.
    BusyLoop { loop_start: usize },
    /// A step from the last state, or a property there (a response property's trigger or
    /// response: in it or on a step out of it), has a range error.
    RangeError { message: String },
    /// The verdict does not show at the end of the trace.
    NotConfirmed { verdict: String, why: String },
}

/// The result of [`replay`].
pub struct Replay {
    pub steps: Vec<ReplayedStep>,
    /// The first step the engine did not take (the replay stops there).
    pub refused: Option<Refused>,
    /// The verdict's check at the end (only if every step was taken).
    pub end: Option<End>,
    /// What the engine's response monitor reported, after which step (numbered from 1):
    /// [`crate::Event::ResponseLate`]s.
    pub late: Vec<(usize, crate::Event)>,
    /// The engine after the replay (its state, its recording).
    pub engine: Engine,
}

/// Replays `trace` on `system` through an engine with default codels (each does what the
/// trace's step says).
pub fn replay(system: System, trace: &Trace) -> Result<Replay, BuildError> {
    let (path, error) = trace.replay_prefix(&system);
    let mut engine = Engine::builder(system)
        .default_codels(DefaultCodels::FirstYield)
        .record(trace.steps.len())
        .build()?;
    let mut steps = Vec::with_capacity(path.len());
    let mut late = Vec::new();
    for (k, (step, state)) in path.iter().enumerate() {
        let name = engine.inspect().system().label_name(step.label);
        let taken = engine.step_as(step.as_step());
        late.extend(
            engine
                .events()
                .filter(|e| matches!(e, crate::Event::ResponseLate { .. }))
                .map(|e| (k + 1, e)),
        );
        match taken {
            // a step into a state with a range error is taken, and stops the engine: the
            // trace ends there, with that range error as its verdict
            Ok(stepped) if engine.inspect().state() == state => {
                steps.push(ReplayedStep { name, stepped })
            }
            Err(StepAsError::TakenThenStopped(_)) if engine.inspect().state() == state => {
                let stepped = engine.stepped_by(step.label);
                steps.push(ReplayedStep { name, stepped })
            }
            Ok(_) | Err(StepAsError::TakenThenStopped(_)) => {
                return Ok(refused_at(
                    engine,
                    steps,
                    k + 1,
                    name,
                    "the engine's step leads elsewhere".into(),
                ));
            }
            // the last step was committed, but a bounded response property cannot be
            // evaluated in the state it leads to, which stops the engine: that is the
            // trace's range error
            Err(StepAsError::Engine(EngineError::Range(e)))
                if k + 1 == path.len()
                    && matches!(trace.verdict, Verdict::RangeError(_))
                    && engine.inspect().state() == state =>
            {
                let stepped = if engine.inspect().system().role(step.label) == Role::Time {
                    Stepped::Tick
                } else {
                    Stepped::Other
                };
                steps.push(ReplayedStep { name, stepped });
                return Ok(Replay {
                    steps,
                    refused: None,
                    end: Some(End::RangeError {
                        message: e.to_string(),
                    }),
                    late,
                    engine,
                });
            }
            Err(e) => {
                let message = match e {
                    StepAsError::NotAllowed => "the engine does not allow it here".into(),
                    other => other.to_string(),
                };
                return Ok(refused_at(engine, steps, k + 1, name, message));
            }
        }
    }
    if let Some(e) = error {
        let name = trace
            .steps
            .get(e.step.wrapping_sub(1))
            .map_or_else(String::new, |s| s.step.clone());
        let mut r = refused_at(engine, steps, e.step, name.clone(), e.message);
        if let Some(refused) = &mut r.refused {
            refused.reasons = reasons_for(&r.engine, &name);
        }
        return Ok(r);
    }
    let end = check_end(&engine, trace, &path);
    Ok(Replay {
        steps,
        refused: None,
        end: Some(end),
        late,
        engine,
    })
}

fn refused_at(
    engine: Engine,
    steps: Vec<ReplayedStep>,
    step: usize,
    name: String,
    message: String,
) -> Replay {
    Replay {
        steps,
        refused: Some(Refused {
            step,
            name,
            message,
            reasons: Vec::new(),
        }),
        end: None,
        late: Vec::new(),
        engine,
    }
}

/// Why the GenoM step named `name` is not allowed now: a request's failing refusals, a
/// codel's failing holds.
fn reasons_for(engine: &Engine, name: &str) -> Vec<String> {
    let system = engine.inspect().system();
    let state = engine.inspect().state();
    let Some(map) = &system.genom else {
        return Vec::new();
    };
    let Some(i) = system.interaction_index(name) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for m in &map.modules {
        for s in &m.services {
            if s.request == Some(i) {
                if let Ok(failed) = s.refused_by(system, state) {
                    out.extend(failed.iter().map(|c| c.to_string()));
                }
            }
            for c in &s.codels {
                if c.run == i || c.fail == i {
                    if let Ok(failed) = c.held_by(system, state) {
                        out.extend(failed.iter().map(|c| c.to_string()));
                    }
                }
            }
        }
    }
    out
}

/// The end of a response property's counterexample: the engine went where the step
/// relation goes, so the path the relation replays is the engine's.
fn unanswered(
    system: &System,
    p: &bip_model::Property,
    trace: &Trace,
    path: &[(OwnedStep, State)],
) -> Result<End, String> {
    trace.check_loop(system, path).map_err(|e| e.message)?;
    let spec = p.kind.response_spec().ok_or("not a response property")?;
    match system.shows_unanswered(spec, path, trace.loop_start, &p.name) {
        Ok(true) => Ok(End::Unanswered {
            property: p.name.clone(),
            loop_start: trace.loop_start,
        }),
        Ok(false) => Err("the trace does not show a trigger left unanswered".into()),
        Err(e) => Err(format!("range error: {e}")),
    }
}

/// The end of a timelock's trace: the last state (where a lasso's cycle returns) is one
/// from which no run fires a tick.
fn timelock(
    system: &System,
    trace: &Trace,
    path: &[(OwnedStep, State)],
    last: &State,
) -> Result<End, String> {
    trace.check_loop(system, path).map_err(|e| e.message)?;
    match system.time_can_pass(last) {
        Ok(Some(false)) => Ok(End::Timelock {
            loop_start: trace.loop_start,
        }),
        Ok(Some(true)) => busy_loop(system, trace, path),
        Ok(None) => Err("the states reachable from the last state are too many to search".into()),
        Err(e) => Err(format!("range error: {e}")),
    }
}

/// A trace of `TimeProgress` whose last state lets time pass in some run: confirmed if it
/// is a lasso none of whose cycle's states has a step of a `Time` connector that fires
/// (a tick in range error lets no time pass, as in the verifier).
fn busy_loop(system: &System, trace: &Trace, path: &[(OwnedStep, State)]) -> Result<End, String> {
    let Some(k) = trace.loop_start else {
        return Err("a run from the last state lets time pass".into());
    };
    // the cycle's states: after step k (its first), ..., after the last (its first again);
    // its steps are the model's own (a cycle of the environment's is its choice)
    for (step, state) in &path[k..] {
        if system.role(step.label) == Role::Environment {
            return Err("the trace's cycle has a step of the environment".into());
        }
        if system
            .ticks_from(state)
            .map_err(|e| format!("range error: {e}"))?
        {
            return Err(
                "a state on the trace's cycle lets time pass, and so does a run from the last state"
                    .into(),
            );
        }
    }
    Ok(End::BusyLoop { loop_start: k })
}

fn check_end(engine: &Engine, trace: &Trace, path: &[(OwnedStep, State)]) -> End {
    let verdict = &trace.verdict;
    let system = engine.inspect().system();
    let state = engine.inspect().state();
    let not = |why: &str| End::NotConfirmed {
        verdict: format!("{verdict:?}"),
        why: why.into(),
    };
    match verdict {
        Verdict::None => End::Recording,
        Verdict::Deadlock => {
            let mut steps = Steps::new();
            let mut checker = LivenessChecker::default();
            let live = system
                .enabled_steps(state, &mut steps)
                .and_then(|()| system.liveness(state, &steps, &mut checker));
            let terminal = system.properties.iter().find_map(|p| match &p.kind {
                PropertyKind::DeadlockFree { terminal } => terminal.as_ref(),
                _ => None,
            });
            let excused = |t: &bip_model::eval::Expr| {
                system.holds(t, state, "terminal condition of DeadlockFree")
            };
            match live {
                Ok(Liveness::Deadlock) if terminal.is_some_and(|t| excused(t) != Ok(false)) => {
                    not("the last state is a deadlock the terminal condition excuses (or cannot evaluate)")
                }
                Ok(Liveness::Deadlock) => {
                    let held = engine
                        .inspect()
                        .outstanding()
                        .unwrap_or_default()
                        .into_iter()
                        .map(|(c, paused, r)| {
                            let (m, s, st) = engine.inspect().codel_name(c);
                            let why: Vec<String> = engine.inspect().hold_texts(c, r).collect();
                            // a task without a period waits for an event of its module
                            let aperiodic = system.genom.as_ref().is_some_and(|g| {
                                g.module(m).zip(g.service(m, s)).is_some_and(|(mm, sv)| {
                                    sv.task
                                        .and_then(|t| mm.tasks.get(t))
                                        .is_some_and(|t| t.period.is_none())
                                })
                            });
                            let wait = match (paused, aperiodic) {
                                (false, _) => "",
                                (true, false) => " (waits for its period)",
                                (true, true) => " (waits for an event of its module)",
                            };
                            if why.is_empty() {
                                format!("{m}.{s} codel `{st}`{wait}")
                            } else {
                                format!("{m}.{s} codel `{st}`{wait}, held by {}", why.join(", "))
                            }
                        })
                        .collect();
                    End::Deadlock { held }
                }
                Ok(Liveness::Unknown) => {
                    not("the time steps from the last state are too many to follow")
                }
                Ok(_) => not("a progress step is enabled in the last state or after ticks"),
                Err(e) => not(&format!("range error: {e}")),
            }
        }
        Verdict::Violation(name) | Verdict::Witness(name) => {
            let Some(p) = system.properties.iter().find(|p| &p.name == name) else {
                if matches!(verdict, Verdict::Violation(n) if n == bip_model::TIME_PROGRESS) {
                    return timelock(system, trace, path, state).unwrap_or_else(|why| not(&why));
                }
                if let Some(of) = name.strip_suffix(WORST_RESPONSE) {
                    if matches!(verdict, Verdict::Witness(_)) {
                        return worst_response(system, trace, name, of)
                            .unwrap_or_else(|why| not(&why));
                    }
                }
                return not("the model has no such property");
            };
            let expr = match &p.kind {
                PropertyKind::Invariant(e) | PropertyKind::Reachable(e) => e,
                PropertyKind::DeadlockFree { .. } => return not("not an invariant"),
                PropertyKind::Response { .. } => {
                    return unanswered(system, p, trace, path).unwrap_or_else(|why| not(&why))
                }
            };
            match (system.holds(expr, state, name), verdict) {
                (Ok(false), Verdict::Violation(_)) => End::Violation {
                    property: name.clone(),
                },
                (Ok(true), Verdict::Witness(_)) => End::Witness {
                    property: name.clone(),
                },
                (Ok(_), _) => not("the property evaluates otherwise in the last state"),
                (Err(e), Verdict::Violation(_)) => End::RangeError {
                    message: e.to_string(),
                },
                (Err(e), _) => not(&format!("range error: {e}")),
            }
        }
        Verdict::RangeError(_) => match system.range_error_from(state) {
            Some(e) => End::RangeError {
                message: e.to_string(),
            },
            None => not("nothing evaluated from the last state has a range error"),
        },
    }
}

/// How the verifier names the witness of a worst response: `m.t worst response`, or a
/// response property's name and this.
const WORST_RESPONSE: &str = " worst response";

/// The end of the run of `of`'s worst response: a task's job end, or any last step for a
/// response property of the model.
fn worst_response(system: &System, trace: &Trace, name: &str, of: &str) -> Result<End, String> {
    let end = End::WorstResponse {
        property: name.to_string(),
    };
    if system
        .properties
        .iter()
        .any(|p| p.name == of && matches!(p.kind, PropertyKind::Response { .. }))
    {
        return Ok(end);
    }
    let task = of.split_once('.').and_then(|(m, t)| {
        let map = system.genom.as_ref()?;
        let module = map.modules.iter().find(|x| x.name == m)?;
        module
            .tasks
            .iter()
            .any(|x| x.name == t)
            .then(|| format!("{m}_{t}_done"))
    });
    let Some(done) = task else {
        return Err(format!("the model has no task or response property `{of}`"));
    };
    match trace.steps.last() {
        Some(last) if last.step == done => Ok(end),
        _ => Err(format!("the last step does not end a job of `{of}`")),
    }
}
