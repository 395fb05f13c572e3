//! The GenoM layer's response properties in the core's terms (docs/model.md, "Response
//! and liveness"): the events a user names in a trigger or a response, `request(m.S)`
//! (a request of `S` is accepted), `reply(m.S)` (a request of `S` gets its final reply),
//! `yield(m.S.c)` and `yield(m.S.c, t)` (codel `c` completes, yielding `t`), become the
//! core's step forms `fires(…)` and `changes(…, …)`; `Replies` and `Terminates` become a
//! trigger and a response.

use super::check::{Layer, Service, ServiceRef, Yield, ETHER, VALIDATE};
use super::names::{
    activity_component, codel_connector, fail_connector, request_connector, PAUSED, REQ,
};
use super::tree::{and, at, boolean, member, not, or};
use crate::compile::{disjuncts, one_of};
use crate::diag::ModelError;
use crate::expr::{Expr, ExprKind, Ident};
use crate::source::Span;

const EVENTS: [&str; 3] = ["request", "reply", "yield"];

/// The step form of a trigger or response written with GenoM events (one, or a `||` of
/// them); `None` if it names none.
pub(super) fn event(layer: &Layer<'_>, e: &Expr) -> Result<Option<Expr>, ModelError> {
    let alternatives = disjuncts(e);
    let events = alternatives.iter().filter(|x| is_event(x)).count();
    if events == 0 {
        return Ok(None);
    }
    if events < alternatives.len() {
        return Err(ModelError::new(
            "this mixes events and a state condition",
            e.span,
        )
        .with_help("a trigger or a response is either events (`request`, `reply`, `yield`) or a state condition"));
    }
    let mut out: Option<Expr> = None;
    for x in alternatives {
        let step = one_event(layer, x)?;
        out = Some(match out {
            None => step,
            Some(prev) => or(prev, step),
        });
    }
    Ok(out)
}

/// `Replies(m.S)`: the trigger (a request of `S` is accepted) and the response (`S` is at
/// rest: not running and no request outstanding; a function or attribute replies in the
/// step that accepts its request).
pub(super) fn replies(layer: &Layer<'_>, r: ServiceRef, span: Span) -> (Expr, Expr) {
    let module = &layer.modules[r.module];
    let s = &module.services[r.service];
    let request = placed(accepted(module.name, s), span);
    let response = if s.is_activity() {
        let c = activity_component(module.name, s.name);
        placed(and(at(&c, ETHER), not(member(&c, REQ))), span)
    } else {
        request.clone()
    };
    (request, response)
}

/// `Terminates(m.S)`: `S` is active, and then it is not.
pub(super) fn terminates(layer: &Layer<'_>, r: ServiceRef, span: Span) -> (Expr, Expr) {
    let module = &layer.modules[r.module];
    let c = activity_component(module.name, module.services[r.service].name);
    (
        placed(not(at(&c, ETHER)), span),
        placed(at(&c, ETHER), span),
    )
}

/// A task's machine has no request and no reply.
fn not_machine(m: &str, s: &Service<'_>, span: Span) -> Result<(), ModelError> {
    if s.machine {
        return Err(ModelError::new(
            format!(
                "`{m}.{}` is the machine of task `{}`: nothing requests it",
                s.name, s.name
            ),
            span,
        )
        .with_help(format!(
            "name its codels instead: `yield({m}.{}.start)`",
            s.name
        )));
    }
    Ok(())
}

fn one_event(layer: &Layer<'_>, e: &Expr) -> Result<Expr, ModelError> {
    let ExprKind::Call(f, args) = &e.kind else {
        unreachable!("one_event is called on events")
    };
    let wrong_args = || {
        ModelError::new(format!("`{}` takes a service, written `module.Service`", f.name), e.span)
            .with_help(match f.name.as_str() {
                "yield" => "e.g. `yield(ndd.GoTo.move)`, `yield(ndd.GoTo.move, ether)` or `yield(ndd.GoTo.move, pause(move))`",
                "request" => "e.g. `request(ndd.GoTo)`",
                _ => "e.g. `reply(ndd.GoTo)`",
            })
    };
    let step = match f.name.as_str() {
        "request" => {
            let [arg] = args.as_slice() else {
                return Err(wrong_args());
            };
            let (m, s) = service(layer, arg).ok_or_else(wrong_args)??;
            not_machine(m, s, arg.span)?;
            accepted(m, s)
        }
        "reply" => {
            let [arg] = args.as_slice() else {
                return Err(wrong_args());
            };
            let (m, s) = service(layer, arg).ok_or_else(wrong_args)??;
            not_machine(m, s, arg.span)?;
            if s.is_activity() {
                // an instance ends (from a codel state to `ether`), or a pending request
                // ends without running (interrupted, aborted, or a start that yields `ether`)
                let c = activity_component(m, s.name);
                let rest = and(at(&c, ETHER), not(member(&c, REQ)));
                or(
                    changes(not(at(&c, ETHER)), at(&c, ETHER)),
                    changes(and(at(&c, ETHER), member(&c, REQ)), rest),
                )
            } else {
                accepted(m, s)
            }
        }
        _ => {
            let (codel_arg, target) = match args.as_slice() {
                [c] => (c, None),
                [c, t] => (c, Some(t)),
                _ => return Err(wrong_args()),
            };
            let ExprKind::Member(base, codel) = &codel_arg.kind else {
                return Err(wrong_args());
            };
            let (m, s) = service(layer, base).ok_or_else(wrong_args)??;
            if let Some(step) = at_request(m, s, codel, target)? {
                return Ok(placed(step, e.span));
            }
            if !s.is_activity() {
                return Err(not_activity(m, s, base.span));
            }
            let Some(k) = s.codel(&codel.name) else {
                return Err(ModelError::new(
                    format!("activity `{m}.{}` has no codel `{}`", s.name, codel.name),
                    codel.span,
                )
                .with_help(one_of("its codels are", s.codels.iter().map(|c| c.state))));
            };
            let fired = fires(&codel_connector(m, s.name, &codel.name));
            match target {
                None => fired,
                Some(t) => {
                    let y = yield_target(s, k, t)?;
                    let c = activity_component(m, s.name);
                    let after = match y {
                        Yield::Ether => at(&c, ETHER),
                        Yield::Go(j) => and(at(&c, s.codels[j].state), not(member(&c, PAUSED))),
                        Yield::Pause(j) => and(at(&c, s.codels[j].state), member(&c, PAUSED)),
                    };
                    and(fired, changes(boolean(true), after))
                }
            }
        }
    };
    Ok(placed(step, e.span))
}

/// The yield `t` names (`ether`, `s`, `pause(s)`), if codel `k` of `s` has it.
fn yield_target(s: &Service<'_>, k: usize, t: &Expr) -> Result<Yield, ModelError> {
    let codel = &s.codels[k];
    let written = match &t.kind {
        ExprKind::Name(n) if n == ETHER => Some(Yield::Ether),
        ExprKind::Name(n) => s.codel(n).map(Yield::Go),
        ExprKind::Call(f, a) if f.name == "pause" => match a.as_slice() {
            [Expr {
                kind: ExprKind::Name(n),
                ..
            }] => s.codel(n).map(Yield::Pause),
            _ => None,
        },
        _ => None,
    };
    let show = |y: &Yield| match *y {
        Yield::Ether => ETHER.to_string(),
        Yield::Go(j) => s.codels[j].state.to_string(),
        Yield::Pause(j) => format!("pause({})", s.codels[j].state),
    };
    match written {
        Some(y) if codel.yields.contains(&y) => Ok(y),
        _ => Err(ModelError::new(
            format!(
                "codel `{}` of `{}` does not yield this",
                codel.state, s.name
            ),
            t.span,
        )
        .with_help(format!(
            "it yields {}",
            codel.yields.iter().map(show).collect::<Vec<_>>().join(", ")
        ))),
    }
}

/// `m.S` naming a service: its module's name and the service, or `None` if `e` is not
/// written `m.S`; an error if it names nothing.
fn service<'l, 'd>(
    layer: &'l Layer<'d>,
    e: &Expr,
) -> Option<Result<(&'d str, &'l Service<'d>), ModelError>> {
    let ExprKind::Member(base, field) = &e.kind else {
        return None;
    };
    let ExprKind::Name(m) = &base.kind else {
        return None;
    };
    let Some(module) = layer.modules.iter().find(|x| x.name == m) else {
        return Some(Err(ModelError::new(
            format!("unknown module `{m}`"),
            base.span,
        )
        .with_help(one_of(
            "the modules are",
            layer.modules.iter().map(|x| x.name),
        ))));
    };
    match module.services.iter().find(|s| s.name == field.name) {
        Some(s) => Some(Ok((module.name, s))),
        None => Some(Err(ModelError::new(
            format!("module `{m}` has no service `{}`", field.name),
            field.span,
        )
        .with_help(one_of(
            "its services are",
            module.services.iter().map(|s| s.name),
        )))),
    }
}

fn not_activity(m: &str, s: &Service<'_>, span: Span) -> ModelError {
    ModelError::new(format!("`{m}.{}` is not an activity", s.name), span).with_help(
        "a function or attribute has one codel, `start`, and a service may have a `validate` codel",
    )
}

/// A request of `m.s` is accepted: its step, or, when a function's codel fails, that
/// step (the request is accepted, its reply an exception).
fn accepted(m: &str, s: &Service<'_>) -> Expr {
    let request = fires(&request_connector(m, s.name));
    match &s.function {
        Some(c) => or(request, fires(&fail_connector(m, s.name, c.state))),
        None => request,
    }
}

/// `yield(m.S.validate)` (the request passed its validation) and `yield(m.F.start)`,
/// `yield(m.F.start, ether)` (a function's codel succeeded): the request's step; `None`
/// if `codel` is neither.
fn at_request(
    m: &str,
    s: &Service<'_>,
    codel: &Ident,
    target: Option<&Expr>,
) -> Result<Option<Expr>, ModelError> {
    let validates = s.validate.is_some() && codel.name == VALIDATE;
    let function = s.function.as_ref().is_some_and(|c| c.state == codel.name);
    if !validates && !function {
        return Ok(None);
    }
    match target {
        None => {}
        Some(t) if function && matches!(&t.kind, ExprKind::Name(n) if n == ETHER) => {}
        Some(t) => {
            return Err(ModelError::new(
                format!(
                    "codel `{}` of `{m}.{}` does not yield this",
                    codel.name, s.name
                ),
                t.span,
            )
            .with_help(if function {
                "a function's codel yields `ether`"
            } else {
                "a `validate` codel yields nothing: `yield(m.S.validate)` is its success"
            }))
        }
    }
    Ok(Some(fires(&request_connector(m, s.name))))
}

fn is_event(e: &Expr) -> bool {
    matches!(&e.kind, ExprKind::Call(f, _) if EVENTS.contains(&f.name.as_str()))
}

fn call(f: &str, args: Vec<Expr>) -> Expr {
    Expr::generated(ExprKind::Call(
        Ident {
            name: f.to_string(),
            span: Span::NONE,
        },
        args,
    ))
}

fn fires(connector: &str) -> Expr {
    call("fires", vec![super::tree::name(connector)])
}

fn changes(before: Expr, after: Expr) -> Expr {
    call("changes", vec![before, after])
}

/// `e` with the position of what the user wrote, so that errors in it point there.
fn placed(mut e: Expr, span: Span) -> Expr {
    e.span = span;
    e
}
