//! `expand`: validation, rewriting of GenoM names and the expansion into core; compiling an
//! expansion with its engine map.

use std::borrow::Cow;
use std::collections::BTreeMap;

use super::build::{Expansion, UserExpr, UserTexts};
use super::{build, check, events, machines, rewrite, timed, timing};
use crate::compile::{compile_core, written_text, Constants};
use crate::diag::{Errors, ModelError};
use crate::expr::{Assign, Expr};
use crate::syntax::{ActionDef, ExprDef, PropertyDef, SystemDef};
use bip_model::System;
use check::ConstraintKind;

/// Expands the GenoM layer of `def` into BIP core. The result has no `modules` or
/// `constraints`; a model without them comes back unchanged.
pub fn expand(def: &SystemDef) -> Result<Expansion, Vec<ModelError>> {
    expand_in(def, None)
}

/// [`expand`], knowing the text of the file `def` was read from (reports then give the
/// constraints' lines).
pub(crate) fn expand_in(def: &SystemDef, text: Option<&str>) -> Result<Expansion, Vec<ModelError>> {
    let with_machines = machines::as_activities(def);
    let def = &*with_machines;
    let (consts, mut const_errors) = Constants::new(def);
    let layer = check::check(def, &consts, text).map_err(|mut e| {
        const_errors.append(&mut e);
        const_errors.clone()
    })?;
    let mut errors = Errors::default();
    for e in const_errors {
        errors.push(e);
    }
    let timing = timing::check(def, &layer, &consts, &mut errors);
    let timed = timed::check(def, &layer, &consts, &timing, &mut errors);

    let mut rw = rewrite::Rewriter::new(&layer, &consts);
    let mut user = UserTexts::default();
    // each user text as a tree, rewritten if it names GenoM things
    let mut expr = |errors: &mut Errors, t: &ExprDef| -> Option<UserExpr<Expr>> {
        let rewritten = rw.expr(errors, t);
        user_tree(errors, rewritten, || t.tree())
    };
    for (k, c) in layer.constraints.iter().enumerate() {
        if let ConstraintKind::Guard { when, .. } = &c.kind {
            let when = ExprDef::Written((*when).clone());
            if let Some(u) = expr(&mut errors, &when) {
                user.guards.insert(k, u.tree);
            }
        }
    }
    for (k, c) in def.connectors.iter().enumerate() {
        if let Some(g) = &c.guard {
            if let Some(u) = expr(&mut errors, g) {
                user.connector_guards.insert(k, u);
            }
        }
    }
    for (k, p) in def.priorities.iter().enumerate() {
        if let Some(w) = &p.when {
            if let Some(u) = expr(&mut errors, w) {
                user.priority_whens.insert(k, u);
            }
        }
    }
    for (k, p) in def.properties.iter().enumerate() {
        let text = match p {
            PropertyDef::DeadlockFree { terminal } => terminal.as_ref(),
            PropertyDef::Invariant { expr, .. } | PropertyDef::Reachable { expr, .. } => Some(expr),
            PropertyDef::Response {
                trigger, response, ..
            } => {
                let t = happens(&layer, &mut errors, &mut expr, trigger);
                let r = happens(&layer, &mut errors, &mut expr, response);
                if let (Some(t), Some(r)) = (t, r) {
                    user.responses.insert(k, (t, r));
                }
                None
            }
            PropertyDef::LeadsTo { from, to, .. } => {
                let t = happens(&layer, &mut errors, &mut expr, from);
                let r = happens(&layer, &mut errors, &mut expr, to);
                if let (Some(t), Some(r)) = (t, r) {
                    user.responses.insert(k, (t, r));
                }
                None
            }
            PropertyDef::Replies { service, .. } | PropertyDef::Terminates { service, .. } => {
                let replies = matches!(p, PropertyDef::Replies { .. });
                if let Some(r) = check::service_ref(&mut errors, &layer, service) {
                    let s = &layer.modules[r.module].services[r.service];
                    if s.machine {
                        errors.push(
                            ModelError::new(format!("`{service}` is a task's machine"), service.span)
                                .with_help("nothing requests a task's machine, so it has no reply and no request to terminate; write a `Response` on its codels: `yield(m.t.s)`"),
                        );
                    } else if replies {
                        let (t, r) = events::replies(&layer, r, service.span);
                        user.responses.insert(k, (built(t), built(r)));
                    } else if s.is_activity() {
                        let (t, r) = events::terminates(&layer, r, service.span);
                        user.responses.insert(k, (built(t), built(r)));
                    } else {
                        errors.push(
                            ModelError::new(format!("`{service}` is not an activity"), service.span)
                                .with_help("`Terminates` is about activities; a function or attribute ends in the step that runs it"),
                        );
                    }
                }
                None
            }
        };
        if let Some(t) = text {
            if let Some(u) = expr(&mut errors, t) {
                user.properties.insert(k, u);
            }
        }
    }
    for (k, c) in def.connectors.iter().enumerate() {
        if let Some(a) = &c.action {
            if let Some(u) = action(&mut rw, &mut errors, a) {
                user.connector_actions.insert(k, u);
            }
        }
    }
    for c in &layer.constraints {
        if let ConstraintKind::Fresh { port, max_age, .. } = &c.kind {
            rw.note_age(*port, *max_age);
        }
    }
    if !errors.is_empty() {
        return Err(errors.list);
    }
    // an age saturates one above the largest constant it is compared with (each checked
    // to be below `i64::MAX`)
    let caps: BTreeMap<_, _> = std::mem::take(&mut rw.ages)
        .into_iter()
        .map(|(p, k)| (p, k.max(0) + 1))
        .collect();
    let mut expansion = build::build(&layer, def, caps, user, timed.as_ref())?;
    expansion.recipe.timing = timing;
    if let Some(t) = &timed {
        expansion.recipe.time_unit_us = Some(t.unit_us);
        expansion.recipe.cores = t
            .tasks
            .iter()
            .map(|m| m.iter().map(|task| task.core).collect())
            .collect();
    }
    Ok(expansion)
}

/// A trigger or a response: GenoM events as the core's step forms, or an expression
/// rewritten if it names GenoM things.
fn happens(
    layer: &check::Layer<'_>,
    errors: &mut Errors,
    expr: &mut impl FnMut(&mut Errors, &ExprDef) -> Option<UserExpr<Expr>>,
    t: &ExprDef,
) -> Option<UserExpr<Expr>> {
    let tree = match t.tree() {
        Ok(tree) => tree,
        Err(e) => {
            errors.push(e);
            return None;
        }
    };
    match events::event(layer, &tree) {
        Ok(Some(steps)) => Some(built(steps)),
        Ok(None) => expr(errors, t),
        Err(e) => {
            errors.push(e);
            None
        }
    }
}

/// A tree the expansion built, which the core holds as it is.
fn built(tree: Expr) -> UserExpr<Expr> {
    UserExpr {
        tree,
        rewritten: true,
    }
}

/// A user's action as a tree, rewritten if it names GenoM things.
fn action(
    rw: &mut rewrite::Rewriter<'_, '_>,
    errors: &mut Errors,
    a: &ActionDef,
) -> Option<UserExpr<Vec<Assign>>> {
    let rewritten = rw.action(errors, a);
    user_tree(errors, rewritten, || a.tree())
}

/// A user's expression or action as a tree: as the rewriter made it if it named GenoM
/// things, else as written (parsed only then). `None` once its error is reported.
fn user_tree<'a, T: ToOwned + ?Sized + 'a>(
    errors: &mut Errors,
    rewritten: Result<Option<T::Owned>, ()>,
    written: impl FnOnce() -> Result<Cow<'a, T>, ModelError>,
) -> Option<UserExpr<T::Owned>> {
    match rewritten {
        Ok(Some(tree)) => Some(UserExpr {
            tree,
            rewritten: true,
        }),
        Ok(None) => match written() {
            Ok(tree) => Some(UserExpr {
                tree: tree.into_owned(),
                rewritten: false,
            }),
            Err(e) => {
                errors.push(e);
                None
            }
        },
        Err(()) => None,
    }
}

impl Expansion {
    /// Compiles the expanded model into a [`System`] with its [`GenomMap`](bip_model::genom::map::GenomMap); `def` is the
    /// model it was expanded from. Errors point into the model's file: the user's
    /// subtrees in generated expressions kept their positions.
    pub fn compile(&self, def: &SystemDef) -> Result<System, Vec<ModelError>> {
        let conditions = self.recipe.conditions();
        let (mut system, exprs) =
            compile_core(&self.def, &conditions, self.recipe.time_unit_us).map_err(placed)?;
        let map = self.recipe.resolve(&system, exprs).map_err(|m| {
            vec![ModelError::new(
                format!(
                    "internal error: the expansion lost `{}` (please report)",
                    m.0
                ),
                crate::source::Span::NONE,
            )]
        })?;
        // reports show the properties as written, not as rewritten for the core
        for (p, written) in system.properties.iter_mut().zip(&def.properties) {
            p.text = written_text(written);
        }
        system.genom = Some(map);
        Ok(system)
    }
}

/// A user's expression inside generated ones (a `Guard` condition in every guard of its
/// service's codels and in their map) fails once per copy: each error is kept once. An
/// error with no place in the file fails only because of one that has a place, which is
/// kept alone.
fn placed(errors: Vec<ModelError>) -> Vec<ModelError> {
    let mut out: Vec<ModelError> = Vec::new();
    for e in errors {
        if !out.contains(&e) {
            out.push(e);
        }
    }
    if out.iter().any(|e| !e.span.is_none()) {
        out.retain(|e| !e.span.is_none());
    }
    out
}
