//! The engine's map by names, as the expansion writes it (a recipe); once the expanded
//! model is compiled, [`Recipe::resolve`] turns the names into the system's indices.

use super::names;
use super::timing::Timing;
use crate::expr::Expr;
use crate::syntax::ServiceKind;
use bip_model::eval;
use bip_model::genom::map::*;
use bip_model::System;

#[derive(Clone, Debug, Default)]
pub(crate) struct Recipe {
    pub tick: String,
    pub modules: Vec<RecipeModule>,
    pub idle: Option<Expr>,
    pub timing: Timing,
    /// A timed model's time unit in microseconds.
    pub time_unit_us: Option<u64>,
    /// A timed model's pinned cores, by module and task.
    pub cores: Vec<Vec<Option<u32>>>,
}

#[derive(Clone, Debug)]
pub(crate) struct RecipeModule {
    pub name: String,
    pub tasks: Vec<(String, Option<i64>)>,
    /// Each task's `delay` in ticks.
    pub delays: Vec<i64>,
    /// Port names and their age caps, for ports whose age is tracked.
    pub ports: Vec<(String, Option<i64>)>,
    /// The declared type of each port's data.
    pub port_types: Vec<Option<DataType>>,
    /// The in ports, with their declared types and the `(module, port)` each reads.
    pub in_ports: Vec<InPortMap>,
    /// Ids field names, in order.
    pub ids: Vec<String>,
    pub services: Vec<RecipeService>,
}

#[derive(Clone, Debug)]
pub(crate) struct RecipeService {
    pub name: String,
    pub kind: ServiceKind,
    pub task: Option<usize>,
    pub component: Option<String>,
    /// The request connector; `None` for a task's machine, which nothing requests.
    pub request: Option<String>,
    /// The connector by which a pending request interrupts again (`None` if the service
    /// interrupts no other activity).
    pub interrupt: Option<String>,
    pub owned_by_model: bool,
    pub refusals: Vec<RecipeCondition>,
    pub interrupts: Vec<String>,
    pub codels: Vec<RecipeCodel>,
    /// A function's codel and a `validate` codel, whose success is the request.
    pub function: Option<RecipeCodel>,
    pub validate: Option<RecipeCodel>,
    pub args: Option<DataType>,
    pub output: Option<DataType>,
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
    /// Written ids fields, in the module's order, and the module port that writes them.
    pub ids: Vec<String>,
    pub ids_port: Option<String>,
    pub holds: Vec<RecipeCondition>,
    /// An async codel's start and return connectors.
    pub apart: Option<(String, String)>,
}

#[derive(Clone, Debug)]
pub(crate) struct RecipeCondition {
    pub reason: Reason,
    /// The condition as an expression of the expanded model (a user's subtree in it keeps
    /// its position in the file).
    pub expr: Expr,
}

/// Something in the recipe that the compiled system lacks: a bug of the expansion.
#[derive(Debug)]
pub(crate) struct MissingName(pub String);

impl Recipe {
    /// The conditions, in the order [`Recipe::resolve`] expects them compiled.
    pub fn conditions(&self) -> Vec<Expr> {
        let mut out = Vec::new();
        for m in &self.modules {
            for s in &m.services {
                out.extend(s.refusals.iter().map(|c| c.expr.clone()));
                for c in &s.codels {
                    out.extend(c.holds.iter().map(|h| h.expr.clone()));
                }
            }
        }
        out.extend(self.idle.clone());
        out
    }

    /// Resolves names into `system`'s indices; `exprs` are the compiled
    /// [`Recipe::conditions`].
    pub fn resolve(
        &self,
        system: &System,
        exprs: Vec<eval::Expr>,
    ) -> Result<GenomMap, MissingName> {
        let missing = |what: &str| MissingName(what.to_string());
        let mut exprs = exprs.into_iter();
        let mut next = |what: &str| exprs.next().ok_or_else(|| missing(what));
        let interaction = |name: &str| system.interaction_index(name).ok_or_else(|| missing(name));
        let component = |name: &str| system.component_index(name).ok_or_else(|| missing(name));
        let mut modules = Vec::new();
        for (mi, m) in self.modules.iter().enumerate() {
            let mc = component(&m.name)?;
            let atom = system.atom_of(mc);
            let mut ports = Vec::new();
            for ((p, cap), ty) in m.ports.iter().zip(&m.port_types) {
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
                    ty: ty.clone(),
                    age,
                });
            }
            let mut ids = Vec::new();
            for x in &m.ids {
                let var = atom.var_index(x).ok_or_else(|| missing(x))?;
                let ty = &atom.vars[var as usize].ty;
                let (lo, hi) = ty.range();
                ids.push(IdsField {
                    name: x.clone(),
                    var,
                    slot: system.components[mc as usize].var_slot(var),
                    lo,
                    hi,
                    is_bool: *ty == bip_model::VarType::Bool,
                });
            }
            let mut services = Vec::new();
            for s in &m.services {
                let mut refusals = Vec::new();
                for c in &s.refusals {
                    let text = c.expr.to_string();
                    refusals.push(Condition {
                        reason: c.reason.clone(),
                        expr: next(&text)?,
                        text,
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
                        let text = h.expr.to_string();
                        holds.push(Condition {
                            reason: h.reason.clone(),
                            expr: next(&text)?,
                            text,
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
                    let matom = system.atom_of(mc);
                    let ids_transitions = match &c.ids_port {
                        None => 0..0,
                        Some(p) => {
                            let port = matom.port_index(p).ok_or_else(|| missing(p))?;
                            matom.transitions_from(0, Some(port))
                        }
                    };
                    let ids = ids_writes(system, mc, &c.ids)?;
                    if !ids.is_empty() && written_values(&ids)? as usize != ids_transitions.len() {
                        return Err(missing("the transitions that write ids"));
                    }
                    let codel_key = (m.name.clone(), s.name.clone(), c.state.clone());
                    codels.push(CodelMap {
                        state: c.state.clone(),
                        run: interaction(&c.run)?,
                        fail: interaction(&c.fail)?,
                        yields,
                        throws: c.throws.clone(),
                        writes: c.writes.clone(),
                        ids,
                        ids_transitions,
                        holds,
                        wcet_us: self.timing.wcets.get(&codel_key).copied(),
                        bcet_us: self.timing.bcets.get(&codel_key).copied(),
                        apart: match &c.apart {
                            Some((start, ret)) => Some(Apart {
                                start: interaction(start)?,
                                returned: interaction(ret)?,
                            }),
                            None => None,
                        },
                        timed: match self.time_unit_us {
                            Some(_) => Some(TimedCodelMap {
                                start: interaction(&names::start_connector(
                                    &m.name, &s.name, &c.state,
                                ))?,
                                dropped: system.interaction_index(&names::dropped_connector(
                                    &m.name, &s.name, &c.state,
                                )),
                            }),
                            None => None,
                        },
                    });
                }
                let at_request = |c: &RecipeCodel| -> Result<CodelMap, MissingName> {
                    let matom = system.atom_of(mc);
                    let port = |p: &str| matom.port_index(p).ok_or_else(|| missing(p));
                    // the function's normal outcomes: its port's transitions (one per
                    // combination of the ids values it writes); a validation's success
                    // is any step of the request
                    let ok = match c.state == super::check::VALIDATE {
                        true => 0..0,
                        false => matom.transitions_from(0, Some(port(&s.name)?)),
                    };
                    let ids = ids_writes(system, mc, &c.ids)?;
                    if !ids.is_empty() && written_values(&ids)? as usize != ok.len() {
                        return Err(missing("the transitions that write ids"));
                    }
                    Ok(CodelMap {
                        state: c.state.clone(),
                        run: interaction(&c.run)?,
                        fail: interaction(&c.fail)?,
                        yields: c
                            .yields
                            .iter()
                            .map(|y| YieldMap {
                                target: y.clone(),
                                transitions: ok.clone().collect(),
                            })
                            .collect(),
                        throws: c.throws.clone(),
                        writes: c.writes.clone(),
                        ids,
                        ids_transitions: if c.ids.is_empty() { 0..0 } else { ok.clone() },
                        holds: Vec::new(),
                        wcet_us: None,
                        bcet_us: None,
                        apart: None,
                        timed: None,
                    })
                };
                services.push(ServiceMap {
                    function: s.function.as_ref().map(at_request).transpose()?,
                    validate: s.validate.as_ref().map(at_request).transpose()?,
                    name: s.name.clone(),
                    kind: s.kind,
                    task: s.task,
                    component: comp,
                    request: s.request.as_deref().map(interaction).transpose()?,
                    interrupt: s.interrupt.as_deref().map(interaction).transpose()?,
                    owned_by_model: s.owned_by_model,
                    refusals,
                    interrupts: s.interrupts.clone(),
                    codels,
                    args: s.args.clone(),
                    output: s.output.clone(),
                });
            }
            modules.push(ModuleMap {
                name: m.name.clone(),
                component: mc,
                tasks: m
                    .tasks
                    .iter()
                    .zip(&m.delays)
                    .enumerate()
                    .map(|(ti, ((n, p), &delay))| {
                        let budget = self
                            .timing
                            .tasks
                            .get(&(m.name.clone(), n.clone()))
                            .copied()
                            .unwrap_or_default();
                        TaskMap {
                            name: n.clone(),
                            period: p.map(|p| u32::try_from(p).unwrap_or(u32::MAX)),
                            delay: u32::try_from(delay).unwrap_or(u32::MAX),
                            core: self
                                .cores
                                .get(mi)
                                .and_then(|c| c.get(ti))
                                .copied()
                                .flatten(),
                            cpu: budget.cpu,
                            priority: budget.priority,
                            deadline_us: budget.deadline_us,
                            timed: self
                                .time_unit_us
                                .and_then(|_| timed_task(system, &m.name, n)),
                        }
                    })
                    .collect(),
                ports,
                in_ports: m.in_ports.clone(),
                ids,
                services,
            });
        }
        let idle = match &self.idle {
            Some(_) => Some(next("the idle condition")?),
            None => None,
        };
        Ok(GenomMap {
            tick: interaction(&self.tick)?,
            tick_ms: system.tick_ms,
            time_unit_us: self.time_unit_us,
            modules,
            idle,
        })
    }
}

/// Task `m.t` of a timed model as the engine reads it: its atom's component and elapsed
/// time, and its deadline's invariant; `None` for a task without codels (it has no atom).
fn timed_task(system: &System, m: &str, t: &str) -> Option<TimedTaskMap> {
    let component = system.component_index(&names::task_component(m, t))?;
    let var = system.atom_of(component).var_index(names::ELAPSED)?;
    // the invariant `m.t meets its D deadline` (`timed/deadlines.rs`)
    let prefix = format!("{m}.{t} meets its ");
    let deadline = system.properties.iter().position(|p| {
        matches!(p.kind, bip_model::PropertyKind::Invariant(_))
            && p.name.starts_with(&prefix)
            && p.name.ends_with(" deadline")
    });
    Some(TimedTaskMap {
        component,
        elapsed_slot: system.components[component as usize].var_slot(var),
        deadline: deadline.map(|k| k as u32),
    })
}

/// The ids fields `names` of module component `mc` that a codel writes, with their strides
/// (the last field varies fastest).
fn ids_writes(system: &System, mc: u32, names: &[String]) -> Result<Vec<IdsWrite>, MissingName> {
    let matom = system.atom_of(mc);
    let mut ids: Vec<IdsWrite> = Vec::new();
    for x in names {
        let var = matom.var_index(x).ok_or_else(|| MissingName(x.clone()))?;
        let (lo, hi) = matom.vars[var as usize].ty.range();
        ids.push(IdsWrite {
            name: x.clone(),
            var,
            slot: system.components[mc as usize].var_slot(var),
            lo,
            hi,
            stride: 1,
        });
    }
    let mut stride = 1u32;
    for f in ids.iter_mut().rev() {
        f.stride = stride;
        stride = f
            .stride
            .checked_mul(values(f).ok_or_else(too_many)?)
            .ok_or_else(too_many)?;
    }
    Ok(ids)
}

/// How many combinations of values the written fields `ids` take.
fn written_values(ids: &[IdsWrite]) -> Result<u32, MissingName> {
    match ids.first() {
        None => Ok(1),
        Some(f) => f
            .stride
            .checked_mul(values(f).ok_or_else(too_many)?)
            .ok_or_else(too_many),
    }
}

fn values(f: &IdsWrite) -> Option<u32> {
    u32::try_from(i128::from(f.hi) - i128::from(f.lo) + 1).ok()
}

fn too_many() -> MissingName {
    MissingName("the transitions that write ids".to_string())
}
