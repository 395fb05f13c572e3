//! GenoM3's own declarations: `component` and `interface`, and what they export (their
//! properties, `ids`, `task`, `port`, `attribute`, `function`, `activity`, `provides`,
//! `uses`, and IDL declarations in their scope), with the properties of tasks and services
//! and the codels.

use super::ast::{
    Codel, CodelParam, Component, Dir, Kind, Param, Port, PortDir, Service, Source, Spec, Task,
};
use super::consts::Value;
use super::cursor::Cursor;
use super::idl::{Idl, DECLARATION_WORDS};
use super::interfaces::{merge, refine, Merge};
use super::lexer::Tok;
use crate::diag::ModelError;
use crate::source::{Span, Text};

/// GenoM3 constructs outside what bip reads, with why.
const UNSUPPORTED: &[(&str, &str)] = &[("template", "`template` declarations are not supported")];

/// A whole preprocessed file.
pub fn spec(c: &mut Cursor) -> Result<Spec, ModelError> {
    let mut idl = Idl::default();
    let mut spec = Spec::default();
    while let Some(t) = c.peek() {
        if t.is_ident("component") {
            let comp = component(c, &mut idl, &spec.interfaces)?;
            spec.components.push(comp);
        } else if t.is_ident("interface") {
            let interface = component(c, &mut idl, &spec.interfaces)?;
            if let Some(task) = interface.tasks.first() {
                return Err(ModelError::new(
                    format!("interface `{}` declares a task", interface.name),
                    task.name.span,
                )
                .with_help(
                    "an interface has no tasks: declare them in the components that provide it",
                ));
            }
            spec.interfaces.push(interface);
        } else if let Some(e) = unsupported(c) {
            return Err(e);
        } else if t.ident().is_some_and(|w| DECLARATION_WORDS.contains(&w)) {
            idl.declaration(c)?;
        } else {
            return Err(c.expected("`component` or an IDL declaration"));
        }
    }
    spec.types = std::mem::take(&mut idl.decls);
    Ok(spec)
}

/// The error for a construct bip does not read, if the next token starts one.
fn unsupported(c: &Cursor) -> Option<ModelError> {
    let t = c.peek()?;
    let (word, why) = UNSUPPORTED.iter().find(|(w, _)| t.is_ident(w))?;
    Some(ModelError::new(format!("`{word}` is not supported"), t.span).with_help(*why))
}

/// A `component` or an `interface` (the same declarations, an interface without tasks).
fn component(
    c: &mut Cursor,
    idl: &mut Idl,
    interfaces: &[Component],
) -> Result<Component, ModelError> {
    c.next();
    let name = c.expect_name("the component's name")?;
    let mut comp = Component {
        name,
        ..Component::default()
    };
    if c.eat_punct(";").is_some() {
        return Ok(comp);
    }
    c.expect_punct("{")?;
    idl.component = Some(comp.name.value.clone());
    let decls_before = idl.decls.len();
    while !c.at_punct("}") {
        if c.at_end() {
            return Err(c.expected("`}` closing the component"));
        }
        export(c, idl, interfaces, &mut comp)?;
    }
    c.expect_punct("}")?;
    c.expect_punct(";")?;
    idl.component = None;
    for d in idl.decls.drain(decls_before..) {
        if d.kind == "exception" {
            comp.exceptions.push(d);
        } else {
            comp.types.push(d);
        }
    }
    Ok(comp)
}

fn export(
    c: &mut Cursor,
    idl: &mut Idl,
    interfaces: &[Component],
    comp: &mut Component,
) -> Result<(), ModelError> {
    if let Some(e) = unsupported(c) {
        return Err(e);
    }
    let Some(word) = c.peek().and_then(|t| t.ident().map(str::to_string)) else {
        return Err(c.expected("a component property or declaration"));
    };
    match word.as_str() {
        "doc" => {
            c.next();
            comp.doc.push(c.expect_strings()?);
        }
        "version" | "lang" | "email" => {
            c.next();
            let s = c.expect_strings()?;
            let slot = match word.as_str() {
                "version" => &mut comp.version,
                "lang" => &mut comp.lang,
                _ => &mut comp.email,
            };
            *slot = Some(s);
        }
        "require" | "requires" | "codels-require" | "codels-requires" => {
            c.next();
            let list = c.list(Cursor::expect_strings)?;
            if word.starts_with("require") {
                comp.require.extend(list);
            } else {
                comp.codels_require.extend(list);
            }
        }
        "provide" | "provides" | "use" | "uses" | "extend" | "extends" => {
            c.next();
            let how = match word.as_str() {
                "use" | "uses" => Merge::Uses,
                "extend" | "extends" => Merge::Extends,
                _ => Merge::Provides,
            };
            for name in c.list(|c| c.scoped_name("an interface's name"))? {
                let Some(interface) = interfaces.iter().find(|i| i.name.value == name.value) else {
                    let known: Vec<&str> = interfaces.iter().map(|i| i.name.as_str()).collect();
                    let help = if known.is_empty() {
                        "declare it (`interface name { ... };`) before the component, or include the file that does".to_string()
                    } else {
                        format!("the interfaces declared before are: {}", known.join(", "))
                    };
                    return Err(ModelError::new(
                        format!("interface `{}` is not declared", name.value),
                        name.span,
                    )
                    .with_help(help));
                };
                merge(comp, interface, how)?;
                match how {
                    Merge::Uses => comp.uses.push(name),
                    _ => comp.provides.push(name),
                }
            }
        }
        "clock-rate" => {
            c.next();
            comp.clock_rate = Some(duration(c, idl)?);
        }
        "ids" => {
            c.next();
            let members = idl.ids_members(c)?;
            comp.ids.extend(members);
        }
        "task" => {
            c.next();
            comp.tasks.push(task(c, idl)?);
            return Ok(());
        }
        "port" => {
            c.next();
            comp.ports.push(port(c, idl)?);
            return Ok(());
        }
        "attribute" | "function" | "activity" => {
            c.next();
            let s = service(c, idl, &word)?;
            match comp
                .services
                .iter_mut()
                .find(|o| o.name.value == s.name.value)
            {
                Some(first) => refine(first, s)?,
                None => comp.services.push(s),
            }
            return Ok(());
        }
        w if DECLARATION_WORDS.contains(&w) => {
            idl.declaration(c)?;
            return Ok(());
        }
        _ => return Err(c.expected("a component property or declaration")),
    }
    c.expect_punct(";")?;
    Ok(())
}

/// `50 ms`, `1 s`, `500 us`, `0.1` (seconds): a duration in whole microseconds, positive
/// (a period, a clock rate, a WCET).
fn duration(c: &mut Cursor, idl: &Idl) -> Result<(u64, Span), ModelError> {
    some_duration(c, idl, true)
}

/// A duration that may be zero (a task's `delay`).
fn any_duration(c: &mut Cursor, idl: &Idl) -> Result<(u64, Span), ModelError> {
    some_duration(c, idl, false)
}

fn some_duration(c: &mut Cursor, idl: &Idl, positive: bool) -> Result<(u64, Span), ModelError> {
    let (v, span) = idl.expression(c)?;
    let scale = if c.eat_ident("ms").is_some() {
        1e3
    } else if c.eat_ident("us").is_some() {
        1.0
    } else {
        c.eat_ident("s");
        1e6
    };
    let span = Span::new(span.start, c.last_span().end);
    let us = match v {
        Value::Int(i) => (i as f64) * scale,
        Value::Float(f) => f * scale,
    };
    let least = if positive { 1.0 } else { 0.0 };
    if !(us.is_finite() && us >= least && us.fract() == 0.0 && us <= 1e15) {
        let what = if positive { "positive" } else { "zero or more" };
        return Err(ModelError::new(
            format!("a duration is {what} and a whole number of microseconds"),
            span,
        ));
    }
    Ok((us as u64, span))
}

fn task(c: &mut Cursor, idl: &mut Idl) -> Result<Task, ModelError> {
    let name = c.expect_name("the task's name")?;
    let mut t = Task {
        name,
        ..Task::default()
    };
    if c.eat_punct("{").is_some() {
        while !c.at_punct("}") {
            let Some(word) = c.peek().and_then(|t| t.ident().map(str::to_string)) else {
                return Err(c.expected("a task property"));
            };
            match word.as_str() {
                "doc" => {
                    c.next();
                    t.doc.push(c.expect_strings()?);
                }
                "period" => {
                    c.next();
                    t.period = Some(duration(c, idl)?);
                }
                "delay" => {
                    c.next();
                    t.delay = Some(any_duration(c, idl)?);
                }
                "priority" => {
                    c.next();
                    t.priority = Some(idl.positive_int(c)?);
                }
                "stack" => {
                    c.next();
                    let (n, span) = idl.positive_int(c)?;
                    let unit = if c.eat_ident("k").is_some() {
                        1024
                    } else if c.eat_ident("M").is_some() {
                        1024 * 1024
                    } else {
                        1
                    };
                    t.stack = Some((n.saturating_mul(unit), span));
                }
                "scheduling" => {
                    c.next();
                    if c.eat_ident("real-time").is_none() {
                        return Err(c.expected("`real-time`"));
                    }
                    t.real_time = true;
                }
                "throw" | "throws" => {
                    c.next();
                    t.throws.extend(c.list(|c| c.scoped_name("an exception"))?);
                }
                "codel" | "async" => {
                    let codel = codel(c, idl, true)?;
                    t.codels.push(codel);
                    continue;
                }
                _ => return Err(c.expected("a task property (period, delay, priority, stack, scheduling, codel, throw, doc)")),
            }
            c.expect_punct(";")?;
        }
        c.expect_punct("}")?;
    }
    c.expect_punct(";")?;
    Ok(t)
}

fn port(c: &mut Cursor, idl: &mut Idl) -> Result<Port, ModelError> {
    let multiple = c.eat_ident("multiple").is_some();
    let dir = if c.eat_ident("in").is_some() {
        PortDir::In
    } else if c.eat_ident("out").is_some() {
        PortDir::Out
    } else {
        return Err(c.expected("`in` or `out`"));
    };
    let ty = idl.type_spec(c, 0)?;
    let name = c.expect_name("the port's name")?;
    let mut doc = Vec::new();
    if c.eat_punct("{").is_some() {
        while c.eat_ident("doc").is_some() {
            doc.push(c.expect_strings()?);
            c.expect_punct(";")?;
        }
        if !c.at_punct("}") {
            return Err(c.expected("`doc` or `}` (a port has only documentation)"));
        }
        c.next();
    }
    c.expect_punct(";")?;
    Ok(Port {
        name,
        dir,
        multiple,
        ty,
        doc,
    })
}

fn direction(c: &mut Cursor) -> Result<Dir, ModelError> {
    if c.eat_ident("in").is_some() {
        Ok(Dir::In)
    } else if c.eat_ident("out").is_some() {
        Ok(Dir::Out)
    } else if c.eat_ident("inout").is_some() {
        Ok(Dir::InOut)
    } else {
        Err(c.expected("`in`, `out` or `inout`"))
    }
}

fn service(c: &mut Cursor, idl: &mut Idl, word: &str) -> Result<Service, ModelError> {
    let kind = match word {
        "attribute" => Kind::Attribute,
        "function" => Kind::Function,
        _ => Kind::Activity,
    };
    let name = c.expect_name(&format!("the {word}'s name"))?;
    c.expect_punct("(")?;
    let mut params = Vec::new();
    if !c.at_punct(")") {
        params = c.list(|c| parameter(c, idl, kind))?;
    }
    c.expect_punct(")")?;
    let mut s = Service {
        name,
        kind,
        params,
        doc: Vec::new(),
        task: None,
        interrupts: Vec::new(),
        after: Vec::new(),
        before: Vec::new(),
        validate: None,
        locals: Vec::new(),
        throws: Vec::new(),
        codels: Vec::new(),
        simple: Vec::new(),
    };
    if c.eat_punct("{").is_some() {
        while !c.at_punct("}") {
            let Some(word) = c.peek().and_then(|t| t.ident().map(str::to_string)) else {
                return Err(c.expected("a service property"));
            };
            match word.as_str() {
                "doc" => {
                    c.next();
                    s.doc.push(c.expect_strings()?);
                }
                "task" => {
                    c.next();
                    s.task = Some(c.expect_name("a task name")?);
                }
                "interrupt" | "interrupts" => {
                    c.next();
                    s.interrupts.extend(c.list(|c| c.expect_name("a service name"))?);
                }
                "after" => {
                    c.next();
                    s.after.extend(c.list(|c| c.expect_name("a service name"))?);
                }
                "before" => {
                    c.next();
                    s.before.extend(c.list(|c| c.expect_name("a service name"))?);
                }
                "validate" => {
                    c.next();
                    let mut v = simple_codel(c, false)?;
                    (v.bcet, v.wcet) = budgets(c, idl)?;
                    s.validate = Some(v);
                }
                "local" => {
                    c.next();
                    s.locals.extend(idl.member(c, 0)?);
                    continue;
                }
                "throw" | "throws" => {
                    c.next();
                    s.throws.extend(c.list(|c| c.scoped_name("an exception"))?);
                }
                "codel" | "async" => {
                    let codel = codel(c, idl, kind == Kind::Activity)?;
                    if codel.states.is_empty() {
                        s.simple.push(codel);
                    } else {
                        s.codels.push(codel);
                    }
                    continue;
                }
                _ => return Err(c.expected("a service property (doc, task, codel, throw, interrupt, after, before, validate, local)")),
            }
            c.expect_punct(";")?;
        }
        c.expect_punct("}")?;
    }
    c.expect_punct(";")?;
    Ok(s)
}

/// `in double x = 0 : "doc"`; for an attribute, `in ids.member = 0 : "doc"`.
fn parameter(c: &mut Cursor, idl: &mut Idl, kind: Kind) -> Result<Param, ModelError> {
    let dir = direction(c)?;
    let (name, ty) = if kind == Kind::Attribute {
        let (path, name) = variable(c)?;
        (Text::new(path.join("."), name.span), None)
    } else {
        let ty = idl.type_spec(c, 0)?;
        let (name, dims) = idl.declarator(c)?;
        (name, Some(format!("{ty}{dims}")))
    };
    let init = if c.eat_punct("=").is_some() {
        let start = c.here();
        initializer(c, idl, 0)?;
        Some(Span::new(start.start, c.last_span().end))
    } else {
        None
    };
    Ok(Param {
        dir,
        name,
        ty,
        init,
    })
}

/// A default value with its documentation: `0.5 : "doc"`, `: "doc"`, `{ .a = 1, [2] = 3 }`.
fn initializer(c: &mut Cursor, idl: &Idl, depth: usize) -> Result<(), ModelError> {
    if depth > 64 {
        return Err(ModelError::new("initializers nested too deeply", c.here()));
    }
    if c.eat_punct(":").is_some() {
        c.expect_strings()?;
        return Ok(());
    }
    if c.eat_punct("{").is_some() {
        if !c.at_punct("}") {
            c.list(|c| initializer(c, idl, depth + 1))?;
        }
        c.expect_punct("}")?;
    } else if c.eat_punct(".").is_some() || c.at_punct("[") {
        if c.eat_punct("[").is_some() {
            idl.positive_int(c)?;
            c.expect_punct("]")?;
        } else {
            c.expect_name("a member name")?;
        }
        c.expect_punct("=")?;
        if !c.at_punct(":") && !c.at_punct(",") && !c.at_punct("}") {
            initializer(c, idl, depth + 1)?;
            return Ok(());
        }
    } else {
        match c.peek().map(|t| &t.tok) {
            Some(Tok::Str(_)) => {
                c.expect_strings()?;
            }
            Some(Tok::Char(_)) => {
                c.next();
            }
            _ => {
                idl.expression(c)?;
            }
        }
    }
    if c.eat_punct(":").is_some() {
        c.expect_strings()?;
    }
    Ok(())
}

/// `a.b[2]`: the path and the first name.
fn variable(c: &mut Cursor) -> Result<(Vec<String>, Text), ModelError> {
    let first = c.expect_name("a variable")?;
    let mut path = vec![first.value.clone()];
    loop {
        if c.eat_punct(".").is_some() {
            path.push(c.expect_name("a member name")?.value);
        } else if c.eat_punct("[").is_some() {
            let n = match c.next() {
                Some(t) if matches!(t.tok, Tok::Int(_)) => t,
                _ => return Err(c.expected("an index")),
            };
            c.expect_punct("]")?;
            if let Tok::Int(i) = n.tok {
                path.push(format!("[{i}]"));
            }
        } else {
            return Ok((path, first));
        }
    }
}

/// `[async] codel <states> f(params) yield events;` or `[async] codel f(params);`. With
/// `fsm` false, states are not allowed.
fn codel(c: &mut Cursor, idl: &Idl, fsm: bool) -> Result<Codel, ModelError> {
    let asynchronous = c.eat_ident("async").is_some();
    let kw = c.here();
    if c.eat_ident("codel").is_none() {
        return Err(c.expected("`codel`"));
    }
    let mut states = Vec::new();
    if c.eat_punct("<").is_some() {
        states = c.list(|c| c.expect_name("a codel state"))?;
        c.expect_close_angle()?;
        if !fsm {
            return Err(ModelError::new(
                "a function's codel has no states",
                Span::new(kw.start, c.last_span().end),
            )
            .with_help("codels with states (`codel<start> …`) belong to activities and tasks"));
        }
    }
    let mut codel = simple_codel(c, asynchronous)?;
    codel.states = states;
    if !codel.states.is_empty() {
        if c.eat_ident("yield")
            .or_else(|| c.eat_ident("yields"))
            .is_none()
        {
            return Err(c.expected("`yield` and the codel's next states"));
        }
        codel.yields = c.list(event)?;
    } else if fsm && (c.at_ident("yield") || c.at_ident("yields")) {
        return Err(ModelError::new(
            "a codel that yields needs its states: `codel<state> f() yield …`",
            c.here(),
        ));
    }
    (codel.bcet, codel.wcet) = budgets(c, idl)?;
    c.expect_punct(";")?;
    Ok(codel)
}

/// The timed dialect's `wcet 10 ms` after a codel, its worst-case execution time, and
/// bip's `bcet 8 ms`, its best-case one, each at most once and in either order: (bcet,
/// wcet).
type Budgets = (Option<(u64, Span)>, Option<(u64, Span)>);
fn budgets(c: &mut Cursor, idl: &Idl) -> Result<Budgets, ModelError> {
    let (mut bcet, mut wcet) = (None, None);
    loop {
        let slot = if wcet.is_none() && c.eat_ident("wcet").is_some() {
            &mut wcet
        } else if bcet.is_none() && c.eat_ident("bcet").is_some() {
            &mut bcet
        } else {
            return Ok((bcet, wcet));
        };
        *slot = Some(duration(c, idl)?);
    }
}

/// `s` or `pause::s`, as one name.
fn event(c: &mut Cursor) -> Result<Text, ModelError> {
    if c.at_ident("pause") && c.peek_at(1).is_some_and(|t| t.is_punct("::")) {
        let start = c.here();
        c.next();
        c.next();
        let s = c.expect_name("a state after `pause::`")?;
        return Ok(Text::new(
            format!("pause::{}", s.value),
            Span::new(start.start, s.span.end),
        ));
    }
    c.expect_name("a codel state, `pause::state` or `ether`")
}

/// `f(in a, out port::p, inout ::ids)` after `codel` and its states.
fn simple_codel(c: &mut Cursor, asynchronous: bool) -> Result<Codel, ModelError> {
    let function = c.expect_name("the codel's function name")?;
    c.expect_punct("(")?;
    let mut params = Vec::new();
    if !c.at_punct(")") {
        params = c.list(codel_param)?;
    }
    c.expect_punct(")")?;
    Ok(Codel {
        states: Vec::new(),
        function,
        params,
        yields: Vec::new(),
        asynchronous,
        wcet: None,
        bcet: None,
    })
}

fn codel_param(c: &mut Cursor) -> Result<CodelParam, ModelError> {
    let source = [
        ("ids", Source::Ids),
        ("local", Source::Local),
        ("port", Source::Port),
        ("remote", Source::Remote),
    ]
    .into_iter()
    .find(|(w, _)| {
        c.at_ident(w)
            && c.peek_at(1)
                .is_some_and(|t| t.is_ident("in") || t.is_ident("out") || t.is_ident("inout"))
    })
    .map(|(_, s)| {
        c.next();
        s
    });
    let dir = direction(c)?;
    if c.eat_punct("::").is_some() {
        let name = c.expect_name("a name after `::`")?;
        return Ok(CodelParam {
            source,
            dir,
            path: Vec::new(),
            name,
        });
    }
    let (path, name) = variable(c)?;
    if c.eat_punct("::").is_some() {
        c.expect_name("the parameter's name in the codel")?;
    }
    Ok(CodelParam {
        source,
        dir,
        path,
        name,
    })
}
