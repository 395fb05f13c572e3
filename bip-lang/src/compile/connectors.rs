//! Connectors: each `forall` instance an interaction, its ports resolved to components
//! (each at most once, the trigger of a broadcast among them), its guard and its action
//! over the participants' variables.

use std::borrow::Cow;

use super::resolve::{one_of, Place, ResolveError, Resolver, Ty};
use super::{check_name, expr_error, unique, Compiler, MAX_COUNT, MAX_TOTAL};
use crate::diag::ModelError;
use crate::expr::{self};
use crate::source::Span;
use crate::syntax::{
    parse_range_in_file, ActionDef, ConnectorDef, ConnectorKindDef, ExprDef, SystemDef,
};
use bip_model::{Assign, Connector, Interaction, PortRef, Role, Target, VarType};

impl Compiler {
    pub(super) fn connectors(&mut self, def: &SystemDef) {
        unique(
            &mut self.errors,
            def.connectors.iter().map(|c| &c.name),
            "connector",
        );
        for cd in &def.connectors {
            if !check_name(&mut self.errors, &cd.name, "connector")
                || self.connector_by_name.contains_key(cd.name.as_str())
            {
                continue;
            }
            if let Err(e) = self.connector(cd) {
                self.errors.push(e);
                self.failed_connectors.insert(cd.name.value.clone());
            }
        }
    }

    fn connector(&mut self, cd: &ConnectorDef) -> Result<(), ModelError> {
        if cd.ports.is_empty() {
            return Err(ModelError::new(
                format!("connector `{}` has no ports", cd.name),
                cd.name.span,
            ));
        }
        let (var, values) = match &cd.forall {
            None => (None, None),
            Some(f) => {
                let r = parse_range_in_file(f)?;
                let names = self.names();
                let mut res = Resolver::new(&names, Place::Constant, &[]);
                let lo = res.constant(&r.lo, Ty::Int).map_err(forall_bound)?;
                let hi = res.constant(&r.hi, Ty::Int).map_err(forall_bound)?;
                let size = i128::from(hi) - i128::from(lo);
                if size > i128::from(MAX_COUNT) {
                    return Err(ModelError::new(
                        format!("`forall` over {size} values; at most {MAX_COUNT} are allowed"),
                        f.span,
                    ));
                }
                let total = self.interactions.len() as i128 + size.max(0);
                if total > MAX_TOTAL as i128 {
                    return Err(ModelError::new(
                        format!(
                            "this `forall` brings the model to {total} connector instances; at \
                             most {MAX_TOTAL} are allowed in all"
                        ),
                        f.span,
                    ));
                }
                (Some(r.var.name.clone()), Some(lo..hi))
            }
        };
        // parse once, resolve per instance
        let ports: Vec<(Span, Cow<expr::Expr>)> = cd
            .ports
            .iter()
            .map(|p| p.tree().map(|e| (p.span(), e)))
            .collect::<Result<_, _>>()?;
        let trigger = match &cd.kind {
            ConnectorKindDef::Rendezvous => None,
            ConnectorKindDef::Broadcast { trigger } => Some((trigger.span(), trigger.tree()?)),
        };
        let guard = cd.guard.as_ref().map(ExprDef::tree).transpose()?;
        let action = cd.action.as_ref().map(ActionDef::tree).transpose()?;
        if let (Some(a), false) = (&cd.advance, cd.role == Role::Time) {
            return Err(ModelError::new(
                format!(
                    "connector `{}` has an `advance` but is not a time step",
                    cd.name
                ),
                a.span(),
            )
            .with_help("only a connector with `role: Time` stands for time passing"));
        }
        let advance = match &cd.advance {
            Some(a) => Some((a.span(), a.tree()?)),
            None => None,
        };

        let id = self.connectors.len() as u32;
        let start = self.interactions.len() as u32;
        let indices: Vec<i64> = values.clone().map(|r| r.collect()).unwrap_or_default();
        let instances: Vec<Option<i64>> = match &values {
            None => vec![None],
            Some(_) => indices.iter().map(|&i| Some(i)).collect(),
        };
        for value in instances {
            let fixed_storage;
            let fixed: &[(&str, i64)] = match (&var, value) {
                (Some(v), Some(i)) => {
                    fixed_storage = [(v.as_str(), i)];
                    &fixed_storage
                }
                _ => &[],
            };
            let name = match value {
                Some(i) => format!("{}[{i}]", cd.name),
                None => cd.name.value.clone(),
            };
            let mut inter =
                self.interaction(cd, id, name, fixed, &ports, &trigger, &guard, &action)?;
            if let Some((span, e)) = &advance {
                inter.advance = Some(self.advance(*span, e, fixed)?);
            }
            self.interactions.push(inter);
        }
        self.connector_by_name.insert(cd.name.value.clone(), id);
        self.connectors.push(Connector {
            name: cd.name.value.clone(),
            interactions: start..self.interactions.len() as u32,
            broadcast: trigger.is_some(),
            role: cd.role,
            indices,
        });
        Ok(())
    }

    /// A `Time` connector's `advance` in one instance: an integer expression over any
    /// component, at least 1 if it is a constant (otherwise where it is evaluated).
    fn advance(
        &self,
        span: Span,
        e: &expr::Expr,
        fixed: &[(&str, i64)],
    ) -> Result<bip_model::eval::Expr, ModelError> {
        let names = self.names();
        let mut r = Resolver::new(&names, Place::Global, fixed);
        let value = r.expect(e, Ty::Int).map_err(|err| {
            let mut m = expr_error(err);
            m.message.push_str(&in_instance(fixed));
            m
        })?;
        if let bip_model::eval::Expr::Const(v) = value {
            if v < 1 {
                return Err(ModelError::new(
                    format!(
                        "`advance` is {v}{}; a time step stands for at least 1 unit",
                        in_instance(fixed)
                    ),
                    span,
                ));
            }
        }
        Ok(value)
    }

    #[allow(clippy::too_many_arguments)]
    fn interaction(
        &self,
        cd: &ConnectorDef,
        id: u32,
        name: String,
        fixed: &[(&str, i64)],
        ports: &[(Span, Cow<expr::Expr>)],
        trigger: &Option<(Span, Cow<expr::Expr>)>,
        guard: &Option<Cow<expr::Expr>>,
        action: &Option<Cow<[expr::Assign]>>,
    ) -> Result<Interaction, ModelError> {
        let names = self.names();
        let mut r = Resolver::new(&names, Place::Global, fixed);
        let at = in_instance;
        let mut port_ref = |e: &expr::Expr| -> Result<PortRef, ModelError> {
            let (comp, member) = r.static_member(e).map_err(|err| {
                let mut m = expr_error(err);
                m.message.push_str(&at(fixed));
                m
            })?;
            let atom = &self.atoms[self.components[comp as usize].atom as usize];
            match atom.port_index(&member.name) {
                Some(port) => Ok(PortRef {
                    component: comp,
                    port,
                }),
                None => Err(ModelError::new(
                    format!("atom `{}` has no port `{}`", atom.name, member.name),
                    member.span,
                )
                .with_help(one_of(
                    "its ports are",
                    atom.ports.iter().map(String::as_str),
                ))),
            }
        };
        let mut refs = Vec::with_capacity(ports.len() + 1);
        let mut spans = Vec::with_capacity(ports.len() + 1);
        for (span, e) in ports {
            refs.push(port_ref(e)?);
            spans.push(*span);
        }
        let mut trigger_pos = None;
        if let Some((span, e)) = trigger {
            let t = port_ref(e)?;
            match refs.iter().position(|p| *p == t) {
                Some(k) => trigger_pos = Some(k as u32),
                None => {
                    refs.insert(0, t);
                    spans.insert(0, *span);
                    trigger_pos = Some(0);
                }
            }
        }
        for (k, p) in refs.iter().enumerate() {
            if let Some(j) = refs[..k].iter().position(|q| q.component == p.component) {
                return Err(ModelError::new(
                    format!(
                        "component `{}` appears twice in connector `{}`{}",
                        self.components[p.component as usize].name,
                        cd.name,
                        at(fixed)
                    ),
                    spans[k],
                )
                .with_note(spans[j], "first here")
                .with_help("a component takes part at most once in a connector"));
            }
        }
        let mut r = Resolver::new(&names, Place::Global, fixed);
        let guard = match guard {
            None => None,
            Some(e) => Some(r.expect(e, Ty::Bool).map_err(|err| {
                let mut m = expr_error(err);
                m.message.push_str(&at(fixed));
                m
            })?),
        };
        let mut assigns = Vec::new();
        if let Some(list) = action {
            for a in list.iter() {
                let fail = |err: ResolveError| {
                    let mut m = expr_error(err);
                    m.message.push_str(&at(fixed));
                    m
                };
                let (comp, member) = r.static_member(&a.target).map_err(fail)?;
                if !refs.iter().any(|p| p.component == comp) {
                    return Err(ModelError::new(
                        format!(
                            "`{}` is not in connector `{}`; a connector's action assigns only \
                             its participants' variables{}",
                            self.components[comp as usize].name,
                            cd.name,
                            at(fixed)
                        ),
                        a.target.span,
                    ));
                }
                let c = &self.components[comp as usize];
                let atom = &self.atoms[c.atom as usize];
                let Some(v) = atom.var_index(&member.name) else {
                    return Err(ModelError::new(
                        format!("atom `{}` has no variable `{}`", atom.name, member.name),
                        member.span,
                    ));
                };
                let ty = match atom.vars[v as usize].ty {
                    VarType::Bool => Ty::Bool,
                    VarType::Int { .. } => Ty::Int,
                };
                // a time step's action reads its `advance`
                r.advance = cd.role == Role::Time;
                let value = r.expect(&a.value, ty).map_err(fail);
                r.advance = false;
                let value = value?;
                assigns.push(Assign {
                    target: Target::Slot(c.var_slot(v)),
                    value,
                });
            }
        }
        Ok(Interaction {
            name,
            connector: id,
            ports: refs,
            trigger: trigger_pos,
            guard,
            action: assigns,
            advance: None,
        })
    }
}

/// Where an error is, in a connector with `forall`: ` (in instance i = 3)`.
fn in_instance(fixed: &[(&str, i64)]) -> String {
    match fixed.first() {
        Some((v, i)) => format!(" (in instance {v} = {i})"),
        None => String::new(),
    }
}

fn forall_bound(mut e: ResolveError) -> ModelError {
    if e.message.starts_with("expected a constant") {
        e.message = "`forall` bounds must be constant expressions".into();
    }
    expr_error(e)
}
