//! The engine's map of a GenoM layer: for each codel, the interactions that run it and the
//! transition of each yield; for each service, its request interaction and the conditions
//! that can refuse it; for each task, its period; the tick. This is the contract between
//! the expansion and `bip-engine` (docs/genom.md, "The engine's map").
//!
//! The expansion writes the map with names (a recipe); once the expanded model is
//! compiled, the names become indices into the [`System`]: the [`GenomMap`].

use crate::eval;
use crate::state::State;
use crate::syntax::{ServiceKind, Text};
use crate::system::{RangeError, System};

/// The GenoM layer of a compiled system, in the system's indices.
#[derive(Clone, Debug)]
pub struct GenomMap {
    /// The clock tick interaction (role `Time`): the engine fires it once per `tick_ms`.
    pub tick: u32,
    /// Real time of one tick in milliseconds (`tick_ms` of the model), if given.
    pub tick_ms: Option<u64>,
    pub modules: Vec<ModuleMap>,
    /// "No activity has work outstanding" (every activity at `ether` and not requested),
    /// which `DeadlockFree` excuses when requests come from the environment; `None` if
    /// the model has no activity or its requests all come from components of the model.
    pub idle: Option<eval::Expr>,
}

#[derive(Clone, Debug)]
pub struct ModuleMap {
    pub name: String,
    /// The module's component: its ids, port ages, and the request ports of its
    /// functions and attributes.
    pub component: u32,
    pub tasks: Vec<TaskMap>,
    pub ports: Vec<PortMap>,
    pub services: Vec<ServiceMap>,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TaskMap {
    pub name: String,
    /// In ticks.
    pub period: u32,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PortMap {
    pub name: String,
    /// Where the port's age lives, if any expression or constraint reads it.
    pub age: Option<AgeMap>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AgeMap {
    /// The state slot of the age (ticks since a codel that writes the port last ended).
    pub slot: u32,
    /// The age saturates at this value, which also stands for "never written".
    pub cap: i64,
}

#[derive(Clone, Debug)]
pub struct ServiceMap {
    pub name: String,
    pub kind: ServiceKind,
    /// Index of the activity's task in [`ModuleMap::tasks`].
    pub task: Option<usize>,
    /// The activity's component; `None` for functions and attributes.
    pub component: Option<u32>,
    /// The interaction that accepts a request.
    pub request: u32,
    /// True if a component of the model sends the requests (a user connector took the
    /// request connector over with a role other than `Environment`): the engine must
    /// not send them itself.
    pub owned_by_model: bool,
    /// What must hold for a request to be accepted; the failed ones say why it is refused.
    pub refusals: Vec<Condition>,
    /// Services (of the same module) a request interrupts.
    pub interrupts: Vec<String>,
    pub codels: Vec<CodelMap>,
}

#[derive(Clone, Debug)]
pub struct CodelMap {
    /// The codel state, as bound by the engine: `("module", "Service", state)`.
    pub state: String,
    /// The interaction of the codel's normal outcomes: one step per yield.
    pub run: u32,
    /// The interaction of the codel's error path: it ends with one of its `throws`, or the
    /// engine found it faulty (a panic, an undeclared yield, an ids value out of range).
    /// The activity ends without success.
    pub fail: u32,
    pub yields: Vec<YieldMap>,
    pub throws: Vec<String>,
    pub writes: Vec<String>,
    /// What must hold for the codel to run; the failed ones say why it is held.
    pub holds: Vec<Condition>,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct YieldMap {
    /// As written: `"main"`, `"pause::main"` or `"ether"`.
    pub target: String,
    /// The transitions of the activity's atom that take this yield (one per place the
    /// codel runs from: its location, and `ether` for `start`). A step of [`CodelMap::run`]
    /// takes this yield if the activity's pick is one of them.
    pub transitions: Vec<u32>,
}

/// A condition of a request or a codel, with the reason it stands for.
#[derive(Clone, Debug)]
pub struct Condition {
    pub reason: Reason,
    /// The condition as an expression of the expanded model.
    pub text: String,
    pub expr: eval::Expr,
}

impl Condition {
    pub fn holds(&self, system: &System, state: &State) -> Result<bool, RangeError> {
        system.holds(&self.expr, state, &self.text)
    }
}

/// Why a request is refused or a codel held.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Reason {
    /// The activity is already requested or active and does not interrupt itself.
    AlreadyRequested,
    /// `after`: this service has not completed successfully yet.
    After { service: String },
    /// The activity waits for a service it interrupts to end.
    Interrupting { service: String },
    /// The constraint at this index of the model's `constraints`.
    Constraint { index: usize, kind: String },
    /// The guard of a user connector that extends the request connector.
    Connector,
}

impl std::fmt::Display for Reason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Reason::AlreadyRequested => f.write_str("already requested or active"),
            Reason::After { service } => write!(f, "after {service}"),
            Reason::Interrupting { service } => write!(f, "waits for {service} to end"),
            Reason::Constraint { index, kind } => write!(f, "constraint #{index} ({kind})"),
            Reason::Connector => f.write_str("the guard of the extending connector"),
        }
    }
}

impl GenomMap {
    pub fn module(&self, name: &str) -> Option<&ModuleMap> {
        self.modules.iter().find(|m| m.name == name)
    }

    pub fn service(&self, module: &str, service: &str) -> Option<&ServiceMap> {
        self.module(module)?
            .services
            .iter()
            .find(|s| s.name == service)
    }

    /// The codel the engine binds as `(module, service, state)`.
    pub fn codel(&self, module: &str, service: &str, state: &str) -> Option<&CodelMap> {
        self.service(module, service)?
            .codels
            .iter()
            .find(|c| c.state == state)
    }
}

impl ServiceMap {
    /// The conditions that refuse a request in `state` (empty: the request is accepted,
    /// unless a user port of an extending connector is not ready).
    pub fn refused_by(
        &self,
        system: &System,
        state: &State,
    ) -> Result<Vec<&Condition>, RangeError> {
        failed(&self.refusals, system, state)
    }
}

impl CodelMap {
    /// The conditions that hold the codel back in `state`.
    pub fn held_by(&self, system: &System, state: &State) -> Result<Vec<&Condition>, RangeError> {
        failed(&self.holds, system, state)
    }

    /// The yield a transition of the activity's atom takes.
    pub fn yield_of(&self, transition: u32) -> Option<&YieldMap> {
        self.yields
            .iter()
            .find(|y| y.transitions.contains(&transition))
    }
}

fn failed<'c>(
    conds: &'c [Condition],
    system: &System,
    state: &State,
) -> Result<Vec<&'c Condition>, RangeError> {
    let mut out = Vec::new();
    for c in conds {
        if !c.holds(system, state)? {
            out.push(c);
        }
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------------
// The recipe: the same, by names, as the expansion writes it.

#[derive(Clone, Debug, Default)]
pub(crate) struct Recipe {
    pub tick: String,
    pub modules: Vec<RecipeModule>,
    pub idle: Option<String>,
}

#[derive(Clone, Debug)]
pub(crate) struct RecipeModule {
    pub name: String,
    pub tasks: Vec<(String, i64)>,
    /// Port names and their age caps, for ports whose age is tracked.
    pub ports: Vec<(String, Option<i64>)>,
    pub services: Vec<RecipeService>,
}

#[derive(Clone, Debug)]
pub(crate) struct RecipeService {
    pub name: String,
    pub kind: ServiceKind,
    pub task: Option<usize>,
    pub component: Option<String>,
    pub request: String,
    pub owned_by_model: bool,
    pub refusals: Vec<RecipeCondition>,
    pub interrupts: Vec<String>,
    pub codels: Vec<RecipeCodel>,
}

#[derive(Clone, Debug)]
pub(crate) struct RecipeCodel {
    pub state: String,
    pub run: String,
    pub fail: String,
    /// The yields as written, in order: the transitions of the codel's port from each
    /// source location are generated in this order.
    pub yields: Vec<String>,
    /// The codel runs from `ether` (it is `start`) and/or from its own location.
    pub from_ether: bool,
    pub from_location: bool,
    pub throws: Vec<String>,
    pub writes: Vec<String>,
    pub holds: Vec<RecipeCondition>,
}

#[derive(Clone, Debug)]
pub(crate) struct RecipeCondition {
    pub reason: Reason,
    /// The condition as an expression of the expanded model.
    pub text: String,
    /// The same, to compile (its span leads back to the user's text it holds, if any).
    pub compiled: Text,
}

/// Something in the recipe that the compiled system lacks: a bug of the expansion.
#[derive(Debug)]
pub(crate) struct MissingName(pub String);

impl Recipe {
    /// The condition texts, in the order [`Recipe::resolve`] expects them compiled.
    pub fn condition_texts(&self) -> Vec<Text> {
        let mut out = Vec::new();
        for m in &self.modules {
            for s in &m.services {
                out.extend(s.refusals.iter().map(|c| c.compiled.clone()));
                for c in &s.codels {
                    out.extend(c.holds.iter().map(|h| h.compiled.clone()));
                }
            }
        }
        if let Some(i) = &self.idle {
            out.push(Text::from(i.as_str()));
        }
        out
    }

    /// Resolves names into `system`'s indices; `exprs` are the compiled
    /// [`Recipe::condition_texts`].
    pub fn resolve(
        &self,
        system: &System,
        exprs: Vec<eval::Expr>,
    ) -> Result<GenomMap, MissingName> {
        let missing = |what: &str| MissingName(what.to_string());
        let mut exprs = exprs.into_iter();
        let mut next = |text: &str| exprs.next().ok_or_else(|| missing(text));
        let interaction = |name: &str| system.interaction_index(name).ok_or_else(|| missing(name));
        let component = |name: &str| system.component_index(name).ok_or_else(|| missing(name));
        let mut modules = Vec::new();
        for m in &self.modules {
            let mc = component(&m.name)?;
            let atom = system.atom_of(mc);
            let mut ports = Vec::new();
            for (p, cap) in &m.ports {
                let age = match cap {
                    None => None,
                    Some(cap) => {
                        let var = atom
                            .var_index(&super::names::age_var(p))
                            .ok_or_else(|| missing(p))?;
                        Some(AgeMap {
                            slot: system.components[mc as usize].var_slot(var),
                            cap: *cap,
                        })
                    }
                };
                ports.push(PortMap {
                    name: p.clone(),
                    age,
                });
            }
            let mut services = Vec::new();
            for s in &m.services {
                let mut refusals = Vec::new();
                for c in &s.refusals {
                    refusals.push(Condition {
                        reason: c.reason.clone(),
                        text: c.text.clone(),
                        expr: next(&c.text)?,
                    });
                }
                let comp = match &s.component {
                    Some(c) => Some(component(c)?),
                    None => None,
                };
                let mut codels = Vec::new();
                for c in &s.codels {
                    let mut holds = Vec::new();
                    for h in &c.holds {
                        holds.push(Condition {
                            reason: h.reason.clone(),
                            text: h.text.clone(),
                            expr: next(&h.text)?,
                        });
                    }
                    let ac = comp.ok_or_else(|| missing(&c.state))?;
                    let atom = system.atom_of(ac);
                    let port = atom.port_index(&c.state).ok_or_else(|| missing(&c.state))?;
                    let mut sources = Vec::new();
                    if c.from_ether {
                        sources.push(
                            atom.location_index(super::check::ETHER)
                                .ok_or_else(|| missing("ether"))?,
                        );
                    }
                    if c.from_location {
                        sources.push(
                            atom.location_index(&c.state)
                                .ok_or_else(|| missing(&c.state))?,
                        );
                    }
                    let yields = c
                        .yields
                        .iter()
                        .enumerate()
                        .map(|(k, y)| {
                            let transitions = sources
                                .iter()
                                .map(|&l| atom.transitions_from(l, Some(port)).start + k as u32)
                                .collect();
                            YieldMap {
                                target: y.clone(),
                                transitions,
                            }
                        })
                        .collect();
                    codels.push(CodelMap {
                        state: c.state.clone(),
                        run: interaction(&c.run)?,
                        fail: interaction(&c.fail)?,
                        yields,
                        throws: c.throws.clone(),
                        writes: c.writes.clone(),
                        holds,
                    });
                }
                services.push(ServiceMap {
                    name: s.name.clone(),
                    kind: s.kind,
                    task: s.task,
                    component: comp,
                    request: interaction(&s.request)?,
                    owned_by_model: s.owned_by_model,
                    refusals,
                    interrupts: s.interrupts.clone(),
                    codels,
                });
            }
            modules.push(ModuleMap {
                name: m.name.clone(),
                component: mc,
                tasks: m
                    .tasks
                    .iter()
                    .map(|(n, p)| TaskMap {
                        name: n.clone(),
                        period: u32::try_from(*p).unwrap_or(u32::MAX),
                    })
                    .collect(),
                ports,
                services,
            });
        }
        let idle = match &self.idle {
            Some(i) => Some(next(i)?),
            None => None,
        };
        Ok(GenomMap {
            tick: interaction(&self.tick)?,
            tick_ms: system.tick_ms,
            modules,
            idle,
        })
    }
}
