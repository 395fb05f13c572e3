//! Validation of the GenoM layer: names, tasks, codel automata, `interrupts`, `after` and
//! constraints, with every error at its place in the file. The result, [`Layer`], holds
//! indices instead of names, which is what the expansion works from.

use std::collections::{HashMap, HashSet};

use crate::compile::{check_name, one_of, unique, Constants};
use crate::diag::{Errors, ModelError};
use crate::source::{line_col, Span};
use crate::syntax::{
    CodelDef, ConstraintDef, ModuleDef, ServiceDef, ServiceKind, SystemDef, Text, TypeDef,
};
use bip_model::genom::map::{ConstraintRef, Reason};

/// The name of the final state of every activity (GenoM's `ether`).
pub const ETHER: &str = "ether";
/// The prefix of a yield that waits for the task's next period.
pub const PAUSE: &str = "pause::";
/// Port names of a generated activity atom that codel states may not take.
pub const ACTIVITY_PORTS: [&str; 4] = ["request", "interrupt", "abort", "tick"];
/// Port names of a generated module atom that services may not take.
pub const MODULE_PORTS: [&str; 2] = ["tick", "write"];
/// A codel that writes ids takes one step per combination of values it may write (the
/// verifier explores them all); more than this many is almost surely a modelling mistake.
pub const MAX_IDS_VALUES: u128 = 1024;

/// A service of a module: `(module, service)` indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ServiceRef {
    pub module: usize,
    pub service: usize,
}

/// A port of a module: `(module, port)` indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PortRef {
    pub module: usize,
    pub port: usize,
}

/// The validated layer.
#[derive(Debug)]
pub struct Layer<'d> {
    pub modules: Vec<Module<'d>>,
    pub constraints: Vec<Constraint<'d>>,
}

#[derive(Debug)]
pub struct Module<'d> {
    pub def: &'d ModuleDef,
    pub name: &'d str,
    /// Task names and periods (in ticks, at least 1).
    pub tasks: Vec<(&'d str, i64)>,
    pub ports: Vec<&'d str>,
    /// The ids fields and their ranges (`None` if a bound is not a constant: the core
    /// reports it).
    pub ids: Vec<(&'d str, Option<(i64, i64)>)>,
    pub services: Vec<Service<'d>>,
}

#[derive(Debug)]
pub struct Service<'d> {
    pub def: &'d ServiceDef,
    pub name: &'d str,
    pub kind: ServiceKind,
    /// The task of an activity.
    pub task: Option<usize>,
    /// Services of the same module this one interrupts (itself included, if listed).
    pub interrupts: Vec<usize>,
    pub after: Vec<usize>,
    /// The codels of an activity, in the order written.
    pub codels: Vec<Codel<'d>>,
    /// Codel states that are locations of the activity's atom: the targets of yields, and
    /// `stop` (where an interrupt leads). `start` is one only if a codel yields to it.
    pub locations: Vec<usize>,
    /// Index of the `stop` codel, if declared.
    pub stop: Option<usize>,
}

impl Service<'_> {
    pub fn is_activity(&self) -> bool {
        self.kind == ServiceKind::Activity
    }

    pub fn interrupts_itself(&self, me: usize) -> bool {
        self.interrupts.contains(&me)
    }

    /// Index of the codel at `state`.
    pub fn codel(&self, state: &str) -> Option<usize> {
        self.codels.iter().position(|c| c.state == state)
    }

    /// True if `state` names a location of the activity's atom (`ether` included).
    pub fn is_location(&self, state: &str) -> bool {
        state == ETHER
            || self
                .locations
                .iter()
                .any(|&k| self.codels[k].state == state)
    }
}

#[derive(Debug)]
pub struct Codel<'d> {
    pub def: &'d CodelDef,
    pub state: &'d str,
    pub yields: Vec<Yield>,
    /// Written ports (indices into the module's ports).
    pub writes: Vec<usize>,
    /// Written ids fields (indices into the module's ids), in the module's order.
    pub ids: Vec<usize>,
    pub throws: Vec<&'d str>,
}

/// Where a codel may go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Yield {
    /// Run this codel next, in the same cycle.
    Go(usize),
    /// Run this codel at the task's next period.
    Pause(usize),
    /// The activity ends successfully.
    Ether,
}

#[derive(Debug)]
pub struct Constraint<'d> {
    pub kind: ConstraintKind<'d>,
    /// What the requests it refuses and the codels it holds say.
    pub reason: Reason,
}

#[derive(Debug)]
pub enum ConstraintKind<'d> {
    Exclusive(Vec<ServiceRef>),
    AtMost {
        max: i64,
        services: Vec<ServiceRef>,
    },
    Requires {
        service: ServiceRef,
        active: Vec<ServiceRef>,
    },
    Fresh {
        service: ServiceRef,
        port: PortRef,
        max_age: i64,
    },
    Guard {
        service: ServiceRef,
        when: &'d Text,
    },
}

/// Validates the modules and constraints of `def`; `text` is the file it was read from,
/// if any (reasons give the constraints' lines).
pub fn check<'d>(
    def: &'d SystemDef,
    consts: &Constants,
    text: Option<&str>,
) -> Result<Layer<'d>, Vec<ModelError>> {
    let mut errors = Errors::default();
    unique(&mut errors, def.modules.iter().map(|m| &m.name), "module");
    let mut seen = HashSet::new();
    let mut modules = Vec::new();
    for m in &def.modules {
        if !check_name(&mut errors, &m.name, "module") || !seen.insert(m.name.as_str()) {
            continue;
        }
        modules.push(module(&mut errors, consts, m));
    }
    let mut layer = Layer {
        modules,
        constraints: Vec::new(),
    };
    unique(
        &mut errors,
        def.constraints.iter().filter_map(ConstraintDef::name),
        "constraint name",
    );
    for (index, c) in def.constraints.iter().enumerate() {
        if let Some(k) = constraint(&mut errors, consts, &layer, c) {
            let reason = Reason::Constraint(ConstraintRef {
                index,
                kind: c.kind().to_string(),
                name: c.name().map(|n| n.value.clone()),
                written: c.written(),
                line: text
                    .filter(|_| !c.span().is_none())
                    .and_then(|t| u32::try_from(line_col(t, c.span().start).0).ok()),
            });
            layer.constraints.push(Constraint { kind: k, reason });
        }
    }
    if errors.is_empty() {
        Ok(layer)
    } else {
        Err(errors.list)
    }
}

fn module<'d>(errors: &mut Errors, consts: &Constants, m: &'d ModuleDef) -> Module<'d> {
    let what = |kind: &str| format!("{kind} of module `{}`", m.name);
    unique(errors, m.tasks.iter().map(|t| &t.name), &what("task"));
    unique(errors, m.ports.iter().map(|p| &p.name), &what("port"));
    unique(errors, m.services.iter().map(|s| &s.name), &what("service"));
    let mut tasks = Vec::new();
    for t in &m.tasks {
        check_name(errors, &t.name, "task");
        let period = match consts.int(&t.period) {
            Ok(p) if p >= 1 => p,
            Ok(p) => {
                errors.push(
                    ModelError::new(format!("task `{}` has period {p}", t.name), t.period.span)
                        .with_label("a period is at least 1 tick")
                        .with_help("a task releases its paused activities every `period` ticks"),
                );
                1
            }
            Err(e) => {
                errors.push(e);
                1
            }
        };
        tasks.push((t.name.as_str(), period));
    }
    for p in &m.ports {
        check_name(errors, &p.name, "port");
    }
    let ports: Vec<&str> = m.ports.iter().map(|p| p.name.as_str()).collect();
    let ids: Vec<(&str, Option<(i64, i64)>)> = m
        .ids
        .iter()
        .map(|v| {
            let range = match &v.ty {
                TypeDef::Bool => Some((0, 1)),
                TypeDef::Int(lo, hi) => consts.int(lo).ok().zip(consts.int(hi).ok()),
            };
            (v.name.as_str(), range)
        })
        .collect();
    let index: HashMap<&str, usize> = m
        .services
        .iter()
        .enumerate()
        .rev() // the first of duplicates wins
        .map(|(k, s)| (s.name.as_str(), k))
        .collect();
    let services: Vec<Service> = m
        .services
        .iter()
        .map(|s| service(errors, m, &tasks, &ports, &ids, &index, s))
        .collect();
    // the port of the module atom through which a codel writes ids must be free
    for s in services.iter().filter(|s| s.is_activity()) {
        for c in s.codels.iter().filter(|c| !c.ids.is_empty()) {
            let port = super::names::ids_port(s.name, c.state);
            if let Some(f) = services.iter().find(|f| !f.is_activity() && f.name == port) {
                errors.push(
                    ModelError::new(
                        format!("a function or attribute cannot be named `{port}`"),
                        f.def.name.span,
                    )
                    .with_note(c.def.state.span, "this codel writes ids through that port")
                    .with_help("docs/genom.md, \"Codels that write ids\""),
                );
            }
        }
    }
    Module {
        def: m,
        name: m.name.as_str(),
        tasks,
        ports,
        ids,
        services,
    }
}

fn service<'d>(
    errors: &mut Errors,
    m: &'d ModuleDef,
    tasks: &[(&str, i64)],
    ports: &[&str],
    ids: &[(&str, Option<(i64, i64)>)],
    index: &HashMap<&str, usize>,
    s: &'d ServiceDef,
) -> Service<'d> {
    check_name(errors, &s.name, "service");
    let activity = s.kind == ServiceKind::Activity;
    if !activity && MODULE_PORTS.contains(&s.name.as_str()) {
        errors.push(
            ModelError::new(
                format!("a function or attribute cannot be named `{}`", s.name),
                s.name.span,
            )
            .with_help(format!(
                "`{}` names a port of the module's generated atom (docs/genom.md)",
                s.name
            )),
        );
    }
    let lookup = |errors: &mut Errors, t: &Text, what: &str| -> Option<usize> {
        let found = index.get(t.as_str()).copied();
        if found.is_none() {
            errors.push(
                ModelError::new(format!("module `{}` has no service `{t}`", m.name), t.span)
                    .with_label(format!("unknown service in `{what}`"))
                    .with_help(one_of(
                        "its services are",
                        m.services.iter().map(|s| s.name.as_str()),
                    )),
            );
        }
        found
    };
    let mut interrupts = Vec::new();
    unique(errors, s.interrupts.iter(), "service in `interrupts`");
    for t in &s.interrupts {
        if let Some(k) = lookup(errors, t, "interrupts") {
            if m.services[k].kind != ServiceKind::Activity {
                errors.push(
                    ModelError::new(format!("`{t}` is not an activity"), t.span)
                        .with_help("only activities run long enough to be interrupted"),
                );
            } else if !interrupts.contains(&k) {
                interrupts.push(k);
            }
        }
    }
    let mut after = Vec::new();
    unique(errors, s.after.iter(), "service in `after`");
    for t in &s.after {
        if let Some(k) = lookup(errors, t, "after") {
            if k == index.get(s.name.as_str()).copied().unwrap_or(usize::MAX) {
                errors.push(
                    ModelError::new(format!("`{t}` cannot come after itself"), t.span)
                        .with_help("`after` lists services that must have completed before"),
                );
            } else if !after.contains(&k) {
                after.push(k);
            }
        }
    }
    let mut out = Service {
        def: s,
        name: s.name.as_str(),
        kind: s.kind,
        task: None,
        interrupts,
        after,
        codels: Vec::new(),
        locations: Vec::new(),
        stop: None,
    };
    if !activity {
        if let Some(t) = &s.task {
            errors.push(
                ModelError::new(
                    format!("`{}` is not an activity; it has no task", s.name),
                    t.span,
                )
                .with_help("functions and attributes run in the control task"),
            );
        }
        if let Some(c) = s.codels.first() {
            errors.push(
                ModelError::new(
                    format!("`{}` is not an activity; it has no codel states", s.name),
                    c.state.span,
                )
                .with_help("a function or attribute runs at once when requested; declare it `kind: Activity` to give it codels"),
            );
        }
        return out;
    }
    match &s.task {
        None => errors.push(
            ModelError::new(format!("activity `{}` has no `task`", s.name), s.name.span)
                .with_help(one_of("the module's tasks are", tasks.iter().map(|t| t.0))),
        ),
        Some(t) => match tasks.iter().position(|x| x.0 == t.as_str()) {
            Some(k) => out.task = Some(k),
            None => errors.push(
                ModelError::new(format!("module `{}` has no task `{t}`", m.name), t.span)
                    .with_help(one_of("its tasks are", tasks.iter().map(|t| t.0))),
            ),
        },
    }
    codels(errors, ports, ids, s, &mut out);
    out
}

/// Checks an activity's codel automaton and fills in its codels and locations.
fn codels<'d>(
    errors: &mut Errors,
    ports: &[&str],
    ids: &[(&str, Option<(i64, i64)>)],
    s: &'d ServiceDef,
    out: &mut Service<'d>,
) {
    let before = errors.list.len();
    unique(errors, s.codels.iter().map(|c| &c.state), "codel state");
    let states: Vec<&str> = s.codels.iter().map(|c| c.state.as_str()).collect();
    let state_index = |name: &str| states.iter().position(|&x| x == name);
    for c in &s.codels {
        if !check_name(errors, &c.state, "codel state") {
            continue;
        }
        let n = c.state.as_str();
        if n == ETHER {
            errors.push(
                ModelError::new("`ether` is the final state; it has no codel", c.state.span)
                    .with_help("yield `ether` to end the activity"),
            );
        } else if ACTIVITY_PORTS.contains(&n) {
            errors.push(
                ModelError::new(format!("a codel state cannot be named `{n}`"), c.state.span)
                    .with_help(format!(
                        "`{n}` names a port of the activity's generated atom (docs/genom.md)"
                    )),
            );
        } else if let Some(base) = n.strip_suffix("_fail") {
            if s.codels.iter().any(|o| o.state.as_str() == base) {
                errors.push(
                    ModelError::new(format!("a codel state cannot be named `{n}`"), c.state.span)
                        .with_help(format!("`{n}` names the error port of codel `{base}`")),
                );
            }
        }
    }
    if state_index("start").is_none() {
        errors.push(
            ModelError::new(
                format!("activity `{}` has no `start` codel", s.name),
                s.name.span,
            )
            .with_help("every activity begins at its `start` codel state"),
        );
    }
    for c in &s.codels {
        let mut yields = Vec::new();
        if c.yields.is_empty() {
            errors.push(
                ModelError::new(format!("codel `{}` yields nothing", c.state), c.state.span)
                    .with_help(
                        "list the states it may go to, e.g. `yields: [\"pause::main\", \"ether\"]`",
                    ),
            );
        }
        unique(errors, c.yields.iter(), "yield");
        for y in &c.yields {
            let (paused, target) = match y.as_str().strip_prefix(PAUSE) {
                Some(t) => (true, t),
                None => (false, y.as_str()),
            };
            if target == ETHER {
                if paused {
                    errors.push(
                        ModelError::new("`pause::ether` is not a yield", y.span)
                            .with_help("an activity ends at once: yield `ether`"),
                    );
                } else {
                    yields.push(Yield::Ether);
                }
                continue;
            }
            match state_index(target) {
                Some(k) => yields.push(if paused { Yield::Pause(k) } else { Yield::Go(k) }),
                None => errors.push(
                    ModelError::new(
                        format!(
                            "codel `{}` yields to `{target}`, which is not a codel state of `{}`",
                            c.state, s.name
                        ),
                        y.span,
                    )
                    .with_label("undeclared state")
                    .with_help(one_of(
                        "yield `ether`, a codel state or `pause::` and a codel state; the codel states are",
                        states.iter().copied(),
                    )),
                ),
            }
        }
        let mut writes = Vec::new();
        let mut written_ids = Vec::new();
        let mut combinations: u128 = 1;
        unique(errors, c.writes.iter(), "written port or ids field");
        for w in &c.writes {
            let port = ports.iter().position(|&p| p == w.as_str());
            let field = ids.iter().position(|&(x, _)| x == w.as_str());
            match (port, field) {
                (Some(_), Some(_)) => errors.push(
                    ModelError::new(
                        format!("`{w}` is both an out port and an ids field of the module"),
                        w.span,
                    )
                    .with_help("rename one of them: `writes` would not say which it writes"),
                ),
                (Some(k), None) => {
                    if !writes.contains(&k) {
                        writes.push(k);
                    }
                }
                (None, Some(k)) => {
                    if written_ids.contains(&k) {
                        continue;
                    }
                    written_ids.push(k);
                    if let Some((lo, hi)) = ids[k].1 {
                        // a full 64-bit range has 2^64 values: count in 128 bits
                        let values = u128::try_from(i128::from(hi) - i128::from(lo) + 1)
                            .unwrap_or(0)
                            .max(1);
                        combinations = combinations.saturating_mul(values);
                        if combinations > MAX_IDS_VALUES {
                            errors.push(
                                ModelError::new(
                                    format!(
                                        "codel `{}` may write {combinations} combinations of ids values; at most {MAX_IDS_VALUES}",
                                        c.state
                                    ),
                                    w.span,
                                )
                                .with_label("here the count passes the limit")
                                .with_help("a codel's step takes every value its written ids may hold, so that the verifier covers them all: narrow the ranges, or write fewer fields"),
                            );
                        }
                    }
                }
                (None, None) => errors.push(
                    ModelError::new(
                        format!("the module has no out port or ids field `{w}`"),
                        w.span,
                    )
                    .with_help(one_of(
                        "its ports and ids fields are",
                        ports.iter().copied().chain(ids.iter().map(|&(x, _)| x)),
                    )),
                ),
            }
        }
        written_ids.sort_unstable();
        unique(errors, c.throws.iter(), "exception");
        for t in &c.throws {
            check_name(errors, t, "exception");
        }
        out.codels.push(Codel {
            def: c,
            state: c.state.as_str(),
            yields,
            writes,
            ids: written_ids,
            throws: c.throws.iter().map(|t| t.as_str()).collect(),
        });
    }
    if errors.list.len() > before {
        return; // the graph checks need every yield resolved
    }
    out.stop = state_index("stop");
    let mut locations: Vec<usize> = Vec::new();
    for c in &out.codels {
        for y in &c.yields {
            if let Yield::Go(k) | Yield::Pause(k) = *y {
                if !locations.contains(&k) {
                    locations.push(k);
                }
            }
        }
    }
    if let Some(k) = out.stop {
        if !locations.contains(&k) {
            locations.push(k);
        }
    }
    locations.sort_unstable();
    out.locations = locations;
    paths(errors, s, out);
}

/// The checks on the codel graph: `start` → `ether` and `stop` → `ether`, every codel
/// reached, and no loop without a pause (which would stop time).
fn paths(errors: &mut Errors, s: &ServiceDef, out: &Service<'_>) {
    let n = out.codels.len();
    let next = |k: usize, with_pause: bool| -> Vec<usize> {
        out.codels[k]
            .yields
            .iter()
            .filter_map(|y| match *y {
                Yield::Go(t) => Some(t),
                Yield::Pause(t) if with_pause => Some(t),
                _ => None,
            })
            .collect()
    };
    let reach = |from: usize| -> Vec<bool> {
        let mut seen = vec![false; n];
        let mut stack = vec![from];
        seen[from] = true;
        while let Some(k) = stack.pop() {
            for t in next(k, true) {
                if !seen[t] {
                    seen[t] = true;
                    stack.push(t);
                }
            }
        }
        seen
    };
    let ends =
        |seen: &[bool]| (0..n).any(|k| seen[k] && out.codels[k].yields.contains(&Yield::Ether));
    let mut reached = vec![false; n];
    for root in ["start", "stop"] {
        let Some(k) = out.codel(root) else { continue };
        let seen = reach(k);
        if !ends(&seen) {
            errors.push(
                ModelError::new(
                    format!("no path from `{root}` to `ether` in activity `{}`", s.name),
                    out.codels[k].def.state.span,
                )
                .with_label("the activity could never end from here")
                .with_help("some codel reachable from here must yield `ether`"),
            );
        }
        for (r, x) in reached.iter_mut().zip(seen) {
            *r |= x;
        }
    }
    for (k, c) in out.codels.iter().enumerate() {
        if !reached[k] {
            errors.push(
                ModelError::new(
                    format!(
                        "codel `{}` is never reached from `start` or `stop`",
                        c.state
                    ),
                    c.def.state.span,
                )
                .with_help("no codel yields to it; remove it or yield to it"),
            );
        }
    }
    // a cycle of yields without `pause::` would run forever within one instant
    let mut colour = vec![0u8; n]; // 0 new, 1 on the stack, 2 done
    for root in 0..n {
        if colour[root] != 0 {
            continue;
        }
        let mut stack: Vec<(usize, usize)> = vec![(root, 0)];
        colour[root] = 1;
        while let Some(top) = stack.last_mut() {
            let (k, i) = *top;
            let succ = next(k, false);
            if i < succ.len() {
                top.1 += 1;
                let t = succ[i];
                if colour[t] == 1 {
                    let from = stack.iter().position(|&(x, _)| x == t).unwrap_or(0);
                    let mut names: Vec<&str> = stack[from..]
                        .iter()
                        .map(|&(x, _)| out.codels[x].state)
                        .collect();
                    names.push(out.codels[t].state);
                    let span = yield_span(out, k, t).unwrap_or(out.codels[k].def.state.span);
                    errors.push(
                        ModelError::new(
                            format!("the codels {} loop without a pause", names.join(" → ")),
                            span,
                        )
                        .with_label("this yield closes the loop")
                        .with_help(format!(
                            "time cannot pass while a codel can run; yield `pause::{}` to wait for the next period",
                            out.codels[t].state
                        )),
                    );
                    return;
                }
                if colour[t] == 0 {
                    colour[t] = 1;
                    stack.push((t, 0));
                }
            } else {
                colour[k] = 2;
                stack.pop();
            }
        }
    }
}

/// The span of codel `from`'s plain yield to codel `to`.
fn yield_span(out: &Service<'_>, from: usize, to: usize) -> Option<Span> {
    let c = &out.codels[from];
    c.def
        .yields
        .iter()
        .find(|y| y.as_str() == out.codels[to].state)
        .map(|y| y.span)
}

/// Resolves `"module.Service"`.
pub fn service_ref(errors: &mut Errors, layer: &Layer<'_>, t: &Text) -> Option<ServiceRef> {
    let (m, s, ms, ss) = split_dotted(errors, t, "`module.Service`")?;
    let Some(mi) = layer.modules.iter().position(|x| x.name == m) else {
        errors.push(
            ModelError::new(format!("unknown module `{m}`"), ms).with_help(one_of(
                "the modules are",
                layer.modules.iter().map(|x| x.name),
            )),
        );
        return None;
    };
    let module = &layer.modules[mi];
    let Some(si) = module.services.iter().position(|x| x.name == s) else {
        errors.push(
            ModelError::new(format!("module `{m}` has no service `{s}`"), ss)
                .with_label("unknown service")
                .with_help(one_of(
                    "its services are",
                    module.services.iter().map(|x| x.name),
                )),
        );
        return None;
    };
    Some(ServiceRef {
        module: mi,
        service: si,
    })
}

/// Resolves `"module.port"`.
fn port_ref(errors: &mut Errors, layer: &Layer<'_>, t: &Text) -> Option<PortRef> {
    let (m, p, ms, ps) = split_dotted(errors, t, "`module.port`")?;
    let Some(mi) = layer.modules.iter().position(|x| x.name == m) else {
        errors.push(
            ModelError::new(format!("unknown module `{m}`"), ms).with_help(one_of(
                "the modules are",
                layer.modules.iter().map(|x| x.name),
            )),
        );
        return None;
    };
    let module = &layer.modules[mi];
    let Some(pi) = module.ports.iter().position(|&x| x == p) else {
        errors.push(
            ModelError::new(format!("module `{m}` has no out port `{p}`"), ps)
                .with_help(one_of("its ports are", module.ports.iter().copied())),
        );
        return None;
    };
    Some(PortRef {
        module: mi,
        port: pi,
    })
}

/// Splits `"a.b"` into its two names and their spans in the file.
fn split_dotted<'t>(
    errors: &mut Errors,
    t: &'t Text,
    form: &str,
) -> Option<(&'t str, &'t str, Span, Span)> {
    let text = t.as_str();
    let ok = |s: &str| {
        s.chars()
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
    };
    match text.split_once('.') {
        Some((a, b)) if ok(a) && ok(b) => Some((
            a,
            b,
            t.sub_span(0..a.len()),
            t.sub_span(a.len() + 1..text.len()),
        )),
        _ => {
            errors.push(ModelError::new(
                format!("expected {form}, found `{text}`"),
                t.span,
            ));
            None
        }
    }
}

fn constraint<'d>(
    errors: &mut Errors,
    consts: &Constants,
    layer: &Layer<'d>,
    c: &'d ConstraintDef,
) -> Option<ConstraintKind<'d>> {
    let svc = |errors: &mut Errors, t: &Text| service_ref(errors, layer, t);
    let activity = |errors: &mut Errors, t: &Text, why: &str| -> Option<ServiceRef> {
        let r = svc(errors, t)?;
        if layer.modules[r.module].services[r.service].is_activity() {
            Some(r)
        } else {
            errors.push(
                ModelError::new(format!("`{t}` is not an activity"), t.span)
                    .with_help(format!("{why}; functions and attributes are never active")),
            );
            None
        }
    };
    let list = |errors: &mut Errors, ts: &[Text], why: &str, min: usize, anchor: Span| {
        unique(errors, ts.iter(), "service");
        let out: Vec<Option<ServiceRef>> = ts.iter().map(|t| activity(errors, t, why)).collect();
        if ts.len() < min {
            errors.push(ModelError::new(
                format!("`{}` needs at least {min} services", c.kind()),
                ts.first().map_or(anchor, |t| t.span),
            ));
        }
        out.into_iter().collect::<Option<Vec<_>>>()
    };
    match c {
        ConstraintDef::Exclusive { services, .. } => {
            let why = "`Exclusive` is about activities being active";
            list(errors, services, why, 2, Span::NONE).map(ConstraintKind::Exclusive)
        }
        ConstraintDef::AtMost { max, services, .. } => {
            let why = "`AtMost` counts active activities";
            let l = list(errors, services, why, 2, max.span);
            let k = match consts.int(max) {
                Ok(k) if k >= 1 => Some(k),
                Ok(k) => {
                    errors.push(
                        ModelError::new(format!("`max` is {k}; it must be at least 1"), max.span)
                            .with_help("with `max: 0` none of the services could ever start"),
                    );
                    None
                }
                Err(e) => {
                    errors.push(e);
                    None
                }
            };
            Some(ConstraintKind::AtMost {
                max: k?,
                services: l?,
            })
        }
        ConstraintDef::Requires {
            service, active, ..
        } => {
            let s = svc(errors, service);
            let why = "`Requires` lists services that must be active";
            let l = list(errors, active, why, 1, service.span);
            let (s, l) = (s?, l?);
            if l.contains(&s) {
                errors.push(ModelError::new(
                    format!("`{service}` cannot require itself"),
                    service.span,
                ));
                return None;
            }
            Some(ConstraintKind::Requires {
                service: s,
                active: l,
            })
        }
        ConstraintDef::Fresh {
            service,
            port,
            max_age,
            ..
        } => {
            let s = svc(errors, service);
            let p = port_ref(errors, layer, port);
            let k = match consts.int(max_age) {
                Ok(k) if k == i64::MAX => {
                    errors.push(too_old(k, max_age.span));
                    None
                }
                Ok(k) if k >= 0 => Some(k),
                Ok(k) => {
                    errors.push(ModelError::new(
                        format!("`max_age` is {k}; an age is never negative"),
                        max_age.span,
                    ));
                    None
                }
                Err(e) => {
                    errors.push(e);
                    None
                }
            };
            Some(ConstraintKind::Fresh {
                service: s?,
                port: p?,
                max_age: k?,
            })
        }
        ConstraintDef::Guard { service, when, .. } => Some(ConstraintKind::Guard {
            service: svc(errors, service)?,
            when,
        }),
    }
}

/// An age compared with `k`: ages count up to one more than the largest such constant,
/// which must fit in 64 bits.
pub fn too_old(k: i64, span: Span) -> ModelError {
    ModelError::new(format!("an age cannot be compared with {k}"), span)
        .with_label("ages count up to one more than this, which does not fit in 64 bits")
        .with_help("an age is a number of ticks: compare it with a smaller constant")
}
