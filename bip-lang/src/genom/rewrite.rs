//! The rewriting of the GenoM names users write in expressions (`active(m.S)`,
//! `pending(m.S)`, `m.S@state`, `age(m.port)`) into names of the generated core.
//!
//! Rewriting works on the expression syntax tree, whose spans are positions in the file: the
//! rewritten tree keeps the positions of what the user wrote, and its generated nodes have
//! none. An expression without GenoM names is kept as written.

use std::collections::{BTreeMap, HashMap};

use super::check::{port_ref, too_old, Layer, PortRef, ETHER};
use super::names::{activity_component, age_var, module_component, REQ};
use super::tree::{at, member};
use crate::compile::{one_of, Constants};
use crate::diag::{Errors, ModelError};
use crate::expr::{self, BinOp, Expr, ExprKind, Ident, UnOp};
use crate::source::Span;
use crate::syntax::{ActionDef, ExprDef};

/// Rewrites GenoM names in user expressions, and records how ports' ages are compared.
pub struct Rewriter<'a, 'd> {
    layer: &'a Layer<'d>,
    consts: &'a Constants,
    modules: HashMap<&'d str, usize>,
    /// For each port whose age is read, the largest constant it is compared with.
    pub ages: BTreeMap<PortRef, i64>,
}

/// A failure inside one expression (trees have their positions in the file).
type Failure = ModelError;

fn fail<T>(span: Span, message: impl Into<String>) -> Result<T, Failure> {
    Err(ModelError::new(message, span))
}

fn fail_help<T>(
    span: Span,
    message: impl Into<String>,
    help: impl Into<String>,
) -> Result<T, Failure> {
    Err(ModelError::new(message, span).with_help(help))
}

impl<'a, 'd> Rewriter<'a, 'd> {
    pub fn new(layer: &'a Layer<'d>, consts: &'a Constants) -> Self {
        let modules = layer
            .modules
            .iter()
            .enumerate()
            .map(|(k, m)| (m.name, k))
            .collect();
        Rewriter {
            layer,
            consts,
            modules,
            ages: BTreeMap::new(),
        }
    }

    /// Records that `age(port)` is compared with `k` (a `Fresh` constraint does too).
    pub fn note_age(&mut self, port: PortRef, k: i64) {
        let e = self.ages.entry(port).or_insert(k);
        *e = (*e).max(k);
    }

    /// Rewrites an expression: `Ok(None)` if it has no GenoM names (it stays as written),
    /// `Ok(Some(..))` with the rewritten tree, `Err` with the error pushed. A syntax error
    /// is left for whoever needs the tree to report.
    pub fn expr(&mut self, errors: &mut Errors, t: &ExprDef) -> Result<Option<Expr>, ()> {
        let Ok(e) = t.tree() else {
            return Ok(None);
        };
        let mut changed = false;
        let mut bound = Vec::new();
        match self.walk(&e, &mut bound, &mut changed) {
            Ok(new) if changed => Ok(Some(new)),
            Ok(_) => Ok(None),
            Err(f) => {
                errors.push(f);
                Err(())
            }
        }
    }

    /// Rewrites the assignments of an action, like [`Rewriter::expr`].
    pub fn action(
        &mut self,
        errors: &mut Errors,
        t: &ActionDef,
    ) -> Result<Option<Vec<expr::Assign>>, ()> {
        let Ok(assigns) = t.tree() else {
            return Ok(None);
        };
        let mut changed = false;
        let mut out = Vec::with_capacity(assigns.len());
        for a in assigns.iter() {
            let mut bound = Vec::new();
            let target = self.walk(&a.target, &mut bound, &mut changed);
            let value = self.walk(&a.value, &mut bound, &mut changed);
            match (target, value) {
                (Ok(target), Ok(value)) => out.push(expr::Assign { target, value }),
                (Err(f), _) | (_, Err(f)) => {
                    errors.push(f);
                    return Err(());
                }
            }
        }
        Ok(changed.then_some(out))
    }

    /// The module `e` names, if it is a bare module name not shadowed by a quantifier.
    fn module_of(&self, e: &Expr, bound: &[String]) -> Option<usize> {
        match &e.kind {
            ExprKind::Name(n) if !bound.iter().any(|b| b == n) => {
                self.modules.get(n.as_str()).copied()
            }
            _ => None,
        }
    }

    /// `m.S` with `m` a module: the module and the member.
    fn dotted<'e>(&self, e: &'e Expr, bound: &[String]) -> Option<(usize, &'e Ident)> {
        match &e.kind {
            ExprKind::Member(base, field) => self.module_of(base, bound).map(|m| (m, field)),
            _ => None,
        }
    }

    /// `m.S` naming an activity: its component name.
    fn activity(&self, arg: &Expr, bound: &[String], what: &str) -> Result<String, Failure> {
        let Some((m, field)) = self.dotted(arg, bound) else {
            return fail_help(
                arg.span,
                format!("`{what}` takes an activity, written `module.Service`"),
                format!("e.g. `{what}(rflex.TrackSpeed)`"),
            );
        };
        let module = &self.layer.modules[m];
        let Some(s) = module.services.iter().find(|s| s.name == field.name) else {
            return fail_help(
                field.span,
                format!("module `{}` has no service `{}`", module.name, field.name),
                one_of("its services are", module.services.iter().map(|s| s.name)),
            );
        };
        if !s.is_activity() {
            return fail_help(
                field.span,
                format!("`{}.{}` is not an activity", module.name, s.name),
                "functions and attributes run at once; they are never active or pending",
            );
        }
        Ok(activity_component(module.name, s.name))
    }

    /// `age(m.p)`: the port and the variable that holds its age.
    fn age(&self, args: &[Expr], span: Span, bound: &[String]) -> Result<(PortRef, Expr), Failure> {
        let [arg] = args else {
            return fail(span, "`age` takes one port, written `module.port`");
        };
        let Some((m, field)) = self.dotted(arg, bound) else {
            return fail_help(
                arg.span,
                "`age` takes a port, written `module.port`",
                "e.g. `age(pom.pose)`",
            );
        };
        // a connected in port's age is its writer's
        let port = port_ref(self.layer, m, &field.name, field.span)?;
        let writer = &self.layer.modules[port.module];
        let var = member(
            &module_component(writer.name),
            &age_var(writer.ports[port.port]),
        );
        Ok((port, var))
    }

    fn walk(
        &mut self,
        e: &Expr,
        bound: &mut Vec<String>,
        changed: &mut bool,
    ) -> Result<Expr, Failure> {
        let kind = match &e.kind {
            ExprKind::Int(_) | ExprKind::Bool(_) | ExprKind::Name(_) => return Ok(e.clone()),
            ExprKind::Call(f, args) => match f.name.as_str() {
                "active" | "pending" => {
                    let [arg] = args.as_slice() else {
                        return fail(e.span, format!("`{}` takes one activity", f.name));
                    };
                    let comp = self.activity(arg, bound, &f.name)?;
                    *changed = true;
                    let at_ether = at(&comp, ETHER);
                    if f.name == "active" {
                        ExprKind::Unary(UnOp::Not, Box::new(at_ether))
                    } else {
                        ExprKind::Binary(BinOp::And, Box::new(at_ether), Box::new(member(&comp, REQ)))
                    }
                }
                "age" => {
                    return fail_help(
                        e.span,
                        "`age(…)` may only be compared with a constant",
                        "write e.g. `age(pom.pose) <= 2`; ages saturate above the largest constant they are compared with",
                    )
                }
                _ => return self.children(e, bound, changed),
            },
            ExprKind::Binary(op, a, b) if op.is_comparison() => {
                let side = |x: &Expr| matches!(&x.kind, ExprKind::Call(f, _) if f.name == "age");
                if !side(a) && !side(b) {
                    return self.children(e, bound, changed);
                }
                let (age_side, other) = if side(a) { (a, b) } else { (b, a) };
                let ExprKind::Call(_, args) = &age_side.kind else {
                    return self.children(e, bound, changed);
                };
                let (port, var) = self.age(args, age_side.span, bound)?;
                let Some(k) = self.consts.int_expr(other) else {
                    return fail_help(
                        other.span,
                        "`age(…)` may only be compared with a constant",
                        "ages saturate above the largest constant they are compared with, so the other side must be a constant",
                    );
                };
                if k == i64::MAX {
                    return Err(too_old(k, other.span));
                }
                self.note_age(port, k);
                *changed = true;
                let other = self.walk(other, bound, changed)?;
                let (a, b) = if side(a) { (var, other) } else { (other, var) };
                ExprKind::Binary(*op, Box::new(a), Box::new(b))
            }
            ExprKind::At(base, loc) => {
                let Some((m, field)) = self.dotted(base, bound) else {
                    return self.children(e, bound, changed);
                };
                let module = &self.layer.modules[m];
                let Some(s) = module.services.iter().find(|s| s.name == field.name) else {
                    return fail_help(
                        field.span,
                        format!("module `{}` has no service `{}`", module.name, field.name),
                        one_of("its services are", module.services.iter().map(|s| s.name)),
                    );
                };
                if !s.is_activity() {
                    return fail(
                        field.span,
                        format!("`{}.{}` is not an activity; it has no codel states", module.name, s.name),
                    );
                }
                if !s.is_location(&loc.name) {
                    return if s.codel(&loc.name).is_some() {
                        fail_help(
                            loc.span,
                            format!("`{}.{}` never rests at `{}`", module.name, s.name, loc.name),
                            "no codel yields to it: its codel runs as soon as the activity starts, in the same step",
                        )
                    } else {
                        fail_help(
                            loc.span,
                            format!("activity `{}.{}` has no codel state `{}`", module.name, s.name, loc.name),
                            one_of(
                                "its states are",
                                std::iter::once(ETHER).chain(s.locations.iter().map(|&k| s.codels[k].state)),
                            ),
                        )
                    };
                }
                *changed = true;
                at(&activity_component(module.name, s.name), &loc.name).kind
            }
            ExprKind::Member(base, field) => {
                if let Some(m) = self.module_of(base, bound) {
                    let module = &self.layer.modules[m];
                    if let Some(s) = module.services.iter().find(|s| s.name == field.name) {
                        return fail_help(
                            field.span,
                            format!("`{}.{}` is a service, not a value", module.name, s.name),
                            format!(
                                "write `active({0}.{1})`, `pending({0}.{1})` or `{0}.{1}@state`",
                                module.name, s.name
                            ),
                        );
                    }
                    let in_port = module.in_ports.iter().any(|p| p.name == field.name);
                    if in_port || module.ports.contains(&field.name.as_str()) {
                        return fail_help(
                            field.span,
                            format!("`{}.{}` is a port, not a value", module.name, field.name),
                            format!("write `age({}.{}) <= k`", module.name, field.name),
                        );
                    }
                    // the module atom's generated variables (`age_p`, `done_f`) stay readable
                    let generated = ["age_", "done_"].iter().any(|p| field.name.starts_with(p));
                    if !generated && !module.ids.iter().any(|(x, _)| *x == field.name) {
                        return fail_help(
                            field.span,
                            format!("module `{}` has no ids field `{}`", module.name, field.name),
                            one_of(
                                "its ids fields are",
                                module.ids.iter().map(|(x, _)| *x),
                            ),
                        );
                    }
                }
                return self.children(e, bound, changed);
            }
            _ => return self.children(e, bound, changed),
        };
        Ok(Expr::new(kind, e.span))
    }

    /// Rewrites the children of `e`, keeping its shape.
    fn children(
        &mut self,
        e: &Expr,
        bound: &mut Vec<String>,
        changed: &mut bool,
    ) -> Result<Expr, Failure> {
        let mut w = |x: &Expr, bound: &mut Vec<String>| self.walk(x, bound, changed).map(Box::new);
        let kind = match &e.kind {
            ExprKind::Int(_) | ExprKind::Bool(_) | ExprKind::Name(_) => return Ok(e.clone()),
            ExprKind::Index(a, i) => ExprKind::Index(w(a, bound)?, w(i, bound)?),
            ExprKind::Member(a, f) => ExprKind::Member(w(a, bound)?, f.clone()),
            ExprKind::At(a, l) => ExprKind::At(w(a, bound)?, l.clone()),
            ExprKind::Call(f, args) => {
                let mut out = Vec::with_capacity(args.len());
                for a in args {
                    out.push(*w(a, bound)?);
                }
                ExprKind::Call(f.clone(), out)
            }
            ExprKind::Unary(op, a) => ExprKind::Unary(*op, w(a, bound)?),
            ExprKind::Binary(op, a, b) => ExprKind::Binary(*op, w(a, bound)?, w(b, bound)?),
            ExprKind::Chain(first, rest) => {
                let first = w(first, bound)?;
                let mut out = Vec::with_capacity(rest.len());
                for (op, x) in rest {
                    out.push((*op, *w(x, bound)?));
                }
                ExprKind::Chain(first, out)
            }
            ExprKind::Cond(c, a, b) => ExprKind::Cond(w(c, bound)?, w(a, bound)?, w(b, bound)?),
            ExprKind::Quant(k, r, body) => {
                let lo = *w(&r.lo, bound)?;
                let hi = *w(&r.hi, bound)?;
                bound.push(r.var.name.clone());
                let body = w(body, bound);
                bound.pop();
                let range = expr::Range {
                    var: r.var.clone(),
                    lo,
                    hi,
                };
                ExprKind::Quant(*k, Box::new(range), body?)
            }
        };
        Ok(Expr::new(kind, e.span))
    }
}
