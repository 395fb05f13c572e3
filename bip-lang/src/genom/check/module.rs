//! A module and its services: tasks and their periods, out and in ports, the `ids` fields and their
//! bounds, and each service's kind, task, `interrupts` and `after`, resolved to indices
//! within the module.

use std::collections::HashMap;

use super::codels::codels;
use super::types::data_type;
use super::{InPort, Module, Service, ETHER, MODULE_PORTS, VALIDATE};
use crate::compile::{check_name, one_of, unique, Constants};
use crate::diag::{Errors, ModelError};
use crate::syntax::{ModuleDef, ServiceDef, ServiceKind, TaskDef, Text, TypeDef};

pub(super) fn module<'d>(errors: &mut Errors, consts: &Constants, m: &'d ModuleDef) -> Module<'d> {
    let what = |kind: &str| format!("{kind} of module `{}`", m.name);
    unique(errors, m.tasks.iter().map(|t| &t.name), &what("task"));
    unique(
        errors,
        m.ports.iter().chain(&m.in_ports).map(|p| &p.name),
        &what("port"),
    );
    unique(
        errors,
        m.services.iter().filter(|s| !s.machine).map(|s| &s.name),
        &what("service"),
    );
    machine_names(errors, m);
    let mut tasks = Vec::new();
    let mut delays = Vec::new();
    for t in &m.tasks {
        check_name(errors, &t.name, "task");
        let period = t.period.as_ref().map(|written| match consts.int(written) {
            Ok(p) if p >= 1 => p,
            Ok(p) => {
                errors.push(
                    ModelError::new(format!("task `{}` has period {p}", t.name), written.span)
                        .with_label("a period is at least 1 tick")
                        .with_help("a task releases its paused activities every `period` ticks; leave `period` out for a task that runs its codels as soon as they are ready"),
                );
                1
            }
            Err(e) => {
                errors.push(e);
                1
            }
        });
        tasks.push((t.name.as_str(), period));
        delays.push(delay(errors, consts, t, period));
    }
    for p in m.ports.iter().chain(&m.in_ports) {
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
    let mut services: Vec<Service> = m
        .services
        .iter()
        .map(|s| service(errors, m, &tasks, &ports, &ids, &index, s))
        .collect();
    before(errors, m, &index, &mut services);
    let port_types = m
        .ports
        .iter()
        .map(|p| p.ty.as_ref().and_then(|t| data_type(errors, consts, t)))
        .collect();
    let in_ports = m
        .in_ports
        .iter()
        .map(|p| InPort {
            name: p.name.as_str(),
            ty: p.ty.as_ref().and_then(|t| data_type(errors, consts, t)),
            reads: None,
        })
        .collect();
    for s in &mut services {
        service_types(errors, consts, s);
    }
    // the port of the module atom through which a codel writes ids must be free
    for s in services.iter().filter(|s| s.is_activity()) {
        for c in s.codels.iter().filter(|c| !c.ids.is_empty()) {
            let port = crate::genom::names::ids_port(s.name, c.state);
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
    // so must the port through which a codel run at a request fails
    for s in &services {
        let codels = [
            s.function.as_ref().map(|c| (c.state, c.def.state.span)),
            s.def.validate.as_ref().map(|_| (VALIDATE, s.def.name.span)),
        ];
        for (codel, span) in codels.into_iter().flatten() {
            let port = crate::genom::names::request_fail_port(s.name, codel);
            if let Some(f) = services.iter().find(|f| !f.is_activity() && f.name == port) {
                errors.push(
                    ModelError::new(
                        format!("a function or attribute cannot be named `{port}`"),
                        f.def.name.span,
                    )
                    .with_note(span, "this codel fails through that port")
                    .with_help("docs/genom.md, \"Codels at the request\""),
                );
            }
        }
    }
    Module {
        def: m,
        name: m.name.as_str(),
        tasks,
        delays,
        ports,
        port_types,
        in_ports,
        ids,
        services,
    }
}

/// A task's `delay`: the offset of its period boundaries, from 0 to one less than its
/// period (0 if not given).
fn delay(errors: &mut Errors, consts: &Constants, t: &TaskDef, period: Option<i64>) -> i64 {
    let Some(written) = &t.delay else { return 0 };
    let Some(period) = period else {
        errors.push(
            ModelError::new(format!("task `{}` has a delay but no period", t.name), written.span)
                .with_label("a delay offsets period boundaries, which this task has none of")
                .with_help("give the task a `period`, or leave the delay out (an aperiodic task runs its codels as soon as they are ready)"),
        );
        return 0;
    };
    match consts.int(written) {
        Ok(d) if (0..period).contains(&d) => d,
        Ok(d) => {
            errors.push(
                ModelError::new(format!("task `{}` has delay {d}", t.name), written.span)
                    .with_label(format!("a delay is from 0 to {} ticks", period - 1))
                    .with_help(
                        "a delay offsets the task's period boundaries: it is below the period",
                    ),
            );
            0
        }
        Err(e) => {
            errors.push(e);
            0
        }
    }
}

/// `before`: each service it lists waits for this one, as if it listed this one in its
/// `after` (the checks and the expansion of `after` then serve both).
fn before(
    errors: &mut Errors,
    m: &ModuleDef,
    index: &HashMap<&str, usize>,
    services: &mut [Service<'_>],
) {
    for (k, s) in m.services.iter().enumerate() {
        if index.get(s.name.as_str()) != Some(&k) {
            continue; // a duplicate, reported
        }
        unique(errors, s.before.iter(), "service in `before`");
        for t in &s.before {
            let Some(&w) = index.get(t.as_str()) else {
                errors.push(
                    ModelError::new(format!("module `{}` has no service `{t}`", m.name), t.span)
                        .with_label("unknown service in `before`")
                        .with_help(one_of(
                            "its services are",
                            m.services.iter().map(|s| s.name.as_str()),
                        )),
                );
                continue;
            };
            if m.services[w].machine {
                errors.push(
                    ModelError::new(format!("`{t}` is the machine of task `{t}`"), t.span)
                        .with_label("in `before`")
                        .with_help("a task's machine runs from the component's start; no service waits for it"),
                );
            } else if w == k {
                errors.push(
                    ModelError::new(format!("`{t}` cannot come before itself"), t.span)
                        .with_help("`before` lists services that wait for this one to complete"),
                );
            } else if !services[w].after.contains(&k) {
                services[w].after.push(k);
            }
        }
    }
}

/// A task's machine is named like its task, in expressions, constraints and the engine's
/// map alike: no service of the module may take that name.
fn machine_names(errors: &mut Errors, m: &ModuleDef) {
    for t in m.services.iter().filter(|s| s.machine) {
        if let Some(s) = m.services.iter().find(|s| !s.machine && s.name == t.name) {
            errors.push(
                ModelError::new(
                    format!(
                        "task `{}` runs a machine, and module `{}` has a service of that name",
                        t.name, m.name
                    ),
                    t.name.span,
                )
                .with_note(s.name.span, "the service")
                .with_help(format!(
                    "a task's machine is named `{}.{}` like a service (docs/genom.md, \"Task machines\"): rename the task or the service",
                    m.name, t.name
                )),
            );
        }
    }
}

/// The types of a service's arguments and output. A function or attribute without a codel
/// has nothing to read arguments (but a `validate` codel) or give an output.
fn service_types(errors: &mut Errors, consts: &Constants, s: &mut Service<'_>) {
    let def = s.def;
    for (what, ty) in [("arguments", &def.args), ("an output", &def.output)] {
        let Some(ty) = ty else { continue };
        let read = s.function.is_some() || (what == "arguments" && s.validate.is_some());
        if !s.is_activity() && !read {
            let field = if what == "arguments" {
                "args"
            } else {
                "output"
            };
            errors.push(
                ModelError::new(
                    format!(
                        "`{}` is not an activity and has no codel for {what}",
                        s.name
                    ),
                    def.name.span,
                )
                .with_label(format!("has `{field}`"))
                .with_help(
                    "an activity's codels, a function's codel and a `validate` codel read a request's arguments; an activity's or a function's codels give an output",
                ),
            );
            continue;
        }
        let t = data_type(errors, consts, ty);
        if what == "arguments" {
            s.args = t;
        } else {
            s.output = t;
        }
    }
}

fn service<'d>(
    errors: &mut Errors,
    m: &'d ModuleDef,
    tasks: &[(&str, Option<i64>)],
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
        if found.is_some_and(|k| m.services[k].machine) {
            errors.push(
                ModelError::new(format!("`{t}` is the machine of task `{t}`"), t.span)
                    .with_label(format!("in `{what}`"))
                    .with_help("a task's machine runs from the component's start; no service interrupts it or waits for it"),
            );
            return None;
        }
        if let (None, Some((module, service))) = (found, t.split_once('.')) {
            // `after: ["loc.Track"]`: a name of another module, or this one's written in full
            let same = if module == m.name.as_str() {
                format!("write `{service}`")
            } else {
                format!("`{service}` of module `{module}` cannot be named here")
            };
            errors.push(
                ModelError::new(
                    format!("`{what}` names services of the same module, by their names alone"),
                    t.span,
                )
                .with_label("a module's name, then a service's")
                .with_help(format!(
                    "{same}; {}",
                    one_of(
                        &format!("the services of `{}` are", m.name),
                        m.services.iter().map(|s| s.name.as_str()),
                    )
                )),
            );
            return None;
        }
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
        function: None,
        validate: None,
        locations: Vec::new(),
        stop: None,
        args: None,
        output: None,
        machine: s.machine,
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
        function_codel(errors, ports, ids, s, &mut out);
        validate(errors, s, &mut out);
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
    validate(errors, s, &mut out);
    out
}

/// A function's or attribute's codel, which runs when its request is accepted: one codel,
/// at `start`, yielding `ether` (GenoM3's function codel has no states).
fn function_codel<'d>(
    errors: &mut Errors,
    ports: &[&str],
    ids: &[(&str, Option<(i64, i64)>)],
    s: &'d ServiceDef,
    out: &mut Service<'d>,
) {
    if s.codels.is_empty() {
        return;
    }
    let shape = s.codels.len() == 1
        && s.codels[0].state.as_str() == "start"
        && s.codels[0].yields.len() == 1
        && s.codels[0].yields[0].as_str() == ETHER;
    if !shape {
        let at = s.codels.get(1).unwrap_or(&s.codels[0]).state.span;
        errors.push(
            ModelError::new(
                format!("`{}` is not an activity; it has one codel, at `start`, yielding `ether`", s.name),
                at,
            )
            .with_help("a function or attribute runs its codel at once when requested: `codels: [(state: \"start\", yields: [\"ether\"])]`; declare it `kind: Activity` to give it codel states"),
        );
        return;
    }
    if s.codels[0].asynchronous {
        errors.push(
            ModelError::new(
                format!("the codel of `{}` cannot be async", s.name),
                s.codels[0].state.span,
            )
            .with_help("a function's codel runs in the control task when the request arrives; an activity's codel may run apart"),
        );
        return;
    }
    codels(errors, ports, ids, s, out);
    out.function = out.codels.pop();
    out.codels.clear();
}

/// A service's `validate` codel: its exceptions.
fn validate<'d>(errors: &mut Errors, s: &'d ServiceDef, out: &mut Service<'d>) {
    let Some(v) = &s.validate else { return };
    unique(errors, v.throws.iter(), "exception");
    for t in &v.throws {
        check_name(errors, t, "exception");
    }
    if let Some(c) = s.codels.iter().find(|c| c.state.as_str() == VALIDATE) {
        errors.push(
            ModelError::new(
                format!("`{}` has a `validate` codel, and a codel state of that name", s.name),
                c.state.span,
            )
            .with_help("`validate` names the codel that checks a request (docs/genom.md, \"Codels at the request\"): rename the codel state"),
        );
    }
    out.validate = Some(v.throws.iter().map(|t| t.as_str()).collect());
}
