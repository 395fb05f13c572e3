//! The names codel parameters give, resolved as GenoM3 resolves them: `ids in x` names an
//! ids member, `local in x` a parameter or local of the service, `port out p` a port
//! (an out port to be written), `remote in r` a remote service of a used interface; a
//! name without its source names whichever of these has it, and is an error when none
//! or several do. `out ::ids` (no name) is the whole ids.

use super::ast::{Codel, CodelParam, Component, PortDir, Service, Source};
use crate::compile::one_of;
use crate::diag::{Errors, ModelError};

/// Checks the parameters of every codel of `c`: its services' (their state machines,
/// simple codels and `validate`) and its tasks'.
pub fn check(c: &Component, errors: &mut Errors) {
    for s in &c.services {
        let codels = s.codels.iter().chain(&s.simple).chain(&s.validate);
        for codel in codels {
            check_codel(c, Some(s), codel, errors);
        }
    }
    for t in &c.tasks {
        for codel in &t.codels {
            check_codel(c, None, codel, errors);
        }
    }
}

fn check_codel(c: &Component, s: Option<&Service>, codel: &Codel, errors: &mut Errors) {
    for p in &codel.params {
        if let Err(e) = resolve(c, s, codel, p) {
            errors.push(e);
        }
    }
}

/// The names a service's codels can read locally: its parameters and locals.
fn locals(s: Option<&Service>) -> Vec<&str> {
    s.map_or(Vec::new(), |s| {
        s.params
            .iter()
            .map(|p| p.local_name())
            .chain(s.locals.iter().map(|l| l.name.as_str()))
            .collect()
    })
}

fn resolve(
    c: &Component,
    s: Option<&Service>,
    codel: &Codel,
    p: &CodelParam,
) -> Result<(), ModelError> {
    let f = &codel.function;
    let Some(first) = p.path.first().map(String::as_str) else {
        return Ok(()); // `::ids`: the whole ids
    };
    let ids = || c.ids.iter().map(|m| m.name.as_str());
    let locals = locals(s);
    let port = c.ports.iter().find(|q| q.name.value == first);
    let is_ids = ids().any(|m| m == first);
    let is_local = locals.contains(&first);
    let is_remote = c.remotes.iter().any(|r| r.value == first);
    let source = match p.source {
        Some(src) => src,
        None => {
            let found: Vec<(&str, Source)> = [
                (is_ids, "an ids member", Source::Ids),
                (
                    is_local,
                    "a parameter or local of the service",
                    Source::Local,
                ),
                (port.is_some(), "a port", Source::Port),
                (is_remote, "a remote service", Source::Remote),
            ]
            .into_iter()
            .filter(|(yes, ..)| *yes)
            .map(|(_, what, src)| (what, src))
            .collect();
            match found.as_slice() {
                [(_, src)] => *src,
                [] => {
                    let known = ids()
                        .chain(locals.iter().copied())
                        .chain(c.ports.iter().map(|q| q.name.as_str()));
                    return Err(ModelError::new(
                        format!("codel `{}`: no ids member, parameter, local or port is named `{first}`", f),
                        p.name.span,
                    )
                    .with_label("unknown name")
                    .with_help(one_of("the names a codel can read here are", known)));
                }
                several => {
                    let whats: Vec<&str> = several.iter().map(|(w, _)| *w).collect();
                    return Err(ModelError::new(
                        format!("`{first}` is {}: say which with `ids`, `local` or `port` before the direction", whats.join(" and ")),
                        p.name.span,
                    )
                    .with_label("ambiguous name"));
                }
            }
        }
    };
    let missing = |what: &str, names: Vec<&str>| {
        ModelError::new(
            format!("codel `{}`: no {what} is named `{first}`", f),
            p.name.span,
        )
        .with_label("unknown name")
        .with_help(one_of(&format!("the {what}s are"), names.into_iter()))
    };
    match source {
        Source::Ids if !is_ids => Err(missing("ids member", ids().collect())),
        Source::Local if !is_local => Err(missing("parameter or local of the service", locals)),
        Source::Port => match port {
            None => Err(missing(
                "port",
                c.ports.iter().map(|q| q.name.as_str()).collect(),
            )),
            Some(q) if q.dir == PortDir::In && p.dir.writes() => Err(ModelError::new(
                format!("port `{first}` is an in port: a codel only reads it"),
                p.name.span,
            )
            .with_help(format!("pass it as `port in {first}`"))),
            Some(_) => Ok(()),
        },
        Source::Remote if !is_remote => Err(missing(
            "remote service",
            c.remotes.iter().map(|r| r.as_str()).collect(),
        )),
        _ => Ok(()),
    }
}
