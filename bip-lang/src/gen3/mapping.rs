//! From a GenoM3 component to a module of bip's GenoM layer (docs/genom.md, "GenoM3
//! files"): what is modelled (tasks and their periods, out and in ports, services, their
//! interrupts, `after`, codel state machines with their yields, exceptions, the ports each
//! codel writes, the data types of ports and activities' parameters, `before`, task
//! `delay`s and codel WCETs; a task without a period is an aperiodic task). The rest is
//! kept in the component as information.

use std::collections::HashSet;

use super::ast::{Codel, Component, Kind, Port, PortDir, Service, Source, Spec, Task};
use super::params;
use super::types::Types;
use crate::diag::{Errors, ModelError};
use crate::genom::syntax::{
    CodelDef, ModuleDef, PortDef, ServiceDef, ServiceKind, TaskDef, ValidateDef,
};
use crate::source::{ConstExpr, ConstValue, Span, Spanned, Text};

/// The modules of a file's components; `tick_us` is the model's tick in microseconds.
pub fn modules(spec: &Spec, tick_us: u64) -> Result<Vec<ModuleDef>, Vec<ModelError>> {
    let mut errors = Errors::default();
    let declared: HashSet<String> = spec
        .types
        .iter()
        .chain(spec.components.iter().flat_map(|c| c.exceptions.iter()))
        .filter(|d| d.kind == "exception")
        .flat_map(|d| {
            let full = d.name.value.clone();
            let last = full.rsplit("::").next().unwrap_or(&full).to_string();
            [full, last]
        })
        .collect();
    let types = Types::new(spec);
    let out: Vec<ModuleDef> = spec
        .components
        .iter()
        .map(|c| module(c, tick_us, &declared, &types, &mut errors))
        .collect();
    if errors.is_empty() {
        Ok(out)
    } else {
        Err(errors.list)
    }
}

/// A task's `delay` in ticks: below its period (as GenoM3 requires), a whole number of
/// ticks.
fn delay(t: &Task, period: u64, tick_us: u64, errors: &mut Errors) -> Option<ConstExpr> {
    let (d, span) = t.delay?;
    if d >= period {
        errors.push(
            ModelError::new(
                format!("the delay of task `{}` is not less than its period", t.name),
                span,
            )
            .with_help("a delay offsets the task's period boundaries: it is below the period"),
        );
        return None;
    }
    if d % tick_us != 0 {
        errors.push(
            ModelError::new(
                format!(
                    "the delay of task `{}` ({d} µs) is not a whole number of ticks of {tick_us} µs",
                    t.name
                ),
                span,
            )
            .with_help("choose the model's `tick_ms` to divide every period and delay"),
        );
        return None;
    }
    let ticks = i64::try_from(d / tick_us).unwrap_or(i64::MAX);
    Some(Spanned {
        value: ConstValue::Int(ticks),
        span,
        verbatim: false,
    })
}

fn doc(lines: &[Text]) -> Option<Text> {
    let first = lines.first()?;
    let text: Vec<&str> = lines.iter().map(|t| t.value.as_str()).collect();
    Some(Text::new(text.join("\n"), first.span))
}

/// A task's period in ticks of `tick_us`; `None` (with an error at it) if it is not a
/// whole number of them.
fn period_ticks(
    t: &Task,
    period: u64,
    span: Span,
    tick_us: u64,
    errors: &mut Errors,
) -> Option<ConstExpr> {
    if !period.is_multiple_of(tick_us) {
        errors.push(
            ModelError::new(
                format!(
                    "the period of task `{}` ({period} µs) is not a whole number of ticks of {tick_us} µs",
                    t.name
                ),
                span,
            )
            .with_help("choose the model's `tick_ms` to divide every period"),
        );
        return None;
    }
    let ticks = i64::try_from(period / tick_us).unwrap_or(i64::MAX);
    Some(Spanned {
        value: ConstValue::Int(ticks),
        span,
        verbatim: false,
    })
}

fn module(
    c: &Component,
    tick_us: u64,
    exceptions: &HashSet<String>,
    types: &Types,
    errors: &mut Errors,
) -> ModuleDef {
    let tasks = c
        .tasks
        .iter()
        .filter_map(|t| {
            if let (None, Some((_, span))) = (t.period, t.delay) {
                errors.push(
                    ModelError::new(format!("task `{}` has a delay and no period", t.name), span)
                        .with_help(
                            "a delay offsets the period boundaries: give the task a `period`",
                        ),
                );
            }
            // without a period, the task is aperiodic: it runs its codels as soon as
            // they are ready (docs/genom.md, "Aperiodic tasks")
            let period = match t.period {
                None => None,
                Some((period, span)) => Some(period_ticks(t, period, span, tick_us, errors)?),
            };
            let delay = t.period.and_then(|(p, _)| delay(t, p, tick_us, errors));
            Some(TaskDef {
                name: t.name.clone(),
                period,
                delay,
                priority: None,
                cpu: None,
                deadline: None,
                core: None,
                doc: doc(&t.doc),
                codels: codel_defs(c, None, &t.codels, &throws(&t.throws, exceptions, errors)),
            })
        })
        .collect();
    let ports_of = |dir: PortDir| {
        c.ports
            .iter()
            .filter(|p| p.dir == dir)
            .map(|p| PortDef {
                name: p.name.clone(),
                doc: doc(&p.doc),
                ty: types.data_type(&p.ty, "", p.name.span),
            })
            .collect()
    };
    let ports = ports_of(PortDir::Out);
    let in_ports = ports_of(PortDir::In);
    params::check(c, errors);
    let services = c
        .services
        .iter()
        .map(|s| service(c, s, exceptions, types, errors))
        .collect();
    ModuleDef {
        name: c.name.clone(),
        doc: doc(&c.doc),
        ids: Vec::new(),
        tasks,
        ports,
        in_ports,
        services,
    }
}

fn service(
    c: &Component,
    s: &Service,
    exceptions: &HashSet<String>,
    types: &Types,
    errors: &mut Errors,
) -> ServiceDef {
    if s.name.value == ALL {
        errors.push(
            ModelError::new("`all` is a reserved service name", s.name.span)
                .with_help("`interrupts all` names every service of the component"),
        );
    }
    let throws = throws(&s.throws, exceptions, errors);
    let kind = match s.kind {
        Kind::Attribute => ServiceKind::Attribute,
        Kind::Function => ServiceKind::Function,
        Kind::Activity => ServiceKind::Activity,
    };
    let mut codels = codel_defs(c, Some(s), &s.codels, &throws);
    // a function's codel has no states: it runs at the request (`start`, yielding `ether`)
    if s.kind != Kind::Activity {
        codels.extend(s.simple.iter().map(|codel| {
            let at = |v: &str| Text::new(v.to_string(), codel.function.span);
            CodelDef {
                state: at("start"),
                yields: vec![at("ether")],
                throws: throws.clone(),
                writes: writes(c, Some(s), codel),
                uses: uses(c, Some(s), codel),
                wcet: budget(codel.wcet),
                bcet: budget(codel.bcet),
                asynchronous: codel.asynchronous,
            }
        }));
    }
    ServiceDef {
        name: s.name.clone(),
        kind,
        doc: doc(&s.doc),
        task: s.task.clone(),
        interrupts: all(c, s, &s.interrupts, true),
        after: all(c, s, &s.after, false),
        before: all(c, s, &s.before, false),
        codels,
        args: types.payload(c, s, false),
        output: types.payload(c, s, true),
        validate: s.validate.as_ref().map(|_| ValidateDef {
            throws: throws.clone(),
        }),
        machine: false,
    }
}

/// GenoM3's name for every service of the component in `interrupts`, `after`, `before`.
const ALL: &str = "all";

/// A list of services with `all` replaced by the services it names: for `interrupts`
/// every activity of the component, `s` itself included (functions and attributes end
/// at once and cannot be interrupted); for `after` and `before` every other service.
fn all(c: &Component, s: &Service, list: &[Text], interrupts: bool) -> Vec<Text> {
    let mut out: Vec<Text> = Vec::new();
    for t in list {
        if t.value != ALL {
            out.push(t.clone()); // a name written twice is reported by the module checks
            continue;
        }
        for o in &c.services {
            let named = if interrupts {
                o.kind == Kind::Activity
            } else {
                o.name.value != s.name.value
            };
            if named && !out.iter().any(|x| x.value == o.name.value) {
                out.push(Text::new(o.name.value.clone(), t.span));
            }
        }
    }
    out
}

/// The exceptions a service or a task throws (each checked declared), by their last name.
fn throws(throws: &[Text], exceptions: &HashSet<String>, errors: &mut Errors) -> Vec<Text> {
    for t in throws {
        let last = t.value.rsplit("::").next().unwrap_or(&t.value);
        if !exceptions.contains(&t.value) && !exceptions.contains(last) {
            errors.push(
                ModelError::new(format!("exception `{}` is not declared", t.value), t.span)
                    .with_help("declare it in the component: `exception name;`"),
            );
        }
    }
    throws
        .iter()
        .map(|t| Text {
            value: t.value.rsplit("::").next().unwrap_or(&t.value).to_string(),
            ..t.clone()
        })
        .collect()
}

/// The codel states of a service (`s`) or of a task's machine (`None`): one per state in
/// each codel's `<…>`, with its yields, the exceptions thrown and the ports it writes.
fn codel_defs(
    c: &Component,
    s: Option<&Service>,
    codels: &[Codel],
    throws: &[Text],
) -> Vec<CodelDef> {
    codels
        .iter()
        .flat_map(|codel| {
            let writes = writes(c, s, codel);
            let uses = uses(c, s, codel);
            let (bcet, wcet) = (budget(codel.bcet), budget(codel.wcet));
            codel.states.iter().map(move |state| CodelDef {
                state: state.clone(),
                yields: codel.yields.clone(),
                throws: throws.to_vec(),
                writes: writes.clone(),
                uses: uses.clone(),
                wcet: wcet.clone(),
                bcet: bcet.clone(),
                asynchronous: codel.asynchronous,
            })
        })
        .collect()
}

/// A codel's WCET or BCET, with its unit: a bare number below 100 µs reads as a slip for
/// milliseconds.
fn budget(micros: Option<(u64, Span)>) -> Option<ConstExpr> {
    micros.map(|(us, span)| Spanned {
        value: ConstValue::Expr(format!("{us}us")),
        span,
        verbatim: false,
    })
}

/// The out ports a codel writes: its `out` and `inout` parameters that name one (`port out
/// p`, or a plain `out p` that is not a parameter or local of its service `s`, nor an ids
/// member).
fn writes(c: &Component, s: Option<&Service>, codel: &Codel) -> Vec<Text> {
    let out_port = |name: &str| -> Option<&Port> {
        c.ports
            .iter()
            .find(|p| p.dir == PortDir::Out && p.name.value == name)
    };
    let shadowed = |name: &str| {
        s.is_some_and(|s| {
            s.params.iter().any(|p| p.name.value == name)
                || s.locals.iter().any(|l| l.name.value == name)
        }) || c.ids.iter().any(|m| m.name.value == name)
    };
    let mut out: Vec<Text> = Vec::new();
    for p in &codel.params {
        if !p.dir.writes() {
            continue;
        }
        let Some(first) = p.path.first() else {
            continue;
        };
        let is_port = match p.source {
            Some(Source::Port) => true,
            None => !shadowed(first),
            Some(_) => false,
        };
        if is_port && out_port(first).is_some() && !out.iter().any(|w| w.value == *first) {
            out.push(Text {
                value: first.clone(),
                ..p.name.clone()
            });
        }
    }
    out
}

/// The ids members and ports a codel reads or writes, by their first name (`ids in
/// a.b` is `a`), each once: the locks it takes in a timed model. `::ids`, the whole ids,
/// is every member; a service's parameters and locals are the codel's own.
fn uses(c: &Component, s: Option<&Service>, codel: &Codel) -> Vec<Text> {
    let local = |name: &str| {
        s.is_some_and(|s| {
            s.params.iter().any(|p| p.local_name() == name)
                || s.locals.iter().any(|l| l.name.value == name)
        })
    };
    let is_ids = |name: &str| c.ids.iter().any(|m| m.name.value == name);
    let is_port = |name: &str| c.ports.iter().any(|p| p.name.value == name);
    let mut out: Vec<Text> = Vec::new();
    let mut add = |name: &str, at: &Text| {
        if !out.iter().any(|u| u.value == name) {
            out.push(Text {
                value: name.to_string(),
                ..at.clone()
            });
        }
    };
    for p in &codel.params {
        let Some(first) = p.path.first() else {
            for m in &c.ids {
                add(&m.name.value, &p.name);
            }
            continue;
        };
        let used = match p.source {
            Some(Source::Ids) | Some(Source::Port) => true,
            Some(_) => false,
            None => !local(first) && (is_ids(first) || is_port(first)),
        };
        if used {
            add(first, &p.name);
        }
    }
    out
}
