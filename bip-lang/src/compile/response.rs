//! What a response property watches for (docs/model.md, "Response and liveness"): a
//! trigger or a response is a state condition, or steps written `fires(c, …)` (a step of
//! one of these connectors), `changes(before, after)` (a step from a state where `before`
//! holds to one where `after` holds), `fires(c) && changes(b, a)` (both), or a `||` of
//! these. The GenoM layer's events (`request(m.S)`, …) are expanded into these forms.

use super::budgets::{show_us, written_duration};
use super::resolve::{one_of, Ty};
use super::Compiler;
use crate::diag::ModelError;
use crate::expr::{Expr, ExprKind};
use crate::source::{ConstExpr, Span};
use crate::syntax::ExprDef;
use bip_model::ops::BinOp;
use bip_model::{Happens, Role, StepPattern};

/// The names of the step forms.
const FIRES: &str = "fires";
const CHANGES: &str = "changes";

impl Compiler {
    /// A trigger or response: steps if it is written with the step forms, else a state
    /// condition. `None` once its error is reported.
    pub(super) fn happens(&mut self, t: &ExprDef) -> Option<Happens> {
        let tree = match t.tree() {
            Ok(tree) => tree.into_owned(),
            Err(e) => {
                self.errors.push(e);
                return None;
            }
        };
        let alternatives = disjuncts(&tree);
        let steps = alternatives.iter().filter(|e| is_step_form(e)).count();
        if steps == 0 {
            return self.global_bool_tree(&tree).map(Happens::State);
        }
        if steps < alternatives.len() {
            self.errors.push(
                ModelError::new("this mixes steps and a state condition", tree.span).with_help(
                    "a trigger or a response is either steps or a state; `changes(true, e)` is any step into a state where `e` holds",
                ),
            );
            return None;
        }
        let mut patterns = Vec::with_capacity(alternatives.len());
        for e in alternatives {
            patterns.push(self.step_pattern(e)?);
        }
        Some(Happens::Step(patterns))
    }

    fn step_pattern(&mut self, e: &Expr) -> Option<StepPattern> {
        let mut p = StepPattern::default();
        let parts: Vec<&Expr> = match &e.kind {
            ExprKind::Binary(BinOp::And, a, b) => vec![a, b],
            _ => vec![e],
        };
        for part in parts {
            let ExprKind::Call(f, args) = &part.kind else {
                return self.fail(part.span, "expected `fires(…)` or `changes(…, …)`");
            };
            if f.name == FIRES {
                if args.is_empty() {
                    return self.fail(part.span, "`fires` takes one or more connectors");
                }
                for a in args {
                    p.connectors.push(self.connector_named(a)?);
                }
            } else {
                let [before, after] = args.as_slice() else {
                    return self.fail(
                        part.span,
                        "`changes` takes two conditions: before the step and after it",
                    );
                };
                p.before = Some(self.global_bool_tree(before)?);
                p.after = Some(self.global_bool_tree(after)?);
            }
        }
        Some(p)
    }

    fn connector_named(&mut self, a: &Expr) -> Option<u32> {
        let found = match &a.kind {
            ExprKind::Name(n) => self.connector_by_name.get(n).copied(),
            _ => None,
        };
        if found.is_none() {
            let what = match &a.kind {
                ExprKind::Name(n) => format!("no connector `{n}`"),
                _ => "`fires` takes connector names".to_string(),
            };
            let help = one_of(
                "the connectors are",
                self.connectors.iter().map(|c| c.name.as_str()),
            );
            self.errors
                .push(ModelError::new(what, a.span).with_help(help));
        }
        found
    }

    /// `within`: a number of ticks, or a duration (`"200ms"`), which needs a `Time`
    /// connector to count it; in the units a `Time` step advances: ticks, or a timed
    /// model's time units.
    pub(super) fn within(&mut self, k: &ConstExpr) -> Option<u64> {
        let units = match written_duration(k) {
            Some(duration) => self.duration_in_steps(k.span, duration)?,
            None => {
                let value = match self.const_value(k, Ty::Int, &[]) {
                    Ok(v) => v,
                    Err(e) => {
                        self.errors.push(e);
                        return None;
                    }
                };
                if value < 0 {
                    return self.fail(
                        k.span,
                        format!("`within` is {value}; it counts ticks, at least 0"),
                    );
                }
                let ticks = value as u64;
                match (self.time_unit_us, self.tick_us) {
                    (Some(unit), Some(tick)) => ticks.saturating_mul(tick / unit),
                    _ => ticks,
                }
            }
        };
        if !self.connectors.iter().any(|c| c.role == Role::Time) {
            self.errors.push(
                ModelError::new(
                    "`within` counts ticks, but no connector has the role `Time`",
                    k.span,
                )
                .with_help(
                    "give the clock's connector `role: Time`, or state the property with `LeadsTo`",
                ),
            );
            return None;
        }
        Some(units)
    }

    /// A `within` written as a duration, in the steps time passes by: the timed model's
    /// units, or ticks of `tick_ms`; it must be a whole number of them.
    fn duration_in_steps(&mut self, span: Span, duration: Result<u64, String>) -> Option<u64> {
        let us = match duration {
            Ok(us) => us,
            Err(why) => {
                return self.fail(span, format!("`within` must be a duration: {why}"));
            }
        };
        let (step, what) = match (self.time_unit_us, self.tick_us) {
            (Some(unit), _) => (unit, "the model's time unit"),
            (None, Some(tick)) => (tick, "a tick (`tick_ms`)"),
            (None, None) => {
                self.errors.push(
                    ModelError::new(
                        "`within` is a duration, but the model has no `tick_ms` to count it in",
                        span,
                    )
                    .with_help("give the model a `tick_ms`, or write `within` in ticks"),
                );
                return None;
            }
        };
        if us % step != 0 {
            self.errors.push(
                ModelError::new(
                    format!(
                        "`within` of {} is not a whole number of {what}, {}",
                        show_us(us),
                        show_us(step)
                    ),
                    span,
                )
                .with_help(format!(
                    "write a multiple of {}, such as `\"{}\"`",
                    show_us(step),
                    show_us(us / step * step + step).replace(' ', "")
                )),
            );
            return None;
        }
        Some(us / step)
    }

    fn fail<T>(&mut self, span: Span, message: impl Into<String>) -> Option<T> {
        self.errors.push(ModelError::new(message, span));
        None
    }
}

/// The operands of a top-level `||` (the expression itself if it is none).
pub(crate) fn disjuncts(e: &Expr) -> Vec<&Expr> {
    match &e.kind {
        ExprKind::Binary(BinOp::Or, a, b) => {
            let mut out = disjuncts(a);
            out.extend(disjuncts(b));
            out
        }
        ExprKind::Chain(first, rest) if rest.iter().all(|(op, _)| *op == BinOp::Or) => {
            let mut out = disjuncts(first);
            for (_, x) in rest {
                out.extend(disjuncts(x));
            }
            out
        }
        _ => vec![e],
    }
}

/// `fires(…)`, `changes(…)`, or one of each joined by `&&`.
fn is_step_form(e: &Expr) -> bool {
    let call =
        |e: &Expr| matches!(&e.kind, ExprKind::Call(f, _) if f.name == FIRES || f.name == CHANGES);
    match &e.kind {
        ExprKind::Binary(BinOp::And, a, b) => call(a) && call(b),
        _ => call(e),
    }
}
