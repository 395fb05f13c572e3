//! The expansion of a checked GenoM layer into BIP core (docs/genom.md): one atom per
//! module and per activity, one clock, a request connector per service, a codel connector
//! per codel state (and one per codel that may throw), one tick, the priorities that make
//! codels urgent and run them in declaration order, and the constraints as guards.

use std::collections::{BTreeMap, HashMap, HashSet};

use super::check::{ConstraintKind, Layer, Module, PortRef, Service, ServiceRef, Yield, ETHER};
use super::names::*;
use super::recipe::{Recipe, RecipeCodel, RecipeCondition, RecipeModule, RecipeService};
use super::tree::{all, and, assign, at, binary, boolean, chain, cond, int, member, name, not, or};
use crate::compile::one_of;
use crate::diag::{Errors, ModelError};
use crate::expr::{Assign, BinOp, Expr, ExprKind};
use crate::source::{ConstExpr, ConstValue, OrderedMap, Span, Spanned};
use crate::syntax::{
    ActionDef, AtomDef, ComponentDef, ConnectorDef, ConnectorKindDef, ExprDef, PriorityDef,
    PropertyDef, Role, SystemDef, Text, TransitionDef, TypeDef, VarDef,
};
use bip_model::genom::map::Reason;

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

fn gcd(a: i64, b: i64) -> i64 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// The clock's phase wraps at this many ticks at most (least common multiple of periods).
const MAX_PHASE: i64 = 1 << 20;

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
    recipe: Recipe,
}

/// `caps`: for each port whose age is read, its cap (one more than the largest constant
/// it is compared with).
pub(super) fn build(
    layer: &Layer<'_>,
    def: &SystemDef,
    caps: BTreeMap<PortRef, i64>,
    user: UserTexts,
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
        recipe: Recipe::default(),
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
    b.tick();
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

    /// The least common multiple of the periods of tasks that have activities.
    fn phase_len(&self) -> i64 {
        let mut l = 1i64;
        for m in &self.layer.modules {
            for s in m.services.iter().filter(|s| s.is_activity()) {
                if let Some(t) = s.task {
                    let p = m.tasks[t].1;
                    l = (l / gcd(l, p)).saturating_mul(p).min(MAX_PHASE + 1);
                }
            }
        }
        l
    }

    fn clock(&mut self) {
        let l = self.phase_len();
        if l > MAX_PHASE {
            let span = self
                .layer
                .modules
                .first()
                .map_or(Span::NONE, |m| m.def.name.span);
            self.errors.push(
                ModelError::new(
                    format!("the task periods have a common cycle longer than {MAX_PHASE} ticks"),
                    span,
                )
                .with_help("use periods with a small least common multiple"),
            );
        }
        let vars = if l > 1 {
            vec![var(
                PHASE,
                TypeDef::Int(ConstExpr::int(0), ConstExpr::int(l - 1)),
                Some(0),
            )]
        } else {
            Vec::new()
        };
        let atom = AtomDef {
            locations: vec![text("on")],
            initial: text("on"),
            ports: vec![text("tick")],
            vars,
            transitions: vec![tr("on", "tick", "on", None, Vec::new())],
        };
        let span = self
            .layer
            .modules
            .first()
            .map_or(Span::NONE, |m| m.def.name.span);
        self.add_atom(CLOCK_ATOM.into(), atom, span, "the clock".into());
        self.add_component(CLOCK.into(), CLOCK_ATOM.into(), span, "the clock".into());
    }

    fn module(&mut self, mi: usize) {
        let m = &self.layer.modules[mi];
        let mut ports = Vec::new();
        let mut transitions = Vec::new();
        let mut vars: Vec<VarDef> = m.def.ids.clone();
        let mut reserved: Vec<(String, Span)> = Vec::new();
        for (si, s) in m.services.iter().enumerate() {
            if s.is_activity() {
                continue;
            }
            ports.push(text(s.name));
            let mut action = Vec::new();
            if self.tracked.contains(&ServiceRef {
                module: mi,
                service: si,
            }) {
                let d = done_var(s.name);
                vars.push(var(&d, TypeDef::Bool, Some(0)));
                action.push(set(&d, true));
                reserved.push((d, s.def.name.span));
            }
            transitions.push(tr("on", s.name, "on", None, action));
        }
        let aged: Vec<(usize, i64)> = self
            .caps
            .iter()
            .filter(|(p, _)| p.module == mi)
            .map(|(p, &cap)| (p.port, cap))
            .collect();
        for &(p, cap) in &aged {
            let a = age_var(m.ports[p]);
            vars.push(var(
                &a,
                TypeDef::Int(ConstExpr::int(0), ConstExpr::int(cap)),
                Some(cap),
            ));
            reserved.push((a, m.def.ports[p].name.span));
        }
        if !aged.is_empty() {
            ports.push(text("tick"));
            transitions.push(tr("on", "tick", "on", None, Vec::new()));
            // a codel that writes ids joins through its own port (below) instead
            let writes = m.services.iter().any(|s| {
                s.codels.iter().any(|c| {
                    c.ids.is_empty() && c.writes.iter().any(|w| aged.iter().any(|&(p, _)| p == *w))
                })
            });
            if writes {
                ports.push(text("write"));
                transitions.push(tr("on", "write", "on", None, Vec::new()));
            }
        }
        // a codel that writes ids: one transition per combination of the values it may
        // write, the last field varying fastest (docs/genom.md, "Codels that write ids")
        for s in m.services.iter().filter(|s| s.is_activity()) {
            for c in s.codels.iter().filter(|c| !c.ids.is_empty()) {
                let port = ids_port(s.name, c.state);
                let fields: Vec<(&str, i64, i64)> = c
                    .ids
                    .iter()
                    .filter_map(|&k| m.ids[k].1.map(|(lo, hi)| (m.ids[k].0, lo, hi)))
                    .collect();
                if fields.len() != c.ids.len() {
                    continue; // a bound is not constant: the core reports it
                }
                ports.push(text(&port));
                let mut values: Vec<i64> = fields.iter().map(|f| f.1).collect();
                loop {
                    let action: Vec<Assign> = fields
                        .iter()
                        .zip(&values)
                        .map(|(f, v)| assign(name(f.0), ids_literal(m, f.0, *v)))
                        .collect();
                    transitions.push(tr("on", &port, "on", None, action));
                    // advance the odometer, last field fastest
                    let mut k = fields.len();
                    loop {
                        if k == 0 {
                            break;
                        }
                        k -= 1;
                        if values[k] < fields[k].2 {
                            values[k] += 1;
                            break;
                        }
                        values[k] = fields[k].1;
                    }
                    if values.iter().zip(&fields).all(|(v, f)| *v == f.1) {
                        break;
                    }
                }
            }
        }
        for (name, span) in reserved {
            if let Some(id) = m.def.ids.iter().find(|v| v.name.as_str() == name) {
                self.errors.push(
                    ModelError::new(format!("ids field `{name}` clashes with a generated variable"), id.name.span)
                        .with_note(span, "generated for this")
                        .with_help("`age_<port>` and `done_<service>` are the module atom's own variables (docs/genom.md)"),
                );
            }
        }
        let atom = AtomDef {
            locations: vec![text("on")],
            initial: text("on"),
            ports,
            vars,
            transitions,
        };
        let what = format!("module `{}`", m.name);
        self.add_atom(module_atom(m.name), atom, m.def.name.span, what.clone());
        self.add_component(
            module_component(m.name),
            module_atom(m.name),
            m.def.name.span,
            what,
        );
    }

    /// True if some service other than `r` interrupts activity `r`.
    fn interrupted_by_others(&self, r: ServiceRef) -> bool {
        self.layer.modules[r.module]
            .services
            .iter()
            .enumerate()
            .any(|(k, s)| k != r.service && s.interrupts.contains(&r.service))
    }

    fn activity(&mut self, r: ServiceRef) {
        let s = self.service(r);
        let m = self.module_name(r);
        let has_stop = s.stop.is_some();
        let self_int = s.interrupts_itself(r.service);
        let locs: Vec<&str> = s.locations.iter().map(|&k| s.codels[k].state).collect();
        let mut locations = vec![text(ETHER)];
        locations.extend(locs.iter().map(|l| text(*l)));
        let mut vars = vec![
            var(REQ, TypeDef::Bool, Some(0)),
            var(PAUSED, TypeDef::Bool, Some(0)),
        ];
        if has_stop {
            vars.push(var(STOPPING, TypeDef::Bool, Some(0)));
        }
        let tracked = self.tracked.contains(&r);
        if tracked {
            vars.push(var(DONE, TypeDef::Bool, Some(0)));
        }
        let mut ports = vec![text("request")];
        let mut t = Vec::new();
        // requests
        t.push(tr(
            ETHER,
            "request",
            ETHER,
            Some(not(name(REQ))),
            vec![set(REQ, true), set(PAUSED, true)],
        ));
        if self_int {
            t.push(tr(ETHER, "request", ETHER, Some(name(REQ)), Vec::new()));
            for l in &locs {
                if has_stop {
                    t.push(tr(
                        l,
                        "request",
                        "stop",
                        Some(not(name(STOPPING))),
                        vec![set(STOPPING, true), set(REQ, true)],
                    ));
                    t.push(tr(
                        l,
                        "request",
                        l,
                        Some(name(STOPPING)),
                        vec![set(REQ, true)],
                    ));
                } else {
                    t.push(tr(
                        l,
                        "request",
                        ETHER,
                        None,
                        vec![set(REQ, true), set(PAUSED, true)],
                    ));
                }
            }
        }
        // interrupts by other services' requests: always enabled, so that a target never
        // holds back the request that interrupts it
        let stop_or_end = |t: &mut Vec<TransitionDef>, port: &str, l: &str| {
            if has_stop {
                t.push(tr(
                    l,
                    port,
                    "stop",
                    Some(not(name(STOPPING))),
                    vec![set(STOPPING, true), set(REQ, false)],
                ));
            } else {
                t.push(tr(
                    l,
                    port,
                    ETHER,
                    None,
                    vec![set(REQ, false), set(PAUSED, false)],
                ));
            }
        };
        if self.interrupted_by_others(r) {
            ports.push(text("interrupt"));
            t.push(tr(
                ETHER,
                "interrupt",
                ETHER,
                None,
                vec![set(REQ, false), set(PAUSED, false)],
            ));
            for l in &locs {
                stop_or_end(&mut t, "interrupt", l);
                if has_stop {
                    t.push(tr(
                        l,
                        "interrupt",
                        l,
                        Some(name(STOPPING)),
                        vec![set(REQ, false)],
                    ));
                }
            }
        }
        // abort, for components of the model (a supervisor, a safety rule): enabled only
        // when there is something to abort, so that it never fires for nothing
        ports.push(text("abort"));
        t.push(tr(
            ETHER,
            "abort",
            ETHER,
            Some(name(REQ)),
            vec![set(REQ, false), set(PAUSED, false)],
        ));
        for l in &locs {
            stop_or_end(&mut t, "abort", l);
            if has_stop {
                t.push(tr(
                    l,
                    "abort",
                    l,
                    Some(and(name(STOPPING), name(REQ))),
                    vec![set(REQ, false)],
                ));
            }
        }
        // time: the tick connector's action clears `paused` at the task's period
        ports.push(text("tick"));
        t.push(tr(ETHER, "tick", ETHER, None, Vec::new()));
        for l in &locs {
            t.push(tr(l, "tick", l, None, Vec::new()));
        }
        // codels: one transition per yield, from each place the codel runs from
        for c in &s.codels {
            ports.push(text(c.state));
            // every codel has an error path: a declared exception, or what the engine does
            // with a codel that panics, yields something undeclared or leaves a range
            ports.push(text(fail_port(c.state)));
            let mut sources: Vec<(&str, Expr, Vec<Assign>)> = Vec::new();
            if c.state == "start" {
                sources.push((
                    ETHER,
                    and(name(REQ), not(name(PAUSED))),
                    vec![set(REQ, false)],
                ));
            }
            if locs.contains(&c.state) {
                sources.push((c.state, not(name(PAUSED)), Vec::new()));
            }
            let mut end = Vec::new();
            if has_stop {
                end.push(set(STOPPING, false));
            }
            end.push(assign(name(PAUSED), name(REQ)));
            for (from, guard, pre) in &sources {
                for y in &c.yields {
                    let mut action = pre.clone();
                    let to = match *y {
                        Yield::Go(k) => s.codels[k].state,
                        Yield::Pause(k) => {
                            action.push(set(PAUSED, true));
                            s.codels[k].state
                        }
                        Yield::Ether => {
                            if tracked {
                                action.push(set(DONE, true));
                            }
                            action.extend(end.iter().cloned());
                            ETHER
                        }
                    };
                    t.push(tr(from, c.state, to, Some(guard.clone()), action));
                }
                let mut action = pre.clone();
                action.extend(end.iter().cloned());
                t.push(tr(
                    from,
                    &fail_port(c.state),
                    ETHER,
                    Some(guard.clone()),
                    action,
                ));
            }
        }
        let atom = AtomDef {
            locations,
            initial: text(ETHER),
            ports,
            vars,
            transitions: t,
        };
        let what = format!("activity `{m}.{}`", s.name);
        let comp = self.comp(r);
        self.activity_components.insert(comp.clone());
        self.add_atom(
            activity_atom(m, s.name),
            atom,
            s.def.name.span,
            what.clone(),
        );
        self.add_component(comp, activity_atom(m, s.name), s.def.name.span, what);
    }

    fn tick(&mut self) {
        let l = self.phase_len();
        let mut ports = vec![port(CLOCK, "tick")];
        let mut action = Vec::new();
        if l > 1 {
            let phase = member(CLOCK, PHASE);
            let next = binary(BinOp::Add, phase.clone(), int(1));
            action.push(assign(phase, binary(BinOp::Rem, next, int(l))));
        }
        for (mi, m) in self.layer.modules.iter().enumerate() {
            for s in &m.services {
                let Some(task) = s.task.filter(|_| s.is_activity()) else {
                    continue;
                };
                let c = activity_component(m.name, s.name);
                ports.push(port(&c, "tick"));
                let p = m.tasks[task].1;
                let paused = member(&c, PAUSED);
                if p == 1 {
                    action.push(assign(paused, boolean(false)));
                } else {
                    let off_period = binary(
                        BinOp::Ne,
                        binary(BinOp::Rem, member(CLOCK, PHASE), int(p)),
                        int(0),
                    );
                    action.push(assign(paused.clone(), and(paused, off_period)));
                }
            }
            let aged: Vec<(usize, i64)> = self
                .caps
                .iter()
                .filter(|(p, _)| p.module == mi)
                .map(|(p, &cap)| (p.port, cap))
                .collect();
            if !aged.is_empty() {
                let c = module_component(m.name);
                ports.push(port(&c, "tick"));
                for (p, cap) in aged {
                    let a = member(&c, &age_var(m.ports[p]));
                    let older = cond(
                        binary(BinOp::Lt, a.clone(), int(cap)),
                        binary(BinOp::Add, a.clone(), int(1)),
                        int(cap),
                    );
                    action.push(assign(a, older));
                }
            }
        }
        let span = self
            .layer
            .modules
            .first()
            .map_or(Span::NONE, |m| m.def.name.span);
        self.claim(TICK, span, "the clock's tick".into());
        self.connectors.push((
            ConnectorDef {
                kind: ConnectorKindDef::Broadcast {
                    trigger: port(CLOCK, "tick"),
                },
                ..connector(TICK, ports, Role::Time)
            },
            None,
            action,
        ));
    }

    /// The conditions on starting activity `r` (waiting for what it interrupts, Exclusive,
    /// AtMost) and on running its codels (Requires, Fresh, Guard).
    fn conditions(&self, r: ServiceRef, user: &UserTexts) -> (Vec<Cond>, Vec<Cond>) {
        let mut start = Vec::new();
        let mut run = Vec::new();
        let s = self.service(r);
        let m = self.module_name(r);
        if s.is_activity() {
            for &x in s.interrupts.iter().filter(|&&x| x != r.service) {
                let target = ServiceRef {
                    module: r.module,
                    service: x,
                };
                start.push(Cond {
                    reason: Reason::Interrupting {
                        service: format!("{m}.{}", self.service(target).name),
                    },
                    expr: at(&self.comp(target), ETHER),
                });
            }
        }
        for (ci, c) in self.layer.constraints.iter().enumerate() {
            let reason = c.reason.clone();
            let others = |list: &[ServiceRef], f: &dyn Fn(String) -> Expr| -> Vec<Expr> {
                list.iter()
                    .filter(|&&y| y != r)
                    .map(|&y| f(self.comp(y)))
                    .collect()
            };
            let expr = match &c.kind {
                ConstraintKind::Exclusive(list) if list.contains(&r) => {
                    all(others(list, &|c| at(&c, ETHER)))
                }
                ConstraintKind::AtMost { max, services } if services.contains(&r) => {
                    let active = |c: String| cond(at(&c, ETHER), int(0), int(1));
                    chain(BinOp::Add, others(services, &active))
                        .map(|count| binary(BinOp::Lt, count, int(*max)))
                }
                ConstraintKind::Requires { service, active } if *service == r => {
                    all(active.iter().map(|&y| not(at(&self.comp(y), ETHER))))
                }
                ConstraintKind::Fresh {
                    service,
                    port,
                    max_age,
                } if *service == r => {
                    let pm = &self.layer.modules[port.module];
                    let age = member(&module_component(pm.name), &age_var(pm.ports[port.port]));
                    Some(binary(BinOp::Le, age, int(*max_age)))
                }
                ConstraintKind::Guard { service, .. } if *service == r => {
                    user.guards.get(&ci).cloned()
                }
                _ => None,
            };
            let Some(expr) = expr else { continue };
            let cond = Cond { reason, expr };
            match &c.kind {
                ConstraintKind::Exclusive(_) | ConstraintKind::AtMost { .. } => start.push(cond),
                _ => run.push(cond),
            }
        }
        (start, run)
    }

    fn service_connectors(&mut self, r: ServiceRef, user: &UserTexts) {
        let s = self.service(r);
        let m = self.module_name(r);
        let (start_conds, run_conds) = self.conditions(r, user);
        // the request
        let mut ports = Vec::new();
        let mut refusals = Vec::new();
        if s.is_activity() {
            let comp = self.comp(r);
            ports.push(port(&comp, "request"));
            if !s.interrupts_itself(r.service) {
                refusals.push(Cond {
                    reason: Reason::AlreadyRequested,
                    expr: and(at(&comp, ETHER), not(member(&comp, REQ))),
                });
            }
        } else {
            ports.push(port(&module_component(m), s.name));
        }
        for &x in s.interrupts.iter().filter(|&&x| x != r.service) {
            let target = ServiceRef {
                module: r.module,
                service: x,
            };
            ports.push(port(&self.comp(target), "interrupt"));
        }
        for &a in &s.after {
            let target = ServiceRef {
                module: r.module,
                service: a,
            };
            let t = self.service(target);
            let flag = if t.is_activity() {
                member(&self.comp(target), DONE)
            } else {
                member(&module_component(m), &done_var(t.name))
            };
            refusals.push(Cond {
                reason: Reason::After {
                    service: format!("{m}.{}", t.name),
                },
                expr: flag,
            });
        }
        if !s.is_activity() {
            refusals.extend(run_conds.iter().cloned());
        }
        // the request port's own guards say "already requested"; the others guard the
        // connector
        let guard = all(refusals
            .iter()
            .filter(|c| c.reason != Reason::AlreadyRequested)
            .map(|c| c.expr.clone()));
        let name = request_connector(m, s.name);
        self.claim(
            &name,
            s.def.name.span,
            format!("requests of `{m}.{}`", s.name),
        );
        self.connectors.push((
            connector(&name, ports, Role::Environment),
            guard,
            Vec::new(),
        ));
        let refusals = refusals.into_iter().map(RecipeCondition::from).collect();
        let mut service = RecipeService {
            name: s.name.to_string(),
            kind: s.kind,
            task: s.task,
            component: s.is_activity().then(|| self.comp(r)),
            request: name,
            owned_by_model: false,
            refusals,
            codels: Vec::new(),
            interrupts: s
                .interrupts
                .iter()
                .map(|&x| self.layer.modules[r.module].services[x].name.to_string())
                .collect(),
        };
        // the codels
        let comp = self.comp(r);
        let start_is_location = s.is_location("start");
        for c in &s.codels {
            let mut holds = Vec::new();
            if c.state == "start" {
                for sc in &start_conds {
                    // a start condition applies to starting, not to re-entering `start`
                    let expr = if start_is_location {
                        or(not(at(&comp, ETHER)), sc.expr.clone())
                    } else {
                        sc.expr.clone()
                    };
                    holds.push(Cond {
                        reason: sc.reason.clone(),
                        expr,
                    });
                }
            }
            for rc in &run_conds {
                // the stop path is not gated
                let expr = if s.stop.is_some() {
                    or(member(&comp, STOPPING), rc.expr.clone())
                } else {
                    rc.expr.clone()
                };
                holds.push(Cond {
                    reason: rc.reason.clone(),
                    expr,
                });
            }
            let guard = all(holds.iter().map(|h| h.expr.clone()));
            let mut ports = vec![port(&comp, c.state)];
            let mut action = Vec::new();
            let mi = r.module;
            for &w in &c.writes {
                if self.caps.contains_key(&PortRef {
                    module: mi,
                    port: w,
                }) {
                    let age = age_var(self.layer.modules[mi].ports[w]);
                    action.push(assign(member(&module_component(m), &age), int(0)));
                }
            }
            if !c.ids.is_empty() {
                ports.push(port(&module_component(m), &ids_port(s.name, c.state)));
            } else if !action.is_empty() {
                ports.push(port(&module_component(m), "write"));
            }
            let run = codel_connector(m, s.name, c.state);
            let span = c.def.state.span;
            self.claim(
                &run,
                span,
                format!("codel `{}` of `{m}.{}`", c.state, s.name),
            );
            self.connectors.push((
                connector(&run, ports, Role::Progress),
                guard.clone(),
                action,
            ));
            let fail = fail_connector(m, s.name, c.state);
            self.claim(
                &fail,
                span,
                format!("error path of codel `{}` of `{m}.{}`", c.state, s.name),
            );
            let fail_ports = vec![port(&comp, &fail_port(c.state))];
            self.connectors.push((
                connector(&fail, fail_ports, Role::Progress),
                guard,
                Vec::new(),
            ));
            let holds = holds.into_iter().map(RecipeCondition::from).collect();
            service.codels.push(RecipeCodel {
                state: c.state.to_string(),
                run,
                fail,
                yields: c.def.yields.iter().map(|y| y.value.clone()).collect(),
                from_ether: c.state == "start",
                from_location: s.is_location(c.state),
                throws: c.throws.iter().map(|t| t.to_string()).collect(),
                writes: c
                    .writes
                    .iter()
                    .map(|&w| self.layer.modules[mi].ports[w].to_string())
                    .collect(),
                ids: c
                    .ids
                    .iter()
                    .map(|&k| self.layer.modules[mi].ids[k].0.to_string())
                    .collect(),
                ids_port: (!c.ids.is_empty()).then(|| ids_port(s.name, c.state)),
                holds,
            });
        }
        let recipe_module = self.recipe_module(r.module);
        recipe_module.services.push(service);
    }

    fn recipe_module(&mut self, mi: usize) -> &mut RecipeModule {
        while self.recipe.modules.len() <= mi {
            let m = &self.layer.modules[self.recipe.modules.len()];
            let k = self.recipe.modules.len();
            self.recipe.modules.push(RecipeModule {
                name: m.name.to_string(),
                tasks: m.tasks.iter().map(|&(n, p)| (n.to_string(), p)).collect(),
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
                ids: m.ids.iter().map(|(x, _)| x.to_string()).collect(),
                services: Vec::new(),
            });
        }
        &mut self.recipe.modules[mi]
    }

    /// Assembles the core model: user atoms and components, generated ones, generated
    /// connectors extended by user connectors of the same name, the other user connectors,
    /// priorities and properties.
    fn finish(&mut self, user: UserTexts) -> Expansion {
        let def = self.def;
        // user names may not clash with generated ones
        for (name, _) in def.atoms.iter() {
            if let Some((span, what)) = self.names.get(name.as_str()) {
                self.errors.push(
                    ModelError::new(
                        format!("atom `{name}` has the name generated for {what}"),
                        name.span,
                    )
                    .with_note(*span, "generated for this")
                    .with_help("rename the atom (docs/genom.md lists the generated names)"),
                );
            }
        }
        for c in &def.components {
            if let Some((span, what)) = self.names.get(c.name.as_str()) {
                self.errors.push(
                    ModelError::new(
                        format!("component `{}` has the name generated for {what}", c.name),
                        c.name.span,
                    )
                    .with_note(*span, "generated for this")
                    .with_help("rename the component (docs/genom.md lists the generated names)"),
                );
            }
        }
        let generated_components: HashSet<String> = self
            .components
            .iter()
            .map(|c| c.name.value.clone())
            .collect();
        // user connectors: extensions of generated ones, or their own
        let mut by_name: HashMap<&str, usize> = HashMap::new();
        for (k, c) in def.connectors.iter().enumerate() {
            by_name.entry(c.name.as_str()).or_insert(k);
        }
        let mut extended = HashSet::new();
        let mut generated = std::mem::take(&mut self.connectors);
        for (g, guard, action) in &mut generated {
            let Some(&k) = by_name.get(g.name.as_str()) else {
                continue;
            };
            extended.insert(k);
            self.extend(g, guard, action, &def.connectors[k], k, &user);
        }
        let mut connectors = Vec::with_capacity(generated.len() + def.connectors.len());
        for (mut g, guard, action) in generated {
            g.guard = guard.map(ExprDef::Built);
            g.action = (!action.is_empty()).then_some(ActionDef::Built(action));
            connectors.push(g);
        }
        for (k, c) in def.connectors.iter().enumerate() {
            if extended.contains(&k) {
                continue;
            }
            self.check_user_ports(c, &generated_components);
            let mut c = c.clone();
            if let (Some(u), Some(written)) = (user.connector_guards.get(&k), &c.guard) {
                c.guard = Some(u.def(written));
            }
            if let (Some(u), Some(written)) = (user.connector_actions.get(&k), &c.action) {
                c.action = Some(u.def(written));
            }
            connectors.push(c);
        }
        let priorities = self.priorities(&user);
        let properties = self.properties(&connectors, &user);
        // record the tick
        self.recipe.tick = TICK.to_string();
        let mut atoms = def.atoms.clone();
        for (n, a) in std::mem::take(&mut self.atoms) {
            atoms.push(n, a);
        }
        let mut components = def.components.clone();
        components.extend(std::mem::take(&mut self.components));
        Expansion {
            def: SystemDef {
                name: def.name.clone(),
                tick_ms: def.tick_ms.clone(),
                // the core has no tasks to place
                cpus: Vec::new(),
                constants: def.constants.clone(),
                atoms,
                components,
                connectors,
                priorities,
                modules: Vec::new(),
                constraints: Vec::new(),
                properties,
            },
            recipe: std::mem::take(&mut self.recipe),
        }
    }

    /// Merges user connector `u` (index `k`) into generated connector `g`: its ports join,
    /// its guard is conjoined, its action runs after the generated one.
    fn extend(
        &mut self,
        g: &mut ConnectorDef,
        guard: &mut Option<Expr>,
        action: &mut Vec<Assign>,
        u: &ConnectorDef,
        k: usize,
        user: &UserTexts,
    ) {
        let is_tick = g.name.as_str() == TICK;
        let trigger = format!("{CLOCK}.tick");
        if let Some(f) = &u.forall {
            self.errors.push(
                ModelError::new(
                    format!(
                        "`{}` extends a generated connector; it cannot have `forall`",
                        u.name
                    ),
                    f.span,
                )
                .with_help(
                    "a connector named like a generated one adds its ports, guard and action to it",
                ),
            );
        }
        match (&u.kind, is_tick) {
            (ConnectorKindDef::Rendezvous, _) => {}
            (ConnectorKindDef::Broadcast { trigger: t }, true) if t.to_string() == trigger => {}
            (ConnectorKindDef::Broadcast { trigger }, _) => {
                self.errors.push(
                    ModelError::new(format!("`{}` extends a generated connector; its kind is fixed", u.name), trigger.span())
                        .with_help(if is_tick {
                            "the tick is `Broadcast(trigger: \"clock.tick\")`; the ports you list join it as receivers"
                        } else {
                            "leave out `kind`: the ports you list join the generated rendezvous"
                        }),
                );
            }
        }
        for p in &u.ports {
            if is_tick && p.to_string() == trigger {
                continue;
            }
            if let Some(e) = self.unknown_generated_port(p) {
                self.errors.push(e);
            }
            g.ports.push(p.clone());
        }
        let role_ok = match g.role {
            Role::Time => matches!(u.role, Role::Progress | Role::Time),
            Role::Environment => true,
            Role::Progress => u.role == Role::Progress,
        };
        if !role_ok {
            self.errors.push(
                ModelError::new(
                    format!(
                        "`{}` extends a generated connector whose role is fixed",
                        u.name
                    ),
                    u.name.span,
                )
                .with_help(
                    "only request connectors take a role from their extension (docs/genom.md)",
                ),
            );
        }
        if g.role == Role::Environment {
            // a request connector taken over by a user connector: its role is the user's
            // (by default `Progress`: a supervisor in the model sends the request)
            g.role = u.role;
            if let Some(s) = self.recipe_request_mut(g.name.as_str()) {
                s.owned_by_model = u.role != Role::Environment;
            }
        }
        if let (Some(ug), Some(written)) = (user.connector_guards.get(&k), &u.guard) {
            *guard = Some(match guard.take() {
                None => ug.tree.clone(),
                Some(gg) => and(gg, ug.tree.clone()),
            });
            let cond = RecipeCondition::from(Cond {
                reason: Reason::Connector {
                    connector: u.name.value.clone(),
                    guard: written.to_string(),
                },
                expr: ug.tree.clone(),
            });
            if let Some(s) = self.recipe_request_mut(g.name.as_str()) {
                s.refusals.push(cond);
            }
        }
        if let Some(ua) = user.connector_actions.get(&k) {
            action.extend(ua.tree.iter().cloned());
        }
    }

    fn recipe_request_mut(&mut self, connector: &str) -> Option<&mut RecipeService> {
        self.recipe
            .modules
            .iter_mut()
            .flat_map(|m| m.services.iter_mut())
            .find(|s| s.request == connector)
    }

    /// A user connector that does not extend a generated one may not use generated ports:
    /// that would run a codel, or accept a request, outside the gates.
    fn check_user_ports(&mut self, c: &ConnectorDef, generated: &HashSet<String>) {
        let mut texts: Vec<&ExprDef> = c.ports.iter().collect();
        if let ConnectorKindDef::Broadcast { trigger } = &c.kind {
            texts.push(trigger);
        }
        for p in texts {
            if let Some(e) = self.unknown_generated_port(p) {
                self.errors.push(e);
                continue;
            }
            let Ok(e) = p.tree() else { continue };
            let ExprKind::Member(base, port) = &e.kind else {
                continue;
            };
            let base = match &base.kind {
                ExprKind::Index(b, _) => b,
                _ => base,
            };
            let ExprKind::Name(comp) = &base.kind else {
                continue;
            };
            if port.name == "abort" && self.activity_components.contains(comp) {
                continue; // aborting an activity is open to every component
            }
            if generated.contains(comp) {
                let help = if comp == CLOCK {
                    "to receive the clock's tick, write a connector named `tick` with your ports: they join the generated tick".to_string()
                } else {
                    format!(
                        "name the connector like the generated one it should join (e.g. `{}`), or see docs/genom.md",
                        self.connector_for_port(comp, &port.name).unwrap_or_else(|| "rflex_TrackSpeed_request".into())
                    )
                };
                self.errors.push(
                    ModelError::new(
                        format!(
                            "`{p}` is a generated port; connector `{}` cannot use it",
                            c.name
                        ),
                        p.span(),
                    )
                    .with_help(help),
                );
            }
        }
    }

    /// A user's port `c.p` on a generated component `c` that has no port `p`, said of the
    /// module or activity `c` stands for (the compiler would name the generated atom).
    fn unknown_generated_port(&self, p: &ExprDef) -> Option<ModelError> {
        let e = p.tree().ok()?;
        let ExprKind::Member(base, port) = &e.kind else {
            return None;
        };
        let ExprKind::Name(comp) = &base.kind else {
            return None;
        };
        let c = self.components.iter().find(|c| c.name.as_str() == comp)?;
        let (_, atom) = self.atoms.iter().find(|(n, _)| *n == c.atom)?;
        if atom.ports.iter().any(|q| q.as_str() == port.name) {
            return None;
        }
        let (_, what) = self.names.get(comp.as_str())?;
        Some(
            ModelError::new(format!("{what} has no port `{}`", port.name), port.span).with_help(
                one_of("its ports are", atom.ports.iter().map(|q| q.as_str())),
            ),
        )
    }

    /// The generated connector that uses port `comp.port`, for help texts: connectors are
    /// named `<component>_<port>` for codels and requests.
    fn connector_for_port(&self, comp: &str, port: &str) -> Option<String> {
        let wanted = format!("{comp}_{port}");
        self.names.keys().filter(|n| **n == wanted).min().cloned()
    }

    /// Codels are urgent (the tick is below every codel step), requests wait for the
    /// functional layer to be quiescent (below every codel step), and codels of different
    /// activities run in declaration order (earlier activities above later ones). The
    /// declared priorities form a chain through the last activity; the core closes them
    /// transitively. Then the user's priorities.
    fn priorities(&mut self, user: &UserTexts) -> Vec<PriorityDef> {
        let mut levels: Vec<Vec<String>> = Vec::new(); // codel connectors per activity
        let mut requests: Vec<String> = Vec::new();
        for m in &self.recipe.modules {
            for s in &m.services {
                requests.push(s.request.clone());
                if s.component.is_some() {
                    let mut level = Vec::new();
                    for c in &s.codels {
                        level.push(c.run.clone());
                        level.push(c.fail.clone());
                    }
                    levels.push(level);
                }
            }
        }
        let pr = |low: &str, high: &str| PriorityDef {
            low: ExprDef::Built(name(low)),
            high: ExprDef::Built(name(high)),
            when: None,
        };
        let mut out = Vec::new();
        if let Some(last) = levels.last() {
            for high in last {
                out.push(pr(TICK, high));
                for r in &requests {
                    out.push(pr(r, high));
                }
            }
        }
        for pair in levels.windows(2) {
            for low in &pair[1] {
                for high in &pair[0] {
                    out.push(pr(low, high));
                }
            }
        }
        for (k, p) in self.def.priorities.iter().enumerate() {
            let mut p = p.clone();
            if let (Some(u), Some(written)) = (user.priority_whens.get(&k), &p.when) {
                p.when = Some(u.def(written));
            }
            out.push(p);
        }
        out
    }

    /// The user's properties with GenoM names rewritten; `DeadlockFree` excuses the states
    /// where no activity has work outstanding, if every request comes from the environment
    /// (once a component of the model sends requests, it is responsible for the layer's
    /// progress, and an idle layer may be a supervisor stuck: the user says when it is not
    /// with `terminal`).
    fn properties(&mut self, connectors: &[ConnectorDef], user: &UserTexts) -> Vec<PropertyDef> {
        let requests: HashSet<&str> = self
            .recipe
            .modules
            .iter()
            .flat_map(|m| m.services.iter().map(|s| s.request.as_str()))
            .collect();
        let open = !requests.is_empty()
            && connectors
                .iter()
                .filter(|c| requests.contains(c.name.as_str()))
                .all(|c| c.role == Role::Environment);
        // with no activity at all, nothing is ever outstanding
        let idle = open.then(|| {
            let activities = self
                .recipe
                .modules
                .iter()
                .flat_map(|m| m.services.iter())
                .filter_map(|s| s.component.as_deref());
            all(activities.map(|c| and(at(c, ETHER), not(member(c, REQ)))))
                .unwrap_or_else(|| boolean(true))
        });
        self.recipe.idle = idle.clone();
        let mut out = Vec::with_capacity(self.def.properties.len());
        for (k, p) in self.def.properties.iter().enumerate() {
            let rewritten = |written: &ExprDef| match user.properties.get(&k) {
                Some(u) => u.def(written),
                None => written.clone(),
            };
            out.push(match p {
                PropertyDef::DeadlockFree { terminal } => {
                    let user_terminal = user.properties.get(&k).map(|u| u.tree.clone());
                    let terminal = match (user_terminal, &idle) {
                        (Some(t), Some(idle)) => Some(ExprDef::Built(or(t, idle.clone()))),
                        (None, Some(idle)) => Some(ExprDef::Built(idle.clone())),
                        (_, None) => terminal.as_ref().map(rewritten),
                    };
                    PropertyDef::DeadlockFree { terminal }
                }
                PropertyDef::Invariant { name, expr } => PropertyDef::Invariant {
                    name: name.clone(),
                    expr: rewritten(expr),
                },
                PropertyDef::Reachable { name, expr } => PropertyDef::Reachable {
                    name: name.clone(),
                    expr: rewritten(expr),
                },
            });
        }
        out
    }
}

/// A value of ids field `x` as the model writes it (`true`/`false` for a `Bool`).
fn ids_literal(m: &Module, x: &str, v: i64) -> Expr {
    let is_bool = m
        .def
        .ids
        .iter()
        .any(|d| d.name.as_str() == x && matches!(d.ty, TypeDef::Bool));
    if is_bool {
        boolean(v != 0)
    } else {
        int(v)
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
