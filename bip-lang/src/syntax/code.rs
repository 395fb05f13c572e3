//! Expressions and actions of a model: as written in the file, or built by the GenoM
//! expansion as syntax trees.
//!
//! A written text is parsed by the compiler; a built tree is compiled as it is, never
//! printed and parsed again. Both give trees whose spans are positions in the model's file:
//! a written text's tree is moved to its place in the file ([`in_file`]), a built tree keeps
//! the positions of the user's subtrees it holds, and its generated nodes have none.
//! A model prints back to RON (`bip expand`) with built trees written out by the expression
//! printer.

use std::borrow::Cow;
use std::fmt;

use serde::de::{Deserialize, Deserializer};
use serde::ser::{Serialize, Serializer};

use crate::diag::ModelError;
use crate::expr::{self, parse_action, parse_expr, parse_range, Assign, Expr, ExprKind, Ident};
use crate::source::{Span, Text};

/// An expression of a model (a guard, a port, a condition, a property).
#[derive(Clone, Debug)]
pub enum ExprDef {
    Written(Text),
    Built(Expr),
}

/// An action: assignments `target = value`.
#[derive(Clone, Debug)]
pub enum ActionDef {
    Written(Text),
    Built(Vec<Assign>),
}

impl ExprDef {
    /// Where the expression is in the file (`Span::NONE` for a generated one).
    pub fn span(&self) -> Span {
        match self {
            ExprDef::Written(t) => t.span,
            ExprDef::Built(e) => e.span,
        }
    }

    /// The expression's tree, with positions in the file; a written text that does not
    /// parse is a syntax error at its place.
    pub fn tree(&self) -> Result<Cow<'_, Expr>, ModelError> {
        match self {
            ExprDef::Written(t) => parse_in_file(t).map(Cow::Owned),
            ExprDef::Built(e) => Ok(Cow::Borrowed(e)),
        }
    }
}

impl ActionDef {
    pub fn span(&self) -> Span {
        match self {
            ActionDef::Written(t) => t.span,
            ActionDef::Built(list) => list.first().map_or(Span::NONE, |a| a.target.span),
        }
    }

    /// The assignments, with positions in the file.
    pub fn tree(&self) -> Result<Cow<'_, [Assign]>, ModelError> {
        match self {
            ActionDef::Written(t) => parse_action_in_file(t).map(Cow::Owned),
            ActionDef::Built(list) => Ok(Cow::Borrowed(list)),
        }
    }
}

impl fmt::Display for ExprDef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ExprDef::Written(t) => f.write_str(t),
            ExprDef::Built(e) => e.fmt(f),
        }
    }
}

impl fmt::Display for ActionDef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ActionDef::Written(t) => f.write_str(t),
            ActionDef::Built(list) => f.write_str(&expr::action_to_string(list)),
        }
    }
}

impl From<&str> for ExprDef {
    fn from(s: &str) -> Self {
        ExprDef::Written(s.into())
    }
}

impl From<Text> for ExprDef {
    fn from(t: Text) -> Self {
        ExprDef::Written(t)
    }
}

impl From<Expr> for ExprDef {
    fn from(e: Expr) -> Self {
        ExprDef::Built(e)
    }
}

impl From<Vec<Assign>> for ActionDef {
    fn from(list: Vec<Assign>) -> Self {
        ActionDef::Built(list)
    }
}

impl Serialize for ExprDef {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            ExprDef::Written(t) => t.serialize(s),
            ExprDef::Built(e) => s.serialize_str(&e.to_string()),
        }
    }
}

impl Serialize for ActionDef {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            ActionDef::Written(t) => t.serialize(s),
            ActionDef::Built(list) => s.serialize_str(&expr::action_to_string(list)),
        }
    }
}

impl<'de> Deserialize<'de> for ExprDef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Text::deserialize(d).map(ExprDef::Written)
    }
}

impl<'de> Deserialize<'de> for ActionDef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Text::deserialize(d).map(ActionDef::Written)
    }
}

/// A syntax error in a written text, at its place in the file.
pub fn syntax_error(t: &Text, e: expr::ParseError) -> ModelError {
    ModelError::new(
        format!("syntax error: {}", e.message),
        t.sub_span(e.span.start..e.span.end),
    )
}

/// Parses a written expression into a tree with positions in the file.
pub fn parse_in_file(t: &Text) -> Result<Expr, ModelError> {
    let mut e = parse_expr(t).map_err(|e| syntax_error(t, e))?;
    in_file(t, &mut e);
    Ok(e)
}

/// Parses a written action into assignments with positions in the file.
pub fn parse_action_in_file(t: &Text) -> Result<Vec<Assign>, ModelError> {
    let mut list = parse_action(t).map_err(|e| syntax_error(t, e))?;
    for a in &mut list {
        in_file(t, &mut a.target);
        in_file(t, &mut a.value);
    }
    Ok(list)
}

/// Parses a `forall` range (`i in lo..hi`) with positions in the file.
pub fn parse_range_in_file(t: &Text) -> Result<expr::Range, ModelError> {
    let mut r = parse_range(t).map_err(|e| syntax_error(t, e))?;
    r.var.span = t.sub_span(r.var.span.start..r.var.span.end);
    in_file(t, &mut r.lo);
    in_file(t, &mut r.hi);
    Ok(r)
}

/// Moves the spans of a tree parsed from `t` (relative to its text) to the file. Walks
/// with a stack of its own: a long chain of operators is a deep tree.
fn in_file(t: &Text, e: &mut Expr) {
    let place = |s: &mut Span| *s = t.sub_span(s.start..s.end);
    let ident = |i: &mut Ident| i.span = t.sub_span(i.span.start..i.span.end);
    let mut stack = vec![e];
    while let Some(e) = stack.pop() {
        place(&mut e.span);
        match &mut e.kind {
            ExprKind::Int(_) | ExprKind::Bool(_) | ExprKind::Name(_) => {}
            ExprKind::Index(a, b) | ExprKind::Binary(_, a, b) => {
                stack.push(a);
                stack.push(b);
            }
            ExprKind::Chain(first, rest) => {
                stack.push(first);
                stack.extend(rest.iter_mut().map(|(_, x)| x));
            }
            ExprKind::Member(a, x) | ExprKind::At(a, x) => {
                ident(x);
                stack.push(a);
            }
            ExprKind::Unary(_, a) => stack.push(a),
            ExprKind::Call(f, args) => {
                ident(f);
                stack.extend(args.iter_mut());
            }
            ExprKind::Cond(a, b, c) => {
                stack.push(a);
                stack.push(b);
                stack.push(c);
            }
            ExprKind::Quant(_, r, body) => {
                ident(&mut r.var);
                let r = &mut **r;
                stack.push(&mut r.lo);
                stack.push(&mut r.hi);
                stack.push(body);
            }
        }
    }
}
