//! A module's atom: one location, a port per function (a service that is not an
//! activity), the `done_` flags of functions that some `after` names, the ages of the
//! ports that constraints read (with the `tick` and `write` ports that move them), and a
//! port per codel that writes ids, with one transition per combination of the values it
//! may write.

use super::{set, text, tr, var, Builder};
use crate::diag::ModelError;
use crate::expr::{Assign, Expr};
use crate::genom::check::{Module, ServiceRef, VALIDATE};
use crate::genom::names::*;
use crate::genom::tree::{assign, boolean, int, name};
use crate::source::{ConstExpr, Span};
use crate::syntax::{AtomDef, TypeDef, VarDef};

impl<'a, 'd> Builder<'a, 'd> {
    pub(super) fn module(&mut self, mi: usize) {
        let m = &self.layer.modules[mi];
        let mut ports = Vec::new();
        let mut transitions = Vec::new();
        let mut vars: Vec<VarDef> = m.def.ids.clone();
        let mut reserved: Vec<(String, Span)> = Vec::new();
        for (si, s) in m.services.iter().enumerate() {
            if s.is_activity() {
                continue;
            }
            ports.push(text(s.name));
            let mut done = Vec::new();
            if self.tracked.contains(&ServiceRef {
                module: mi,
                service: si,
            }) {
                let d = done_var(s.name);
                vars.push(var(&d, TypeDef::Bool, Some(0)));
                done.push(set(&d, true));
                reserved.push((d, s.def.name.span));
            }
            // its codel's normal outcome: a transition per combination of the ids values
            // it may write
            let written = s.function.as_ref().map_or(&[][..], |c| &c.ids[..]);
            for mut action in ids_writes(m, written) {
                action.extend(done.iter().cloned());
                transitions.push(tr("on", s.name, "on", None, action));
            }
        }
        // the failures of the codels that run at a request
        for s in &m.services {
            let codels = [
                s.function.as_ref().map(|c| c.state),
                s.validate.as_ref().map(|_| VALIDATE),
            ];
            for codel in codels.into_iter().flatten() {
                let port = request_fail_port(s.name, codel);
                ports.push(text(&port));
                transitions.push(tr("on", &port, "on", None, Vec::new()));
            }
        }
        let aged = self.aged_ports(mi);
        for &(p, cap) in &aged {
            let a = age_var(m.ports[p]);
            vars.push(var(
                &a,
                TypeDef::Int(ConstExpr::int(0), ConstExpr::int(cap)),
                Some(cap),
            ));
            reserved.push((a, m.def.ports[p].name.span));
        }
        if !aged.is_empty() {
            ports.push(text("tick"));
            transitions.push(tr("on", "tick", "on", None, Vec::new()));
            // a codel that writes ids joins through its own port (below) instead
            let writes = m.services.iter().any(|s| {
                s.codels.iter().any(|c| {
                    c.ids.is_empty() && c.writes.iter().any(|w| aged.iter().any(|&(p, _)| p == *w))
                })
            });
            if writes {
                ports.push(text("write"));
                transitions.push(tr("on", "write", "on", None, Vec::new()));
            }
        }
        // a codel that writes ids: one transition per combination of the values it may
        // write (docs/genom.md, "Codels that write ids")
        for s in m.services.iter().filter(|s| s.is_activity()) {
            for c in s.codels.iter().filter(|c| !c.ids.is_empty()) {
                let port = ids_port(s.name, c.state);
                ports.push(text(&port));
                for action in ids_writes(m, &c.ids) {
                    transitions.push(tr("on", &port, "on", None, action));
                }
            }
        }
        for (name, span) in reserved {
            if let Some(id) = m.def.ids.iter().find(|v| v.name.as_str() == name) {
                self.errors.push(
                    ModelError::new(format!("ids field `{name}` clashes with a generated variable"), id.name.span)
                        .with_note(span, "generated for this")
                        .with_help("`age_<port>` and `done_<service>` are the module atom's own variables (docs/genom.md)"),
                );
            }
        }
        let atom = AtomDef {
            locations: vec![text("on")],
            initial: text("on"),
            ports,
            vars,
            transitions,
            task: None,
        };
        let what = format!("module `{}`", m.name);
        self.add_atom(module_atom(m.name), atom, m.def.name.span, what.clone());
        self.add_component(
            module_component(m.name),
            module_atom(m.name),
            m.def.name.span,
            what,
        );
    }
}

/// The assignments of each combination of the values the ids fields `written` may take,
/// the last field varying fastest; one empty combination if it writes none (or a bound is
/// not constant: the core reports it).
fn ids_writes(m: &Module, written: &[usize]) -> Vec<Vec<Assign>> {
    let fields: Vec<(&str, i64, i64)> = written
        .iter()
        .filter_map(|&k| m.ids[k].1.map(|(lo, hi)| (m.ids[k].0, lo, hi)))
        .collect();
    if fields.is_empty() || fields.len() != written.len() {
        return vec![Vec::new()];
    }
    let mut out = Vec::new();
    let mut values: Vec<i64> = fields.iter().map(|f| f.1).collect();
    loop {
        out.push(
            fields
                .iter()
                .zip(&values)
                .map(|(f, v)| assign(name(f.0), ids_literal(m, f.0, *v)))
                .collect(),
        );
        // advance the odometer, last field fastest
        let mut k = fields.len();
        loop {
            if k == 0 {
                break;
            }
            k -= 1;
            if values[k] < fields[k].2 {
                values[k] += 1;
                break;
            }
            values[k] = fields[k].1;
        }
        if values.iter().zip(&fields).all(|(v, f)| *v == f.1) {
            return out;
        }
    }
}

/// A value of ids field `x` as the model writes it (`true`/`false` for a `Bool`).
fn ids_literal(m: &Module, x: &str, v: i64) -> Expr {
    let is_bool = m
        .def
        .ids
        .iter()
        .any(|d| d.name.as_str() == x && matches!(d.ty, TypeDef::Bool));
    if is_bool {
        boolean(v != 0)
    } else {
        int(v)
    }
}
