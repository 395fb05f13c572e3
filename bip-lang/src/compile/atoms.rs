//! Atoms: locations, ports and typed variables, and transitions whose guards and actions
//! read and write only the atom's own variables; initial values checked against their
//! ranges (also for a family's `vars_init`).

use super::resolve::{one_of, Place, Resolver, Ty};
use super::{check_name, expr_error, unique, Compiler};
use crate::diag::{Errors, ModelError};
use crate::expr::ExprKind;
use crate::source::ConstExpr;
use crate::syntax::{ActionDef, AtomDef, ExprDef, SystemDef, Text, TypeDef};
use bip_model::eval;
use bip_model::{Assign, Atom, Target, Transition, Var, VarType};

impl Compiler {
    pub(super) fn atoms(&mut self, def: &SystemDef) {
        unique(&mut self.errors, def.atoms.iter().map(|(k, _)| k), "atom");
        for (name, a) in def.atoms.iter() {
            if !check_name(&mut self.errors, name, "atom")
                || self.atom_by_name.contains_key(name.as_str())
            {
                continue;
            }
            let atom = self.atom(name, a);
            self.atom_by_name
                .insert(name.value.clone(), self.atoms.len() as u32);
            self.atoms.push(atom);
        }
    }

    fn atom(&mut self, name: &Text, a: &AtomDef) -> Atom {
        let errors = &mut self.errors;
        if a.locations.is_empty() {
            errors.push(ModelError::new(
                format!("atom `{name}` has no locations"),
                name.span,
            ));
        }
        for l in &a.locations {
            check_name(errors, l, "location");
        }
        for p in &a.ports {
            check_name(errors, p, "port");
        }
        let locs = unique(errors, a.locations.iter(), "location");
        let ports = unique(errors, a.ports.iter(), "port");
        unique(errors, a.vars.iter().map(|v| &v.name), "variable");
        let lookup_loc = |errors: &mut Errors, l: &Text| -> Option<u32> {
            let found = locs.get(l.as_str()).map(|&i| i as u32);
            if found.is_none() {
                errors.push(
                    ModelError::new(format!("atom `{name}` has no location `{l}`"), l.span)
                        .with_help(one_of(
                            "its locations are",
                            a.locations.iter().map(|l| l.as_str()),
                        )),
                );
            }
            found
        };
        let initial = lookup_loc(errors, &a.initial).unwrap_or(0);

        let mut vars = Vec::new();
        for v in &a.vars {
            check_name(&mut self.errors, &v.name, "variable");
            let ty = match &v.ty {
                TypeDef::Bool => VarType::Bool,
                TypeDef::Int(lo, hi) => {
                    let lo_v = self.const_value(lo, Ty::Int, &[]);
                    let hi_v = self.const_value(hi, Ty::Int, &[]);
                    match (lo_v, hi_v) {
                        (Ok(l), Ok(h)) if l <= h => VarType::Int { lo: l, hi: h },
                        (Ok(l), Ok(h)) => {
                            self.errors.push(ModelError::new(
                                format!("empty range: {l} is greater than {h}"),
                                lo.span,
                            ));
                            VarType::Int { lo: h, hi: h }
                        }
                        (l, h) => {
                            for e in [l.err(), h.err()].into_iter().flatten() {
                                self.errors.push(e);
                            }
                            VarType::Int { lo: 0, hi: 0 }
                        }
                    }
                }
            };
            let init = match &v.init {
                None => ty.range().0,
                Some(init) => self
                    .checked_init(init, &ty, &v.name, &[])
                    .unwrap_or(ty.range().0),
            };
            vars.push(Var {
                name: v.name.value.clone(),
                ty,
                init,
            });
        }

        // the atom as far as its transitions' guards and actions need it
        let atom = Atom::new(
            name.value.clone(),
            a.locations.iter().map(|l| l.value.clone()).collect(),
            initial,
            a.ports.iter().map(|p| p.value.clone()).collect(),
            vars,
            Vec::new(),
        );
        let mut transitions = Vec::new();
        for t in &a.transitions {
            let from = lookup_loc(&mut self.errors, &t.from);
            let to = lookup_loc(&mut self.errors, &t.to);
            let port = match &t.port {
                None => Some(None),
                Some(p) => match ports.get(p.as_str()) {
                    Some(&i) => Some(Some(i as u32)),
                    None => {
                        self.errors.push(
                            ModelError::new(format!("atom `{name}` has no port `{p}`"), p.span)
                                .with_help(one_of(
                                    "its ports are",
                                    a.ports.iter().map(|p| p.as_str()),
                                )),
                        );
                        None
                    }
                },
            };
            let guard = t.guard.as_ref().and_then(|g| self.atom_guard(&atom, g));
            let action = t
                .action
                .as_ref()
                .map(|act| self.atom_action(&atom, act))
                .unwrap_or_default();
            if let (Some(from), Some(to), Some(port)) = (from, to, port) {
                transitions.push(Transition {
                    from,
                    port,
                    to,
                    guard,
                    action,
                });
            }
        }
        Atom::new(
            atom.name,
            atom.locations,
            atom.initial,
            atom.ports,
            atom.vars,
            transitions,
        )
    }

    /// Checks an initial value against its variable's type and range.
    pub(super) fn checked_init(
        &mut self,
        init: &ConstExpr,
        ty: &VarType,
        var: &str,
        fixed: &[(&str, i64)],
    ) -> Option<i64> {
        let want = match ty {
            VarType::Bool => Ty::Bool,
            VarType::Int { .. } => Ty::Int,
        };
        match self.const_value(init, want, fixed) {
            Ok(v) => {
                if let VarType::Int { lo, hi } = ty {
                    if v < *lo || v > *hi {
                        let mut e = ModelError::new(
                            format!(
                                "initial value {v} of `{var}` is outside its range Int({lo}, {hi})"
                            ),
                            init.span,
                        );
                        if let Some((_, k)) = fixed.iter().find(|(n, _)| *n == "self_index") {
                            e = e.with_help(format!("for the instance with self_index = {k}"));
                        }
                        self.errors.push(e);
                        return None;
                    }
                }
                Some(v)
            }
            Err(e) => {
                self.errors.push(e);
                None
            }
        }
    }

    fn atom_guard(&mut self, atom: &Atom, g: &ExprDef) -> Option<eval::Expr> {
        let e = match g.tree() {
            Ok(e) => e,
            Err(e) => {
                self.errors.push(e);
                return None;
            }
        };
        let names = self.names();
        let mut r = Resolver::new(&names, Place::Atom(atom), &[]);
        match r.expect(&e, Ty::Bool) {
            Ok(c) => Some(c),
            Err(e) => {
                self.errors.push(expr_error(e));
                None
            }
        }
    }

    fn atom_action(&mut self, atom: &Atom, act: &ActionDef) -> Vec<Assign> {
        let assigns = match act.tree() {
            Ok(a) => a,
            Err(e) => {
                self.errors.push(e);
                return Vec::new();
            }
        };
        let mut out = Vec::new();
        for a in assigns.iter() {
            let ExprKind::Name(n) = &a.target.kind else {
                self.errors.push(
                    ModelError::new(
                        "an atom's action assigns only its own variables",
                        a.target.span,
                    )
                    .with_help("write `x = …` with `x` a variable of this atom"),
                );
                continue;
            };
            let Some(v) = atom.var_index(n) else {
                self.errors.push(
                    ModelError::new(
                        format!("atom `{}` has no variable `{n}`", atom.name),
                        a.target.span,
                    )
                    .with_help(one_of(
                        "its variables are",
                        atom.vars.iter().map(|v| v.name.as_str()),
                    )),
                );
                continue;
            };
            let ty = match atom.vars[v as usize].ty {
                VarType::Bool => Ty::Bool,
                VarType::Int { .. } => Ty::Int,
            };
            let names = self.names();
            let mut r = Resolver::new(&names, Place::Atom(atom), &[]);
            match r.expect(&a.value, ty) {
                Ok(value) => out.push(Assign {
                    target: Target::Local(v),
                    value,
                }),
                Err(e) => self.errors.push(expr_error(e)),
            }
        }
        out
    }
}
