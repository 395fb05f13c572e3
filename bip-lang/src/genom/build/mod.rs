//! The expansion of a checked GenoM layer into BIP core (docs/genom.md): one atom per
//! module and per activity, one clock, a request connector per service, an interrupt
//! connector per activity that interrupts another, a codel connector per codel state (and
//! one per codel that may throw), one tick, the priorities that make codels urgent and run
//! them in declaration order, and the constraints as guards.
//!
//! This file holds the builder, what it collects and the helpers every part uses; each
//! part of the expansion is a file of its own:
//! - `clock.rs`: the clock atom and the tick connector (the tasks' common cycle);
//! - `module.rs`: a module's atom (functions, ages, ids written by codels);
//! - `activity.rs`: an activity's atom (requests, interrupts, abort, codels);
//! - `async_codels.rs`: async codels, which run apart from their task;
//! - `services.rs`: a service's request, interrupt and codel connectors, with their
//!   conditions;
//! - `wake.rs`: aperiodic tasks, whose paused activities wait for an event of the module;
//! - `timed/`: a timed model's tasks, codel starts and finishes, dispatch and tick;
//! - `finish.rs`: the core model assembled, user connectors joining generated ones;
//! - `priorities.rs`, `properties.rs`: the generated priorities, and the properties.

mod activity;
mod async_codels;
mod clock;
mod finish;
mod module;
mod priorities;
mod properties;
mod services;
mod timed;
mod wake;

use std::collections::{BTreeMap, HashMap, HashSet};

use super::check::{Layer, PortRef, Service, ServiceRef};
use super::names::*;
use super::recipe::{Recipe, RecipeCondition, RecipeModule};
use super::timed::Timed;
use super::tree::{assign, boolean, member, name};
use crate::diag::{Errors, ModelError};
use crate::expr::{Assign, Expr};
use crate::source::{ConstExpr, ConstValue, OrderedMap, Span, Spanned};
use crate::syntax::{
    ActionDef, AtomDef, ComponentDef, ConnectorDef, ConnectorKindDef, ExprDef, Role, SystemDef,
    Text, TransitionDef, TypeDef, VarDef,
};
use bip_model::genom::map::{InPortMap, Reason};

/// The result of expanding a model: its core form and the recipe of the engine's map
/// (compile it with [`Expansion::compile`]).
pub struct Expansion {
    /// The expanded model: BIP core only.
    pub def: SystemDef,
    pub(crate) recipe: Recipe,
}

/// A user's expression as the expansion uses it: its tree (positions in the file) and
/// whether rewriting GenoM names changed it (if not, the core keeps the text as written).
#[derive(Clone)]
pub(super) struct UserExpr<T> {
    pub tree: T,
    pub rewritten: bool,
}

impl<T: Clone> UserExpr<T> {
    /// What the core holds: the text as written, or the rewritten tree.
    fn def<D: Clone + From<T>>(&self, written: &D) -> D {
        if self.rewritten {
            D::from(self.tree.clone())
        } else {
            written.clone()
        }
    }
}

/// The user texts the expansion needs (rewritten where they name GenoM things), by place.
#[derive(Default)]
pub(super) struct UserTexts {
    /// `Guard` constraints' conditions, by constraint index.
    pub guards: HashMap<usize, Expr>,
    /// User connectors' guards and actions, by connector index.
    pub connector_guards: HashMap<usize, UserExpr<Expr>>,
    pub connector_actions: HashMap<usize, UserExpr<Vec<Assign>>>,
    pub priority_whens: HashMap<usize, UserExpr<Expr>>,
    pub properties: HashMap<usize, UserExpr<Expr>>,
    /// Response properties' triggers and responses (`Replies` and `Terminates` too),
    /// GenoM events as the core's step forms.
    pub responses: HashMap<usize, (UserExpr<Expr>, UserExpr<Expr>)>,
}

/// A condition of a request or a codel, while the expansion builds it.
#[derive(Clone)]
struct Cond {
    reason: Reason,
    expr: Expr,
}

fn text(s: impl Into<String>) -> Text {
    Spanned::generated(s.into())
}

/// `comp.port`, a port of a generated connector.
fn port(comp: &str, port: &str) -> ExprDef {
    ExprDef::Built(member(comp, port))
}

/// A generated rendezvous connector (guards and actions are set when it is finished).
fn connector(name: &str, ports: Vec<ExprDef>, role: Role) -> ConnectorDef {
    ConnectorDef {
        name: text(name),
        forall: None,
        ports,
        kind: ConnectorKindDef::Rendezvous,
        role,
        guard: None,
        action: None,
        advance: None,
    }
}

/// A generated transition.
fn tr(from: &str, port: &str, to: &str, guard: Option<Expr>, action: Vec<Assign>) -> TransitionDef {
    TransitionDef {
        from: text(from),
        port: Some(text(port)),
        to: text(to),
        guard: guard.map(ExprDef::Built),
        action: (!action.is_empty()).then_some(ActionDef::Built(action)),
    }
}

/// `var = b`, for an atom's own boolean.
fn set(var: &str, b: bool) -> Assign {
    assign(name(var), boolean(b))
}

fn var(name: &str, ty: TypeDef, init: Option<i64>) -> VarDef {
    let init = match (&ty, init) {
        (TypeDef::Bool, Some(v)) => Some(Spanned::generated(ConstValue::Bool(v != 0))),
        (_, v) => v.map(ConstExpr::int),
    };
    VarDef {
        name: text(name),
        ty,
        init,
    }
}

struct Builder<'a, 'd> {
    layer: &'a Layer<'d>,
    def: &'d SystemDef,
    errors: Errors,
    /// For each port whose age is read, its cap (one more than the largest constant).
    caps: BTreeMap<PortRef, i64>,
    /// Services listed in some `after`.
    tracked: HashSet<ServiceRef>,
    /// Generated names: components, atoms, connectors, with where they come from.
    names: HashMap<String, (Span, String)>,
    atoms: Vec<(Text, AtomDef)>,
    components: Vec<ComponentDef>,
    /// The activities' components (their `abort` port is open to user connectors).
    activity_components: HashSet<String>,
    /// Generated connectors, their guards and actions kept apart until user connectors
    /// have extended them.
    connectors: Vec<(ConnectorDef, Option<Expr>, Vec<Assign>)>,
    /// The modules' wake connectors, above every other step (`wake.rs`).
    wakes: Vec<String>,
    recipe: Recipe,
    /// A timed model's durations and cores (`timed/`).
    timed: Option<&'a Timed>,
    /// In a timed model, what must hold for each codel to start, by (activity, codel
    /// index): its conditions, which gate its start rather than its finish.
    holds: HashMap<(ServiceRef, usize), Option<Expr>>,
}

/// `caps`: for each port whose age is read, its cap (one more than the largest constant
/// it is compared with).
pub(super) fn build(
    layer: &Layer<'_>,
    def: &SystemDef,
    caps: BTreeMap<PortRef, i64>,
    user: UserTexts,
    timed: Option<&Timed>,
) -> Result<Expansion, Vec<ModelError>> {
    let mut tracked = HashSet::new();
    for (mi, m) in layer.modules.iter().enumerate() {
        for s in &m.services {
            for &a in &s.after {
                tracked.insert(ServiceRef {
                    module: mi,
                    service: a,
                });
            }
        }
    }
    let mut b = Builder {
        layer,
        def,
        errors: Errors::default(),
        caps,
        tracked,
        names: HashMap::new(),
        atoms: Vec::new(),
        components: Vec::new(),
        activity_components: HashSet::new(),
        connectors: Vec::new(),
        wakes: Vec::new(),
        recipe: Recipe::default(),
        timed,
        holds: HashMap::new(),
    };
    for mi in 0..layer.modules.len() {
        b.recipe_module(mi);
    }
    b.clock();
    for mi in 0..layer.modules.len() {
        b.module(mi);
    }
    for mi in 0..layer.modules.len() {
        for si in 0..layer.modules[mi].services.len() {
            if layer.modules[mi].services[si].is_activity() {
                b.activity(ServiceRef {
                    module: mi,
                    service: si,
                });
            }
        }
    }
    match timed {
        None => b.tick(),
        Some(t) => b.timed_tick(t),
    }
    for mi in 0..layer.modules.len() {
        for si in 0..layer.modules[mi].services.len() {
            b.service_connectors(
                ServiceRef {
                    module: mi,
                    service: si,
                },
                &user,
            );
        }
    }
    if let Some(t) = timed {
        b.timed_tasks(t);
    }
    for mi in 0..layer.modules.len() {
        b.wake(mi);
    }
    let out = b.finish(user);
    if b.errors.is_empty() {
        Ok(out)
    } else {
        Err(b.errors.list)
    }
}

impl<'a, 'd> Builder<'a, 'd> {
    fn service(&self, r: ServiceRef) -> &'a Service<'d> {
        &self.layer.modules[r.module].services[r.service]
    }

    fn module_name(&self, r: ServiceRef) -> &'d str {
        self.layer.modules[r.module].name
    }

    /// The component of activity `r`.
    fn comp(&self, r: ServiceRef) -> String {
        activity_component(self.module_name(r), self.service(r).name)
    }

    /// Registers a generated name; two generated things may not share one.
    fn claim(&mut self, name: &str, span: Span, what: String) {
        if let Some((first, first_what)) = self.names.get(name) {
            self.errors.push(
                ModelError::new(
                    format!("the expansion would generate `{name}` twice: for {first_what} and for {what}"),
                    span,
                )
                .with_note(*first, "the other one comes from here")
                .with_help("rename a module or service so that the generated names differ (docs/genom.md)"),
            );
        } else {
            self.names.insert(name.to_string(), (span, what));
        }
    }

    fn add_atom(&mut self, name: String, atom: AtomDef, span: Span, what: String) {
        self.claim(&name, span, what);
        self.atoms.push((text(name), atom));
    }

    fn add_component(&mut self, name: String, atom: String, span: Span, what: String) {
        self.claim(&name, span, what);
        self.components.push(ComponentDef {
            name: text(name),
            atom: text(atom),
            count: None,
            vars_init: OrderedMap::default(),
        });
    }

    fn recipe_module(&mut self, mi: usize) -> &mut RecipeModule {
        while self.recipe.modules.len() <= mi {
            let m = &self.layer.modules[self.recipe.modules.len()];
            let k = self.recipe.modules.len();
            self.recipe.modules.push(RecipeModule {
                name: m.name.to_string(),
                tasks: m.tasks.iter().map(|&(n, p)| (n.to_string(), p)).collect(),
                delays: m.delays.clone(),
                ports: m
                    .ports
                    .iter()
                    .enumerate()
                    .map(|(pi, &p)| {
                        let cap = self
                            .caps
                            .get(&PortRef {
                                module: k,
                                port: pi,
                            })
                            .copied();
                        (p.to_string(), cap)
                    })
                    .collect(),
                port_types: m.port_types.clone(),
                in_ports: m
                    .in_ports
                    .iter()
                    .map(|p| InPortMap {
                        name: p.name.to_string(),
                        ty: p.ty.clone(),
                        reads: p.reads.map(|r| (r.module as u32, r.port as u32)),
                    })
                    .collect(),
                ids: m.ids.iter().map(|(x, _)| x.to_string()).collect(),
                services: Vec::new(),
            });
        }
        &mut self.recipe.modules[mi]
    }
}

impl From<Cond> for RecipeCondition {
    fn from(c: Cond) -> Self {
        RecipeCondition {
            reason: c.reason,
            expr: c.expr,
        }
    }
}
