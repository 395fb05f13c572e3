//! What a component takes from the interfaces it names (`provides`, `uses`, an interface's
//! `extends`), and a service declared again, which refines the first declaration, as
//! GenoM3 reopens it.

use super::ast::{Component, PortDir, Service};
use crate::diag::ModelError;
use crate::source::Text;

/// How a component takes in an interface's objects.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Merge {
    /// `provides` (and an interface's `extends`): every object as it is.
    Provides,
    Extends,
    /// `uses`: its ports with their direction reversed, its services as remote ones
    /// (which the model does not hold), its other objects as they are.
    Uses,
}

/// The objects of an interface, in the component where `provides`, `uses` or `extends` is
/// written: its ids members, ports, services, exceptions and types. A service the
/// component already has is refined by the interface's, as a declaration written again.
pub fn merge(comp: &mut Component, interface: &Component, how: Merge) -> Result<(), ModelError> {
    comp.ids.extend(interface.ids.iter().cloned());
    comp.ports.extend(interface.ports.iter().map(|p| {
        let mut p = p.clone();
        if how == Merge::Uses {
            p.dir = match p.dir {
                PortDir::In => PortDir::Out,
                PortDir::Out => PortDir::In,
            };
        }
        p
    }));
    if how == Merge::Uses {
        comp.remotes
            .extend(interface.services.iter().map(|s| s.name.clone()));
    } else {
        for s in &interface.services {
            match comp
                .services
                .iter_mut()
                .find(|o| o.name.value == s.name.value)
            {
                Some(first) => refine(first, s.clone())?,
                None => comp.services.push(s.clone()),
            }
        }
    }
    comp.exceptions.extend(interface.exceptions.iter().cloned());
    comp.types.extend(interface.types.iter().cloned());
    comp.provides.extend(interface.provides.iter().cloned());
    comp.remotes.extend(interface.remotes.iter().cloned());
    Ok(())
}

/// A service declared again (in the component that provides it, or twice in one
/// component), as GenoM3 reopens it: the same kind and the same parameters (direction,
/// type as written, name) in the same order; its documentation is appended, its `throw`
/// and `interrupts` lists joined, its locals and codels (one per function name) added;
/// any other property (`task`, `after`, `before`, `validate`) given twice is an error.
pub fn refine(first: &mut Service, again: Service) -> Result<(), ModelError> {
    let declared_here = |e: ModelError| {
        e.with_note(
            first.name.span,
            format!("`{}` is first declared here", first.name),
        )
    };
    if first.kind != again.kind {
        return Err(declared_here(ModelError::new(
            format!(
                "{} `{}` conflicts with its first declaration, a {}",
                again.kind.word(),
                again.name,
                first.kind.word()
            ),
            again.name.span,
        )));
    }
    for k in 0..first.params.len().max(again.params.len()) {
        let (a, b) = (first.params.get(k), again.params.get(k));
        let what = match (a, b) {
            (Some(a), Some(b))
                if a.dir == b.dir && a.ty == b.ty && a.name.value == b.name.value =>
            {
                continue
            }
            (Some(a), Some(b)) => (
                b.name.span,
                format!(
                    "parameter `{}` differs from its first declaration `{}`",
                    b.name, a.name
                ),
            ),
            (None, Some(b)) => (
                b.name.span,
                format!("parameter `{}` is not in the first declaration", b.name),
            ),
            (Some(a), None) => (
                again.name.span,
                format!("parameter `{}` of the first declaration is missing", a.name),
            ),
            (None, None) => continue,
        };
        return Err(declared_here(
            ModelError::new(what.1, what.0)
                .with_help("a service declared again repeats its parameters: the same directions, types and names, in order"),
        ));
    }
    let once = |a: &Option<Text>, b: &Option<Text>, what: &str| match (a, b) {
        (Some(_), Some(b)) => Err(declared_here(ModelError::new(
            format!("duplicate `{what}` of `{}`", first.name),
            b.span,
        ))),
        _ => Ok(()),
    };
    once(&first.task, &again.task, "task")?;
    let first_of = |l: &[Text]| l.first().cloned();
    once(&first_of(&first.after), &first_of(&again.after), "after")?;
    once(&first_of(&first.before), &first_of(&again.before), "before")?;
    once(
        &first.validate.as_ref().map(|v| v.function.clone()),
        &again.validate.as_ref().map(|v| v.function.clone()),
        "validate",
    )?;
    for codel in again.codels.iter().chain(&again.simple) {
        let f = &codel.function;
        if first
            .codels
            .iter()
            .chain(&first.simple)
            .any(|o| o.function.value == f.value)
        {
            return Err(declared_here(ModelError::new(
                format!("duplicate codel `{f}` of `{}`", first.name),
                f.span,
            )));
        }
    }
    let join = |a: &mut Vec<Text>, b: Vec<Text>| {
        for t in b {
            if !a.iter().any(|x| x.value == t.value) {
                a.push(t);
            }
        }
    };
    first.doc.extend(again.doc);
    first.task = first.task.take().or(again.task);
    join(&mut first.interrupts, again.interrupts);
    join(&mut first.throws, again.throws);
    first.after.extend(again.after);
    first.before.extend(again.before);
    first.validate = first.validate.take().or(again.validate);
    for l in again.locals {
        if !first.locals.iter().any(|x| x.name.value == l.name.value) {
            first.locals.push(l);
        }
    }
    first.codels.extend(again.codels);
    first.simple.extend(again.simple);
    Ok(())
}
