//! The core model assembled: user names checked against the generated ones, generated
//! connectors extended by the user connectors named like them, the other user connectors
//! kept off the generated ports (but an activity's `abort`), then priorities and
//! properties.

use std::collections::{HashMap, HashSet};

use super::{Builder, Cond, Expansion, UserTexts};
use crate::compile::one_of;
use crate::diag::ModelError;
use crate::expr::{Assign, Expr, ExprKind};
use crate::genom::names::*;
use crate::genom::recipe::{RecipeCondition, RecipeService};
use crate::genom::tree::and;
use crate::syntax::{ActionDef, ConnectorDef, ConnectorKindDef, CpuDef, ExprDef, Role, SystemDef};
use bip_model::genom::map::Reason;

impl<'a, 'd> Builder<'a, 'd> {
    /// Assembles the core model: user atoms and components, generated ones, generated
    /// connectors extended by user connectors of the same name, the other user connectors,
    /// priorities and properties.
    pub(super) fn finish(&mut self, user: UserTexts) -> Expansion {
        let def = self.def;
        // user names may not clash with generated ones
        for (name, _) in def.atoms.iter() {
            if let Some((span, what)) = self.names.get(name.as_str()) {
                self.errors.push(
                    ModelError::new(
                        format!("atom `{name}` has the name generated for {what}"),
                        name.span,
                    )
                    .with_note(*span, "generated for this")
                    .with_help("rename the atom (docs/genom.md lists the generated names)"),
                );
            }
        }
        for c in &def.components {
            if let Some((span, what)) = self.names.get(c.name.as_str()) {
                self.errors.push(
                    ModelError::new(
                        format!("component `{}` has the name generated for {what}", c.name),
                        c.name.span,
                    )
                    .with_note(*span, "generated for this")
                    .with_help("rename the component (docs/genom.md lists the generated names)"),
                );
            }
        }
        let generated_components: HashSet<String> = self
            .components
            .iter()
            .map(|c| c.name.value.clone())
            .collect();
        // user connectors: extensions of generated ones, or their own
        let mut by_name: HashMap<&str, usize> = HashMap::new();
        for (k, c) in def.connectors.iter().enumerate() {
            by_name.entry(c.name.as_str()).or_insert(k);
        }
        // a request's other outcomes (its function's codel fails, its `validate` codel
        // refuses it) are extended as the request is: whoever sends it takes part
        let outcomes: HashMap<String, String> = self
            .recipe
            .modules
            .iter()
            .flat_map(|m| &m.services)
            .flat_map(|s| {
                let request = s.request.clone();
                s.function
                    .iter()
                    .chain(&s.validate)
                    .filter_map(move |c| Some((c.fail.clone(), request.clone()?)))
            })
            .collect();
        let mut extended = HashSet::new();
        let mut generated = std::mem::take(&mut self.connectors);
        for (g, guard, action) in &mut generated {
            let request = outcomes
                .get(g.name.as_str())
                .map_or(g.name.as_str(), |r| r.as_str());
            let Some(&k) = by_name.get(request) else {
                continue;
            };
            extended.insert(k);
            self.extend(g, guard, action, &def.connectors[k], k, &user);
        }
        let mut connectors = Vec::with_capacity(generated.len() + def.connectors.len());
        for (mut g, guard, action) in generated {
            g.guard = guard.map(ExprDef::Built);
            g.action = (!action.is_empty()).then_some(ActionDef::Built(action));
            connectors.push(g);
        }
        for (k, c) in def.connectors.iter().enumerate() {
            if extended.contains(&k) {
                continue;
            }
            self.check_user_ports(c, &generated_components);
            let mut c = c.clone();
            if let (Some(u), Some(written)) = (user.connector_guards.get(&k), &c.guard) {
                c.guard = Some(u.def(written));
            }
            if let (Some(u), Some(written)) = (user.connector_actions.get(&k), &c.action) {
                c.action = Some(u.def(written));
            }
            connectors.push(c);
        }
        let priorities = self.priorities(&user);
        let properties = self.properties(&connectors, &user);
        // record the tick
        self.recipe.tick = TICK.to_string();
        let mut atoms = def.atoms.clone();
        for (n, a) in std::mem::take(&mut self.atoms) {
            atoms.push(n, a);
        }
        let mut components = def.components.clone();
        components.extend(std::mem::take(&mut self.components));
        Expansion {
            def: SystemDef {
                name: def.name.clone(),
                tick_ms: def.tick_ms.clone(),
                // a timed layer's time is in the generated atoms now
                time: None,
                // the atoms' tasks are placed on them; their cores and scheduling are the
                // timed layer's, expanded
                cpus: def
                    .cpus
                    .iter()
                    .map(|c| CpuDef::named(c.name.clone()))
                    .collect(),
                constants: def.constants.clone(),
                atoms,
                components,
                connectors,
                priorities,
                modules: Vec::new(),
                connections: Vec::new(),
                constraints: Vec::new(),
                sources: def.sources.clone(),
                properties,
            },
            recipe: std::mem::take(&mut self.recipe),
        }
    }

    /// Merges user connector `u` (index `k`) into generated connector `g`: its ports join,
    /// its guard is conjoined, its action runs after the generated one.
    fn extend(
        &mut self,
        g: &mut ConnectorDef,
        guard: &mut Option<Expr>,
        action: &mut Vec<Assign>,
        u: &ConnectorDef,
        k: usize,
        user: &UserTexts,
    ) {
        let is_tick = g.name.as_str() == TICK;
        let trigger = format!("{CLOCK}.tick");
        if let Some(f) = &u.forall {
            self.errors.push(
                ModelError::new(
                    format!(
                        "`{}` extends a generated connector; it cannot have `forall`",
                        u.name
                    ),
                    f.span,
                )
                .with_help(
                    "a connector named like a generated one adds its ports, guard and action to it",
                ),
            );
        }
        match (&u.kind, is_tick) {
            (ConnectorKindDef::Rendezvous, _) => {}
            (ConnectorKindDef::Broadcast { trigger: t }, true) if t.to_string() == trigger => {}
            (ConnectorKindDef::Broadcast { trigger }, _) => {
                self.errors.push(
                    ModelError::new(format!("`{}` extends a generated connector; its kind is fixed", u.name), trigger.span())
                        .with_help(if is_tick {
                            "the tick is `Broadcast(trigger: \"clock.tick\")`; the ports you list join it as receivers"
                        } else {
                            "leave out `kind`: the ports you list join the generated rendezvous"
                        }),
                );
            }
        }
        for p in &u.ports {
            if is_tick && p.to_string() == trigger {
                continue;
            }
            if let Some(e) = self.unknown_generated_port(p) {
                self.errors.push(e);
            }
            g.ports.push(p.clone());
        }
        let role_ok = match g.role {
            Role::Time => matches!(u.role, Role::Progress | Role::Time),
            Role::Environment => true,
            Role::Progress => u.role == Role::Progress,
        };
        if !role_ok {
            self.errors.push(
                ModelError::new(
                    format!(
                        "`{}` extends a generated connector whose role is fixed",
                        u.name
                    ),
                    u.name.span,
                )
                .with_help(
                    "only request connectors take a role from their extension (docs/genom.md)",
                ),
            );
        }
        if g.role == Role::Environment {
            // a request connector taken over by a user connector: its role is the user's
            // (by default `Progress`: a supervisor in the model sends the request)
            g.role = u.role;
            if let Some(s) = self.recipe_request_mut(g.name.as_str()) {
                s.owned_by_model = u.role != Role::Environment;
            }
        }
        if let (Some(ug), Some(written)) = (user.connector_guards.get(&k), &u.guard) {
            *guard = Some(match guard.take() {
                None => ug.tree.clone(),
                Some(gg) => and(gg, ug.tree.clone()),
            });
            let cond = RecipeCondition::from(Cond {
                reason: Reason::Connector {
                    connector: u.name.value.clone(),
                    guard: written.to_string(),
                },
                expr: ug.tree.clone(),
            });
            if let Some(s) = self.recipe_request_mut(g.name.as_str()) {
                s.refusals.push(cond);
            }
        }
        if let Some(ua) = user.connector_actions.get(&k) {
            action.extend(ua.tree.iter().cloned());
        }
    }

    fn recipe_request_mut(&mut self, connector: &str) -> Option<&mut RecipeService> {
        self.recipe
            .modules
            .iter_mut()
            .flat_map(|m| m.services.iter_mut())
            .find(|s| s.request.as_deref() == Some(connector))
    }

    /// A user connector that does not extend a generated one may not use generated ports:
    /// that would run a codel, or accept a request, outside the gates.
    fn check_user_ports(&mut self, c: &ConnectorDef, generated: &HashSet<String>) {
        let mut texts: Vec<&ExprDef> = c.ports.iter().collect();
        if let ConnectorKindDef::Broadcast { trigger } = &c.kind {
            texts.push(trigger);
        }
        for p in texts {
            if let Some(e) = self.unknown_generated_port(p) {
                self.errors.push(e);
                continue;
            }
            let Ok(e) = p.tree() else { continue };
            let ExprKind::Member(base, port) = &e.kind else {
                continue;
            };
            let base = match &base.kind {
                ExprKind::Index(b, _) => b,
                _ => base,
            };
            let ExprKind::Name(comp) = &base.kind else {
                continue;
            };
            if port.name == "abort" && self.activity_components.contains(comp) {
                continue; // aborting an activity is open to every component
            }
            if generated.contains(comp) {
                let help = if comp == CLOCK {
                    "to receive the clock's tick, write a connector named `tick` with your ports: they join the generated tick".to_string()
                } else {
                    format!(
                        "name the connector like the generated one it should join (e.g. `{}`), or see docs/genom.md",
                        self.connector_for_port(comp, &port.name).unwrap_or_else(|| "rflex_TrackSpeed_request".into())
                    )
                };
                self.errors.push(
                    ModelError::new(
                        format!(
                            "`{p}` is a generated port; connector `{}` cannot use it",
                            c.name
                        ),
                        p.span(),
                    )
                    .with_help(help),
                );
            }
        }
    }

    /// A user's port `c.p` on a generated component `c` that has no port `p`, said of the
    /// module or activity `c` stands for (the compiler would name the generated atom).
    fn unknown_generated_port(&self, p: &ExprDef) -> Option<ModelError> {
        let e = p.tree().ok()?;
        let ExprKind::Member(base, port) = &e.kind else {
            return None;
        };
        let ExprKind::Name(comp) = &base.kind else {
            return None;
        };
        let c = self.components.iter().find(|c| c.name.as_str() == comp)?;
        let (_, atom) = self.atoms.iter().find(|(n, _)| *n == c.atom)?;
        if atom.ports.iter().any(|q| q.as_str() == port.name) {
            return None;
        }
        let (_, what) = self.names.get(comp.as_str())?;
        Some(
            ModelError::new(format!("{what} has no port `{}`", port.name), port.span).with_help(
                one_of("its ports are", atom.ports.iter().map(|q| q.as_str())),
            ),
        )
    }

    /// The generated connector that uses port `comp.port`, for help texts: connectors are
    /// named `<component>_<port>` for codels and requests.
    fn connector_for_port(&self, comp: &str, port: &str) -> Option<String> {
        let wanted = format!("{comp}_{port}");
        self.names.keys().filter(|n| **n == wanted).min().cloned()
    }
}
