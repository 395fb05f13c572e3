//! A trace in the user's terms: who takes part in each step (a module, or a component of
//! the model's own), what the step is (a request, a codel and the yield it took, a tick,
//! a connector of the user's), and what it changed (an activity's codel state, an ids
//! field, a port's age, a component's location or variable), without the expansion's
//! bookkeeping (`req`, `paused`, the clock's phase) unless asked. The text printout and
//! the sequence chart both read it.

use std::collections::BTreeMap;

use bip_model::genom::{CodelMap, GenomMap};
use bip_model::{Label, OwnedStep, State, System, Trace, Verdict};

/// What a slot of the state stands for.
enum Slot {
    /// Shown under this name, as `name = value` (`name@value` for a location).
    Shown { name: String, location: bool },
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

/// The interactions of a GenoM layer, by what they do.
enum Role<'m> {
    Tick,
    Request {
        service: String,
    },
    Codel {
        service: String,
        codel: &'m CodelMap,
        activity: Option<u32>,
    },
    Fail {
        service: String,
        codel: &'m str,
    },
    /// An async codel's start apart from its task, or its return.
    Apart {
        service: String,
        codel: &'m str,
        returns: bool,
    },
}

/// The trace replayed on `system` and named in the user's terms; `all` shows the
/// bookkeeping variables too.
pub fn user_trace(system: &System, trace: &Trace, all: bool) -> Result<UserTrace, String> {
    let path = trace
        .replay(system)
        .map_err(|e| format!("the trace does not fit the model: {e}"))?;
    let (lifelines, lifeline_of) = lifelines(system);
    let roles = system.genom.as_ref().map(roles).unwrap_or_default();
    let slots = slots(system);
    let mut before = system.initial_state();
    let mut steps = Vec::with_capacity(path.len());
    let advance = system.has_advance();
    for (k, (step, after)) in path.iter().enumerate() {
        let role = match step.label {
            Label::Interaction(i) => roles.get(&i),
            Label::Internal { .. } => None,
        };
        let (mut label, kind, shown_elsewhere) = describe(system, step, role);
        // where time steps may stand for several units, each says how many
        if advance {
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
                if a == b || Some(slot as u32) == shown_elsewhere {
                    continue;
                }
                let value = system.trace_value(after, slot as u32);
                match &slots[slot] {
                    Slot::Shown {
                        name,
                        location: true,
                    } => changes.push(format!("{name}@{value}")),
                    Slot::Shown { name, .. } => changes.push(format!("{name} = {value}")),
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
/// the model's own; the GenoM clock has none (its ticks are rules across the chart).
fn lifelines(system: &System) -> (Vec<String>, Vec<Option<usize>>) {
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
            names.push(component.name.clone());
        }
    }
    (names, of)
}

/// The GenoM clock: the trigger of the tick.
pub(super) fn clock_component(system: &System, map: &GenomMap) -> Option<u32> {
    let tick = system.interactions.get(map.tick as usize)?;
    let trigger = tick.trigger? as usize;
    Some(tick.ports.get(trigger)?.component)
}

fn roles(map: &GenomMap) -> BTreeMap<u32, Role<'_>> {
    let mut out = BTreeMap::new();
    out.insert(map.tick, Role::Tick);
    for module in &map.modules {
        for s in &module.services {
            let service = format!("{}.{}", module.name, s.name);
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
                    },
                );
                out.insert(
                    codel.fail,
                    Role::Fail {
                        service: service.clone(),
                        codel: &codel.state,
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
            }
        }
    }
    out
}

/// The step's label, kind, and the slot its label already tells (the activity's codel
/// state, after a codel).
fn describe(system: &System, step: &OwnedStep, role: Option<&Role>) -> (String, Kind, Option<u32>) {
    let plain = system.label_name(step.label);
    match role {
        Some(Role::Tick) => ("tick".into(), Kind::Tick, None),
        Some(Role::Request { service }) => (format!("request {service}"), Kind::Step, None),
        Some(Role::Fail { service, codel }) => {
            (format!("{service}: {codel} throws"), Kind::Step, None)
        }
        Some(Role::Apart {
            service,
            codel,
            returns,
        }) => {
            let what = if *returns { "returns" } else { "starts apart" };
            (format!("{service}: {codel} {what}"), Kind::Step, None)
        }
        Some(Role::Codel {
            service,
            codel,
            activity,
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
            let slot = activity.map(|c| system.components[c as usize].slot);
            (label, Kind::Step, slot)
        }
        None => (plain, Kind::Step, None),
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
fn slots(system: &System) -> Vec<Slot> {
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
    let (names, of) = lifelines(system);
    let slots = slots(system);
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
        let name = match what {
            Slot::Shown { name, .. } => name.clone(),
            Slot::Bookkeeping if all => system.slot_name(slot),
            Slot::Bookkeeping => continue,
        };
        let mut value = system.trace_value(state, slot).to_string();
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
/// `tick`, a connector of the user's).
pub fn step_labels(system: &System, steps: &[OwnedStep]) -> Vec<String> {
    let roles = system.genom.as_ref().map(roles).unwrap_or_default();
    steps
        .iter()
        .map(|step| {
            let role = match step.label {
                Label::Interaction(i) => roles.get(&i),
                Label::Internal { .. } => None,
            };
            describe(system, step, role).0
        })
        .collect()
}
