//! Properties, and the global boolean expressions they (and priorities' `when`s, and the
//! GenoM layer's conditions) are written in.

use std::collections::HashMap;

use super::resolve::{Place, Resolver, Ty};
use super::{expr_error, Compiler};
use crate::diag::ModelError;
use crate::expr::{self};
use crate::source::Span;
use crate::syntax::{ExprDef, PropertyDef, SystemDef};
use bip_model::eval;
use bip_model::{Property, PropertyKind};

impl Compiler {
    pub(super) fn properties(&mut self, def: &SystemDef) -> Vec<Property> {
        let mut out = Vec::new();
        let mut seen: HashMap<String, Span> = HashMap::new();
        for p in &def.properties {
            let (name_span, text) = match p {
                PropertyDef::DeadlockFree { terminal } => (
                    terminal.as_ref().map_or(Span::NONE, ExprDef::span),
                    terminal.as_ref(),
                ),
                PropertyDef::Invariant { name, expr } | PropertyDef::Reachable { name, expr } => {
                    (name.span, Some(expr))
                }
            };
            let name = p.name().to_string();
            if let Some(&first) = seen.get(&name) {
                self.errors.push(
                    ModelError::new(format!("duplicate property `{name}`"), name_span)
                        .with_note(first, "first defined here"),
                );
                continue;
            }
            seen.insert(name.clone(), name_span);
            let compiled = match text {
                None => None,
                Some(t) => match self.global_bool(t) {
                    Some(e) => Some(e),
                    None => continue,
                },
            };
            let kind = match (p, compiled) {
                (PropertyDef::DeadlockFree { .. }, terminal) => {
                    PropertyKind::DeadlockFree { terminal }
                }
                (PropertyDef::Invariant { .. }, Some(e)) => PropertyKind::Invariant(e),
                (PropertyDef::Reachable { .. }, Some(e)) => PropertyKind::Reachable(e),
                _ => continue,
            };
            out.push(Property {
                name,
                kind,
                text: text.map(ExprDef::to_string).unwrap_or_default(),
            });
        }
        out
    }

    /// Parses and resolves a global boolean expression (property, priority condition).
    pub(super) fn global_bool(&mut self, t: &ExprDef) -> Option<eval::Expr> {
        match t.tree() {
            Ok(e) => self.global_bool_tree(&e),
            Err(e) => {
                self.errors.push(e);
                None
            }
        }
    }

    pub(super) fn global_bool_tree(&mut self, e: &expr::Expr) -> Option<eval::Expr> {
        let names = self.names();
        let mut r = Resolver::new(&names, Place::Global, &[]);
        match r.expect(e, Ty::Bool) {
            Ok(c) => Some(c),
            Err(e) => {
                self.errors.push(expr_error(e));
                None
            }
        }
    }
}
