//! A trace in the user's terms: who takes part in each step (a module, or a component of
//! the model's own), what the step is (a request, a codel and the yield it took, a tick,
//! a connector of the user's), and what it changed (an activity's codel state, an ids
//! field, a port's age, a component's location or variable), without the expansion's
//! bookkeeping (`req`, `paused`, the clock's phase) unless asked. The text printout and
//! the sequence chart both read it.

use std::collections::BTreeMap;

use bip_model::genom::{CodelMap, GenomMap};
use bip_model::{Label, OwnedStep, State, System, Trace, Verdict};

use super::timed::{clock_component, Stage, TaskStep, TaskVar, TimedLayer};

/// What a slot of the state stands for.
enum Slot {
    /// Shown under this name, as `name = value` (`name@value` for a location).
    Shown { name: String, location: bool },
    /// A variable of a timed model's task atom ([`TimedLayer::tasks`]), told in words.
    Task { task: usize, var: TaskVar },
    /// The expansion's bookkeeping: shown only with all variables, under its own name.
    Bookkeeping,
}

pub enum Kind {
    Tick,
    Step,
}

pub struct UserStep {
    pub number: usize,
    pub label: String,
    pub kind: Kind,
    /// Indices into [`UserTrace::lifelines`].
    pub lifelines: Vec<usize>,
    pub changes: Vec<String>,
}

pub struct UserTrace {
    pub lifelines: Vec<String>,
    pub steps: Vec<UserStep>,
    /// The last state the trace reaches.
    pub last: State,
}

/// The interactions of a GenoM layer, by what they do. `task`: in a timed model, the
/// atom of the codel's task.
enum Role<'m> {
    Tick,
    Request {
        service: String,
    },
    Codel {
        service: String,
        codel: &'m CodelMap,
        activity: Option<u32>,
        task: Option<u32>,
    },
    Fail {
        service: String,
        codel: &'m str,
        task: Option<u32>,
    },
    /// An async codel's start apart from its task, or its return.
    Apart {
        service: String,
        codel: &'m str,
        returns: bool,
    },
    /// A timed codel's start on its task's core, or its finish after its activity left
    /// it (its outcome dropped).
    Timed {
        service: String,
        codel: &'m str,
        task: u32,
        dropped: bool,
    },
    /// A step of the scheduling of a timed model.
    Schedule(TaskStep),
}

/// A change a step's label already tells: of `slot`, to `value` (`None`: to any).
struct Told {
    slot: u32,
    value: Option<i64>,
}

/// How a model's steps and slots are named.
struct Names<'m> {
    roles: BTreeMap<u32, Role<'m>>,
    timed: Option<TimedLayer>,
}

impl<'m> Names<'m> {
    fn of(system: &'m System) -> Names<'m> {
        let timed = TimedLayer::of(system);
        let roles = system
            .genom
            .as_ref()
            .map(|map| roles(system, map, timed.as_ref()))
            .unwrap_or_default();
        Names { roles, timed }
    }

    /// The step's label, its kind and the changes the label tells; `before` is the state
    /// it leaves. A timed model's time step says how far it goes, its release which
    /// tasks it releases.
    fn label(
        &self,
        system: &System,
        step: &OwnedStep,
        before: &State,
    ) -> Result<(String, Kind, Vec<Told>), String> {
        let role = match step.label {
            Label::Interaction(i) => self.roles.get(&i),
            Label::Internal { .. } => None,
        };
        let (mut label, kind, told) = describe(system, self.timed.as_ref(), step, role, before);
        if let (Some(layer), Kind::Tick) = (&self.timed, &kind) {
            let units = system
                .time_advance(before, step.as_step())
                .map_err(|e| e.to_string())?;
            label = layer.time_passes(before, units);
        }
        Ok((label, kind, told))
    }
}

/// The trace replayed on `system` and named in the user's terms; `all` shows the
/// bookkeeping variables too.
pub fn user_trace(system: &System, trace: &Trace, all: bool) -> Result<UserTrace, String> {
    let path = trace
        .replay(system)
        .map_err(|e| format!("the trace does not fit the model: {e}"))?;
    let names = Names::of(system);
    let (lifelines, lifeline_of) = lifelines(system, names.timed.as_ref());
    let slots = slots(system, names.timed.as_ref());
    let mut before = system.initial_state();
    let mut steps = Vec::with_capacity(path.len());
    for (k, (step, after)) in path.iter().enumerate() {
        let (mut label, kind, told) = names
            .label(system, step, &before)
            .map_err(|e| format!("step {}: {e}", k + 1))?;
        // where time steps of an untimed model may stand for several units, each says how
        // many (a timed model's says how long)
        if names.timed.is_none() && system.has_advance() {
            let units = system
                .time_advance(&before, step.as_step())
                .map_err(|e| format!("step {}: {e}", k + 1))?;
            if units > 0 {
                label = format!("{label} +{units}");
            }
        }
        // a tick is time passing for everyone: a rule, not a synchronisation
        let mut lanes: Vec<usize> = match kind {
            Kind::Tick => Vec::new(),
            Kind::Step => participants(system, step)
                .into_iter()
                .filter_map(|c| lifeline_of[c as usize])
                .collect(),
        };
        lanes.sort_unstable();
        lanes.dedup();
        let mut changes = Vec::new();
        if !matches!(kind, Kind::Tick) || all {
            for (slot, (a, b)) in before.slots().iter().zip(after.slots()).enumerate() {
                let is_told = told
                    .iter()
                    .any(|t| t.slot == slot as u32 && t.value.is_none_or(|v| v == *b));
                if a == b || is_told {
                    continue;
                }
                let value = system.trace_value(after, slot as u32);
                match &slots[slot] {
                    Slot::Shown {
                        name,
                        location: true,
                    } => changes.push(format!("{name}@{value}")),
                    Slot::Shown { name, .. } => changes.push(format!("{name} = {value}")),
                    Slot::Task { task, var } => {
                        if let Some(t) = names.timed.as_ref().map(|l| &l.tasks[*task]) {
                            changes.push(format!("{} {}", t.name, t.tell(*var, *b)));
                        }
                    }
                    Slot::Bookkeeping if all => {
                        changes.push(format!("{} = {value}", system.slot_name(slot as u32)))
                    }
                    Slot::Bookkeeping => {}
                }
            }
        }
        steps.push(UserStep {
            number: k + 1,
            label,
            kind,
            lifelines: lanes,
            changes,
        });
        before = after.clone();
    }
    Ok(UserTrace {
        lifelines,
        steps,
        last: before,
    })
}

/// One lifeline per module (its component and its activities'), then one per component of
/// the model's own (a timed model's task atom under its task's name); the GenoM clock has
/// none (its ticks are rules across the chart).
fn lifelines(system: &System, timed: Option<&TimedLayer>) -> (Vec<String>, Vec<Option<usize>>) {
    let mut names = Vec::new();
    let mut of = vec![None; system.components.len()];
    let mut genom = vec![false; system.components.len()];
    if let Some(map) = &system.genom {
        if let Some(clock) = clock_component(system, map) {
            genom[clock as usize] = true;
        }
        for module in &map.modules {
            let lane = names.len();
            names.push(module.name.clone());
            of[module.component as usize] = Some(lane);
            genom[module.component as usize] = true;
            for s in &module.services {
                if let Some(c) = s.component {
                    of[c as usize] = Some(lane);
                    genom[c as usize] = true;
                }
            }
        }
    }
    for (c, component) in system.components.iter().enumerate() {
        if !genom[c] {
            of[c] = Some(names.len());
            let task = timed.and_then(|l| l.task_of(c as u32));
            names.push(task.map_or_else(|| component.name.clone(), |t| t.name.clone()));
        }
    }
    (names, of)
}

fn roles<'m>(
    system: &System,
    map: &'m GenomMap,
    timed: Option<&TimedLayer>,
) -> BTreeMap<u32, Role<'m>> {
    let mut out = BTreeMap::new();
    out.insert(map.tick, Role::Tick);
    for module in &map.modules {
        for s in &module.services {
            let service = format!("{}.{}", module.name, s.name);
            let task = s
                .task
                .and_then(|t| module.tasks.get(t)?.timed)
                .map(|t| t.component);
            if let Some(r) = s.request {
                out.insert(
                    r,
                    Role::Request {
                        service: service.clone(),
                    },
                );
            }
            for codel in &s.codels {
                out.insert(
                    codel.run,
                    Role::Codel {
                        service: service.clone(),
                        codel,
                        activity: s.component,
                        task,
                    },
                );
                out.insert(
                    codel.fail,
                    Role::Fail {
                        service: service.clone(),
                        codel: &codel.state,
                        task,
                    },
                );
                if let Some(apart) = codel.apart {
                    for (i, returns) in [(apart.start, false), (apart.returned, true)] {
                        out.insert(
                            i,
                            Role::Apart {
                                service: service.clone(),
                                codel: &codel.state,
                                returns,
                            },
                        );
                    }
                }
                let (Some(steps), Some(task)) = (codel.timed, task) else {
                    continue;
                };
                let dropped = steps.dropped.map(|i| (i, true));
                for (i, dropped) in std::iter::once((steps.start, false)).chain(dropped) {
                    out.insert(
                        i,
                        Role::Timed {
                            service: service.clone(),
                            codel: &codel.state,
                            task,
                            dropped,
                        },
                    );
                }
            }
        }
    }
    if let Some(layer) = timed {
        for i in 0..system.interactions.len() as u32 {
            if out.contains_key(&i) {
                continue;
            }
            if let Some(step) = layer.step_of(system, i) {
                out.insert(i, Role::Schedule(step));
            }
        }
    }
    out
}

/// The step's label, kind, and the changes its label already tells (the activity's codel
/// state after a codel, its task's stage or codel in a timed model).
fn describe(
    system: &System,
    timed: Option<&TimedLayer>,
    step: &OwnedStep,
    role: Option<&Role>,
    before: &State,
) -> (String, Kind, Vec<Told>) {
    let task = |c: u32| timed.and_then(|l| l.task_of(c));
    let name = |c: u32| {
        task(c).map_or_else(
            || system.components[c as usize].name.clone(),
            |t| t.name.clone(),
        )
    };
    let told = |c: u32, var: TaskVar, value: Option<i64>| {
        task(c)
            .and_then(|t| t.slot(system, var))
            .map(|slot| Told { slot, value })
    };
    let stage = |c: u32, stage: Stage| told(c, TaskVar::Stage, Some(stage.value()));
    // a codel's finish frees its task's core
    let freed = |t: &Option<u32>| t.and_then(|c| told(c, TaskVar::Codel, Some(0)));
    let named = |label: String, told: Vec<Option<Told>>| {
        (label, Kind::Step, told.into_iter().flatten().collect())
    };
    match role {
        Some(Role::Tick) => ("tick".into(), Kind::Tick, Vec::new()),
        Some(Role::Request { service }) => named(format!("request {service}"), vec![]),
        Some(Role::Fail {
            service,
            codel,
            task,
        }) => named(format!("{service}: {codel} throws"), vec![freed(task)]),
        Some(Role::Apart {
            service,
            codel,
            returns,
        }) => {
            let what = if *returns { "returns" } else { "starts apart" };
            named(format!("{service}: {codel} {what}"), vec![])
        }
        Some(Role::Codel {
            service,
            codel,
            activity,
            task,
        }) => {
            let taken = codel.yields.iter().find(|y| {
                step.picks.iter().any(|p| {
                    Some(p.component) == *activity && y.transitions.contains(&p.transition)
                })
            });
            let label = match taken {
                Some(y) => format!("{service}: {} → {}", codel.state, y.target),
                None => format!("{service}: {}", codel.state),
            };
            let state = activity.map(|c| Told {
                slot: system.components[c as usize].slot,
                value: None,
            });
            named(label, vec![state, freed(task)])
        }
        Some(Role::Timed {
            service,
            codel,
            task,
            dropped: false,
        }) => named(
            format!("{service}: {codel} starts"),
            vec![told(*task, TaskVar::Codel, None)],
        ),
        Some(Role::Timed {
            service,
            codel,
            task,
            dropped: true,
        }) => named(
            format!("{service}: {codel}'s outcome dropped"),
            vec![freed(&Some(*task))],
        ),
        Some(Role::Schedule(s)) => match *s {
            TaskStep::Dispatch(t) => named(
                format!("dispatch {}", name(t)),
                vec![stage(t, Stage::Running)],
            ),
            TaskStep::Done(t) => named(
                format!("{}: job done", name(t)),
                vec![stage(t, Stage::Idle)],
            ),
            TaskStep::Yield(t) => named(
                format!("{} yields its core", name(t)),
                vec![stage(t, Stage::Ready)],
            ),
            TaskStep::Preempts { by, task } => named(
                format!("{} preempts {}", name(by), name(task)),
                vec![stage(by, Stage::Running), stage(task, Stage::Ready)],
            ),
            TaskStep::Release => {
                let released: Vec<&str> = timed
                    .map(|l| l.at_boundary(before).map(|t| t.name.as_str()).collect())
                    .unwrap_or_default();
                let label = match released[..] {
                    [] => "release".to_string(),
                    _ => format!("release {}", released.join(", ")),
                };
                named(label, vec![])
            }
        },
        None => named(system.label_name(step.label), vec![]),
    }
}

/// The components a step synchronises.
fn participants(system: &System, step: &OwnedStep) -> Vec<u32> {
    match step.label {
        Label::Internal { component } => vec![component],
        Label::Interaction(_) if !step.picks.is_empty() => {
            step.picks.iter().map(|p| p.component).collect()
        }
        Label::Interaction(i) => system.interactions[i as usize]
            .ports
            .iter()
            .map(|p| p.component)
            .collect(),
    }
}

/// What each slot of the state stands for, in the user's names.
fn slots(system: &System, timed: Option<&TimedLayer>) -> Vec<Slot> {
    let mut out: Vec<Slot> = (0..system.slot_count() as u32)
        .map(|slot| {
            if system.is_bookkeeping(slot) {
                return Slot::Bookkeeping;
            }
            let c = system.component_of_slot(slot);
            Slot::Shown {
                name: system.slot_name(slot),
                location: slot == system.components[c as usize].slot,
            }
        })
        .collect();
    let Some(map) = &system.genom else {
        return out;
    };
    // a GenoM component's slots are bookkeeping unless named below
    if let Some(clock) = clock_component(system, map) {
        bookkeeping(system, clock, &mut out);
    }
    for module in &map.modules {
        bookkeeping(system, module.component, &mut out);
        for field in &module.ids {
            out[field.slot as usize] = Slot::Shown {
                name: format!("{}.{}", module.name, field.name),
                location: false,
            };
        }
        for port in &module.ports {
            if let Some(age) = &port.age {
                out[age.slot as usize] = Slot::Shown {
                    name: format!("age({}.{})", module.name, port.name),
                    location: false,
                };
            }
        }
        for s in &module.services {
            let Some(c) = s.component else { continue };
            bookkeeping(system, c, &mut out);
            out[system.components[c as usize].slot as usize] = Slot::Shown {
                name: format!("{}.{}", module.name, s.name),
                location: true,
            };
        }
    }
    for (k, task) in timed.iter().flat_map(|l| l.tasks.iter().enumerate()) {
        bookkeeping(system, task.component, &mut out);
        for (slot, var) in task.told_slots(system) {
            out[slot as usize] = Slot::Task { task: k, var };
        }
    }
    out
}

fn bookkeeping(system: &System, component: u32, out: &mut [Slot]) {
    let first = system.components[component as usize].slot as usize;
    let vars = system.atom_of(component).vars.len();
    for slot in out.iter_mut().skip(first).take(vars + 1) {
        *slot = Slot::Bookkeeping;
    }
}

/// The trace's verdict in words.
pub fn verdict(trace: &Trace) -> String {
    match &trace.verdict {
        Verdict::Deadlock => "deadlock".to_string(),
        Verdict::Violation(p) => format!("violation of {p}"),
        Verdict::Witness(p) => format!("witness for {p}"),
        Verdict::RangeError(m) => format!("range error: {m}"),
        Verdict::None => "recording".to_string(),
    }
}

/// A part of a state shown together: a module (its activities' codel states, its ids
/// fields, its ports' ages) or a component of the model's own.
pub struct StateGroup {
    pub name: String,
    /// `(name, value)`; a location's name is the component's (or the activity's).
    pub entries: Vec<(String, String)>,
}

/// A state in the user's terms, grouped as a trace's lifelines are; `all` shows the
/// bookkeeping variables too.
pub fn user_state(system: &System, state: &State, all: bool) -> Vec<StateGroup> {
    let timed = TimedLayer::of(system);
    let (names, of) = lifelines(system, timed.as_ref());
    let slots = slots(system, timed.as_ref());
    let mut groups: Vec<StateGroup> = names
        .into_iter()
        .map(|name| StateGroup {
            name,
            entries: Vec::new(),
        })
        .collect();
    let pending = pending_requests(system, state);
    for (slot, what) in slots.iter().enumerate() {
        let slot = slot as u32;
        let c = system.component_of_slot(slot);
        let Some(group) = of[c as usize] else {
            continue;
        };
        let (name, mut value) = match what {
            Slot::Shown { name, .. } => (name.clone(), system.trace_value(state, slot).to_string()),
            Slot::Task { task, var } => {
                let Some(t) = timed.as_ref().map(|l| &l.tasks[*task]) else {
                    continue;
                };
                let value = t.tell(*var, state.slots()[slot as usize]);
                (t.name.clone(), value)
            }
            Slot::Bookkeeping if all => (
                system.slot_name(slot),
                system.trace_value(state, slot).to_string(),
            ),
            Slot::Bookkeeping => continue,
        };
        if slot == system.components[c as usize].slot && pending.contains(&c) {
            value.push_str(", requested");
        }
        groups[group].entries.push((name, value));
    }
    groups
}

/// The GenoM activities with a request waiting to be taken (the expansion's `req`).
fn pending_requests(system: &System, state: &State) -> Vec<u32> {
    let Some(map) = &system.genom else {
        return Vec::new();
    };
    map.modules
        .iter()
        .flat_map(|m| &m.services)
        .filter_map(|s| s.component)
        .filter(|&c| {
            let atom = system.atom_of(c);
            atom.vars
                .iter()
                .position(|v| v.name == "req")
                .is_some_and(|k| system.value(state, c, k as u32) != 0)
        })
        .collect()
}

/// Each step's label as a trace shows it (`request nav.GoTo`, `nav.GoTo: start → drive`,
/// `tick`, a connector of the user's, in a timed model `dispatch nav.plan`, `time passes
/// 500 µs: 4 ms → 4.5 ms`), each leaving the state of `befores` at its index; a step
/// whose advance is a range error keeps its plain name.
pub fn step_labels(system: &System, steps: &[OwnedStep], befores: &[&State]) -> Vec<String> {
    let names = Names::of(system);
    steps
        .iter()
        .zip(befores)
        .map(|(step, before)| match names.label(system, step, before) {
            Ok((label, ..)) => label,
            Err(_) => system.label_name(step.label),
        })
        .collect()
}
