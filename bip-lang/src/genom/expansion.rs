//! `expand`: validation, rewriting of GenoM names and the expansion into core; compiling an
//! expansion with its engine map.

use super::build::Expansion;
use super::{build, check, origin, rewrite, timing};
use crate::compile::{compile_core, Constants};
use crate::diag::{Errors, ModelError};
use crate::syntax::{PropertyDef, SystemDef, Text};
use bip_model::System;
use build::UserTexts;
use check::ConstraintKind;
use origin::Origins;

/// Expands the GenoM layer of `def` into BIP core. The result has no `modules` or
/// `constraints`; a model without them comes back unchanged.
pub fn expand(def: &SystemDef) -> Result<Expansion, Vec<ModelError>> {
    let (consts, mut const_errors) = Constants::new(def);
    let layer = check::check(def, &consts).map_err(|mut e| {
        const_errors.append(&mut e);
        const_errors.clone()
    })?;
    let mut errors = Errors::default();
    for e in const_errors {
        errors.push(e);
    }
    let timing = timing::check(def, &layer, &consts, &mut errors);
    let mut rw = rewrite::Rewriter::new(&layer, &consts);
    let mut origins = Origins::default();
    let mut user = UserTexts::default();
    // each user text, rewritten if it names GenoM things, becomes a piece with its origin
    let mut expr = |errors: &mut Errors, origins: &mut Origins, t: &Text| {
        rw.expr(errors, t).ok().map(|r| origins.user(t, r))
    };
    for (k, c) in layer.constraints.iter().enumerate() {
        if let ConstraintKind::Guard { when, .. } = &c.kind {
            if let Some(src) = expr(&mut errors, &mut origins, when) {
                user.guards.insert(k, src);
            }
        }
    }
    for (k, c) in def.connectors.iter().enumerate() {
        if let Some(g) = &c.guard {
            if let Some(src) = expr(&mut errors, &mut origins, g) {
                user.connector_guards.insert(k, src);
            }
        }
    }
    for (k, p) in def.priorities.iter().enumerate() {
        if let Some(w) = &p.when {
            if let Some(src) = expr(&mut errors, &mut origins, w) {
                user.priority_whens.insert(k, src);
            }
        }
    }
    for (k, p) in def.properties.iter().enumerate() {
        let text = match p {
            PropertyDef::DeadlockFree { terminal } => terminal.as_ref(),
            PropertyDef::Invariant { expr, .. } | PropertyDef::Reachable { expr, .. } => Some(expr),
        };
        if let Some(t) = text {
            if let Some(src) = expr(&mut errors, &mut origins, t) {
                user.properties.insert(k, src);
            }
        }
    }
    for (k, c) in def.connectors.iter().enumerate() {
        if let Some(a) = &c.action {
            if let Ok(r) = rw.action(&mut errors, a) {
                user.connector_actions.insert(k, origins.user(a, r));
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
    let ages = std::mem::take(&mut rw.ages);
    let mut expansion = build::build(&layer, def, ages, user, origins)?;
    expansion.recipe.timing = timing;
    Ok(expansion)
}

impl Expansion {
    /// Compiles the expanded model into a [`System`] with its [`GenomMap`](bip_model::genom::map::GenomMap); `def` is the
    /// model it was expanded from. Errors point into the model's file (the expanded texts
    /// that hold user texts have spans of their own, which this maps back).
    pub fn compile(&self, def: &SystemDef) -> Result<System, Vec<ModelError>> {
        let texts = self.recipe.condition_texts();
        let (mut system, exprs) =
            compile_core(&self.def, &texts).map_err(|e| self.origins.locate_errors(e))?;
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
            p.text = match written {
                PropertyDef::DeadlockFree { terminal } => terminal
                    .as_ref()
                    .map(|t| t.value.clone())
                    .unwrap_or_default(),
                PropertyDef::Invariant { expr, .. } | PropertyDef::Reachable { expr, .. } => {
                    expr.value.clone()
                }
            };
        }
        system.genom = Some(map);
        Ok(system)
    }
}
