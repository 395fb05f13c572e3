//! Properties, and the global boolean expressions they (and priorities' `when`s, and the
//! GenoM layer's conditions) are written in.

use std::collections::HashMap;

use super::budgets::{show_us, written_duration};
use super::resolve::{Place, Resolver, Ty};
use super::{expr_error, Compiler};
use crate::diag::ModelError;
use crate::expr::{self};
use crate::source::{ConstExpr, Span};
use crate::syntax::{ExprDef, PropertyDef, SystemDef};
use bip_model::eval;
use bip_model::{Property, PropertyKind};

impl Compiler {
    pub(super) fn properties(&mut self, def: &SystemDef) -> Vec<Property> {
        let mut out = Vec::new();
        let mut seen: HashMap<String, Span> = HashMap::new();
        for p in &def.properties {
            let name_span = p.name_span();
            let name = p.name().into_owned();
            if let Some(&first) = seen.get(&name) {
                self.errors.push(
                    ModelError::new(format!("duplicate property `{name}`"), name_span)
                        .with_note(first, "first defined here"),
                );
                continue;
            }
            seen.insert(name.clone(), name_span);
            let kind = match p {
                PropertyDef::DeadlockFree { terminal } => match terminal {
                    None => PropertyKind::DeadlockFree { terminal: None },
                    Some(t) => match self.global_bool(t) {
                        Some(e) => PropertyKind::DeadlockFree { terminal: Some(e) },
                        None => continue,
                    },
                },
                PropertyDef::Invariant { expr, .. } => match self.global_bool(expr) {
                    Some(e) => PropertyKind::Invariant(e),
                    None => continue,
                },
                PropertyDef::Reachable { expr, .. } => match self.global_bool(expr) {
                    Some(e) => PropertyKind::Reachable(e),
                    None => continue,
                },
                PropertyDef::Response {
                    trigger,
                    response,
                    within,
                    ..
                } => {
                    let (t, r, k) = (
                        self.happens(trigger),
                        self.happens(response),
                        self.within(within),
                    );
                    let (Some(trigger), Some(response), Some(k)) = (t, r, k) else {
                        continue;
                    };
                    PropertyKind::Response {
                        trigger,
                        response,
                        within: Some(k),
                    }
                }
                PropertyDef::LeadsTo { from, to, .. } => {
                    let (Some(trigger), Some(response)) = (self.happens(from), self.happens(to))
                    else {
                        continue;
                    };
                    PropertyKind::Response {
                        trigger,
                        response,
                        within: None,
                    }
                }
                PropertyDef::Replies { service, .. } | PropertyDef::Terminates { service, .. } => {
                    self.errors.push(
                        ModelError::new(
                            format!("`{service}` names a GenoM service, but the model has no modules"),
                            service.span,
                        )
                        .with_help("`Replies` and `Terminates` are about the services of a GenoM layer; in BIP core, write `Response` or `LeadsTo`"),
                    );
                    continue;
                }
            };
            out.push(Property {
                name,
                kind,
                text: written_text(p),
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

/// A property's expressions as written, for reports.
pub(crate) fn written_text(p: &PropertyDef) -> String {
    match p {
        PropertyDef::DeadlockFree { terminal } => terminal
            .as_ref()
            .map(ExprDef::to_string)
            .unwrap_or_default(),
        PropertyDef::Invariant { expr, .. } | PropertyDef::Reachable { expr, .. } => {
            expr.to_string()
        }
        PropertyDef::Response {
            trigger,
            response,
            within,
            ..
        } => format!("{trigger} → {response} within {}", bound_text(within)),
        PropertyDef::LeadsTo { from, to, .. } => format!("{from} → {to} eventually"),
        PropertyDef::Replies {
            service, within, ..
        } => match within {
            Some(k) => format!(
                "every accepted request of {service} is replied to within {}",
                bound_text(k)
            ),
            None => format!("every accepted request of {service} is replied to"),
        },
        PropertyDef::Terminates { service, .. } => {
            format!("every started {service} ends")
        }
    }
}

/// A `within` for reports: a duration as written, else its number of ticks.
fn bound_text(k: &ConstExpr) -> String {
    match written_duration(k) {
        Some(Ok(us)) => show_us(us),
        _ => format!("{} ticks", k.value),
    }
}
