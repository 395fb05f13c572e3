//! The user's properties in the core's names, and the idle states of the layer that
//! `DeadlockFree` excuses when every request comes from the environment.

use std::collections::HashSet;

use super::{Builder, UserTexts};
use crate::genom::check::{ServiceRef, ETHER};
use crate::genom::names::*;
use crate::genom::tree::{all, and, at, boolean, member, not, or};
use crate::syntax::{ConnectorDef, ExprDef, PropertyDef, Role, Text};

impl<'a, 'd> Builder<'a, 'd> {
    /// The user's properties with GenoM names rewritten; `DeadlockFree` excuses the states
    /// where no activity has work outstanding, if every request comes from the environment
    /// (once a component of the model sends requests, it is responsible for the layer's
    /// progress, and an idle layer may be a supervisor stuck: the user says when it is not
    /// with `terminal`).
    pub(super) fn properties(
        &mut self,
        connectors: &[ConnectorDef],
        user: &UserTexts,
    ) -> Vec<PropertyDef> {
        let requests: HashSet<&str> = self
            .recipe
            .modules
            .iter()
            .flat_map(|m| m.services.iter().filter_map(|s| s.request.as_deref()))
            .collect();
        // a layer without services has no requests and nothing to do but let time pass:
        // it is idle for good, and excused, unless components of the model's own are
        // there to make progress
        let open = if requests.is_empty() {
            self.def.components.is_empty()
        } else {
            connectors
                .iter()
                .filter(|c| requests.contains(c.name.as_str()))
                .all(|c| c.role == Role::Environment)
        };
        // with no activity at all, nothing is ever outstanding; an aperiodic task's
        // activity that sleeps until an event of its module waits as an idle one waits
        // for a request
        let sleeping: HashSet<String> = (0..self.layer.modules.len())
            .flat_map(|mi| self.sleepers(mi).into_iter().map(move |k| (mi, k)))
            .map(|(module, service)| self.comp(ServiceRef { module, service }))
            .collect();
        let idle = open.then(|| {
            let activities = self
                .recipe
                .modules
                .iter()
                .flat_map(|m| m.services.iter())
                .filter_map(|s| s.component.as_deref());
            all(activities.map(|c| {
                let idle = and(at(c, ETHER), not(member(c, REQ)));
                match sleeping.contains(c) {
                    true => or(idle, member(c, PAUSED)),
                    false => idle,
                }
            }))
            .unwrap_or_else(|| boolean(true))
        });
        self.recipe.idle = idle.clone();
        let mut out = Vec::with_capacity(self.def.properties.len());
        for (k, p) in self.def.properties.iter().enumerate() {
            let rewritten = |written: &ExprDef| match user.properties.get(&k) {
                Some(u) => u.def(written),
                None => written.clone(),
            };
            out.push(match p {
                PropertyDef::DeadlockFree { terminal } => {
                    let user_terminal = user.properties.get(&k).map(|u| u.tree.clone());
                    let terminal = match (user_terminal, &idle) {
                        (Some(t), Some(idle)) => Some(ExprDef::Built(or(t, idle.clone()))),
                        (None, Some(idle)) => Some(ExprDef::Built(idle.clone())),
                        (_, None) => terminal.as_ref().map(rewritten),
                    };
                    PropertyDef::DeadlockFree { terminal }
                }
                PropertyDef::Invariant { name, expr } => PropertyDef::Invariant {
                    name: name.clone(),
                    expr: rewritten(expr),
                },
                PropertyDef::Reachable { name, expr } => PropertyDef::Reachable {
                    name: name.clone(),
                    expr: rewritten(expr),
                },
                PropertyDef::Response {
                    name,
                    trigger,
                    response,
                    within,
                } => {
                    let (t, r) = &user.responses[&k];
                    PropertyDef::Response {
                        name: name.clone(),
                        trigger: t.def(trigger),
                        response: r.def(response),
                        within: within.clone(),
                    }
                }
                PropertyDef::LeadsTo { name, from, to } => {
                    let (t, r) = &user.responses[&k];
                    PropertyDef::LeadsTo {
                        name: name.clone(),
                        from: t.def(from),
                        to: r.def(to),
                    }
                }
                PropertyDef::Replies { .. } | PropertyDef::Terminates { .. } => {
                    // named as written, so that the report keeps the user's name
                    let name = Text::new(p.name().into_owned(), p.name_span());
                    let (t, r) = &user.responses[&k];
                    let (from, to) = (
                        ExprDef::Built(t.tree.clone()),
                        ExprDef::Built(r.tree.clone()),
                    );
                    match p {
                        PropertyDef::Replies {
                            within: Some(k), ..
                        } => PropertyDef::Response {
                            name,
                            trigger: from,
                            response: to,
                            within: k.clone(),
                        },
                        _ => PropertyDef::LeadsTo { name, from, to },
                    }
                }
            });
        }
        if let Some(t) = self.timed {
            // a model without properties is checked for deadlocks, and the deadlines
            // generated beside them must not take that away
            if out.is_empty() {
                out.push(PropertyDef::DeadlockFree {
                    terminal: idle.map(ExprDef::Built),
                });
            }
            out.extend(self.deadline_invariants(t));
        }
        out
    }
}
