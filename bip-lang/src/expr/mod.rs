//! The expression language of docs/model.md ("Expressions"), as written: a syntax tree with positions
//! relative to the expression's text, a parser, and a printer that writes an expression back
//! with the fewest parentheses (used by `bip expand`).
//!
//! Names are not resolved here; `compile::resolve` gives them meaning.

mod parse;

use std::fmt;

pub use parse::{check_depth, parse_action, parse_expr, parse_range, ParseError, MAX_DEPTH};

use crate::source::Span;
pub use bip_model::ops::{BinOp, QuantKind};

#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    pub kind: ExprKind,
    /// Byte range within the expression's text.
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Ident {
    pub name: String,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub enum ExprKind {
    Int(i64),
    Bool(bool),
    /// A variable, constant, quantified variable or component name.
    Name(String),
    /// `e[i]`
    Index(Box<Expr>, Box<Expr>),
    /// `e.x`
    Member(Box<Expr>, Ident),
    /// `e@loc`
    At(Box<Expr>, Ident),
    /// `f(args)`, e.g. `active(m.S)` in the GenoM layer
    Call(Ident, Vec<Expr>),
    Unary(UnOp, Box<Expr>),
    Binary(BinOp, Box<Expr>, Box<Expr>),
    /// `a op b op c …`, three operands or more joined by operators of one precedence, read
    /// left to right (`a - b + c` is `(a - b) + c`): a long chain is one flat node, so that
    /// no pass over it recurses once per operand.
    Chain(Box<Expr>, Vec<(BinOp, Expr)>),
    /// `c ? a : b`
    Cond(Box<Expr>, Box<Expr>, Box<Expr>),
    /// `forall i in lo..hi: body` and its kin
    Quant(QuantKind, Box<Range>, Box<Expr>),
}

/// `i in lo..hi` (half-open), in quantifiers and in `forall` connectors.
#[derive(Clone, Debug, PartialEq)]
pub struct Range {
    pub var: Ident,
    pub lo: Expr,
    pub hi: Expr,
}

/// `target = value`, one assignment of an action.
#[derive(Clone, Debug, PartialEq)]
pub struct Assign {
    pub target: Expr,
    pub value: Expr,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum UnOp {
    Not,
    Neg,
}

const PREC_COND: u8 = 1;
const PREC_UNARY: u8 = 8;
const PREC_POSTFIX: u8 = 9;

impl Expr {
    pub fn new(kind: ExprKind, span: Span) -> Expr {
        Expr { kind, span }
    }

    /// An expression made by the tool (no position).
    pub fn generated(kind: ExprKind) -> Expr {
        Expr::new(kind, Span::NONE)
    }

    fn precedence(&self) -> u8 {
        match &self.kind {
            ExprKind::Cond(..) => PREC_COND,
            ExprKind::Binary(op, ..) => op.precedence(),
            ExprKind::Chain(_, rest) => {
                rest.first().map_or(PREC_POSTFIX, |(op, _)| op.precedence())
            }
            ExprKind::Unary(..) => PREC_UNARY,
            // A quantifier's body extends to the right as far as it can, so it is printed
            // in parentheses unless it is the whole expression.
            ExprKind::Quant(..) => 0,
            ExprKind::Int(i) if *i < 0 => PREC_UNARY,
            _ => PREC_POSTFIX,
        }
    }

    fn fmt_prec(&self, f: &mut fmt::Formatter<'_>, min: u8) -> fmt::Result {
        if self.precedence() < min {
            f.write_str("(")?;
            self.fmt_prec(f, 0)?;
            return f.write_str(")");
        }
        match &self.kind {
            ExprKind::Int(i) => write!(f, "{i}"),
            ExprKind::Bool(b) => write!(f, "{b}"),
            ExprKind::Name(n) => f.write_str(n),
            ExprKind::Index(e, i) => {
                e.fmt_prec(f, PREC_POSTFIX)?;
                f.write_str("[")?;
                i.fmt_prec(f, 0)?;
                f.write_str("]")
            }
            ExprKind::Member(e, x) => {
                e.fmt_prec(f, PREC_POSTFIX)?;
                write!(f, ".{}", x.name)
            }
            ExprKind::At(e, l) => {
                e.fmt_prec(f, PREC_POSTFIX)?;
                write!(f, "@{}", l.name)
            }
            ExprKind::Call(name, args) => {
                write!(f, "{}(", name.name)?;
                for (k, a) in args.iter().enumerate() {
                    if k > 0 {
                        f.write_str(", ")?;
                    }
                    a.fmt_prec(f, 0)?;
                }
                f.write_str(")")
            }
            ExprKind::Unary(op, e) => {
                f.write_str(match op {
                    UnOp::Not => "!",
                    UnOp::Neg => "-",
                })?;
                e.fmt_prec(f, PREC_UNARY)
            }
            ExprKind::Binary(op, a, b) => {
                let p = op.precedence();
                // `=>` is right-associative, every other operator left-associative;
                // comparisons do not chain, so both sides need a tighter operand.
                let (lp, rp) = match op {
                    BinOp::Implies => (p + 1, p),
                    _ if op.is_comparison() => (p + 1, p + 1),
                    _ => (p, p + 1),
                };
                a.fmt_prec(f, lp)?;
                write!(f, " {} ", op.symbol())?;
                b.fmt_prec(f, rp)
            }
            ExprKind::Chain(first, rest) => {
                let p = self.precedence();
                first.fmt_prec(f, p)?;
                for (op, x) in rest {
                    write!(f, " {} ", op.symbol())?;
                    x.fmt_prec(f, p + 1)?;
                }
                Ok(())
            }
            ExprKind::Cond(c, a, b) => {
                c.fmt_prec(f, PREC_COND + 1)?;
                f.write_str(" ? ")?;
                a.fmt_prec(f, PREC_COND + 1)?;
                f.write_str(" : ")?;
                b.fmt_prec(f, PREC_COND)
            }
            ExprKind::Quant(k, r, body) => {
                write!(f, "{} {}: ", k.keyword(), r)?;
                body.fmt_prec(f, 0)
            }
        }
    }
}

impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.fmt_prec(f, 0)
    }
}

impl fmt::Display for Range {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} in ", self.var.name)?;
        self.lo.fmt_prec(f, BinOp::Add.precedence())?;
        f.write_str("..")?;
        self.hi.fmt_prec(f, BinOp::Add.precedence())
    }
}

impl fmt::Display for Assign {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} = {}", self.target, self.value)
    }
}

/// Writes an action back as `a = e; b = f`.
pub fn action_to_string(action: &[Assign]) -> String {
    action
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("; ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip(text: &str) -> String {
        parse_expr(text).expect("parses").to_string()
    }

    #[test]
    fn printer_keeps_meaning_with_few_parentheses() {
        assert_eq!(round_trip("(a + b) * c"), "(a + b) * c");
        assert_eq!(round_trip("a + (b * c)"), "a + b * c");
        assert_eq!(round_trip("a - (b - c)"), "a - (b - c)");
        assert_eq!(round_trip("(a => b) => c"), "(a => b) => c");
        assert_eq!(round_trip("a => (b => c)"), "a => b => c");
        assert_eq!(round_trip("!(x && y)"), "!(x && y)");
        assert_eq!(round_trip("-(-x)"), "--x");
        assert_eq!(round_trip("c ? a : d ? e : f"), "c ? a : d ? e : f");
        assert_eq!(round_trip("(c ? a : d) ? e : f"), "(c ? a : d) ? e : f");
        assert_eq!(
            round_trip("(forall i in 0..N: p[i]@e) && q"),
            "(forall i in 0..N: p[i]@e) && q"
        );
        assert_eq!(
            round_trip("exists i in 0..N - 1: fork[(i + 1) % N].x > 2"),
            "exists i in 0..N - 1: fork[(i + 1) % N].x > 2"
        );
        assert_eq!(
            round_trip("active(m.S) && m.S@start"),
            "active(m.S) && m.S@start"
        );
    }

    #[test]
    fn printed_expressions_parse_to_the_same_tree_shape() {
        for text in [
            "(a < b) == (c < d)",
            "x % 3 * -y",
            "sum i in 0..N: (b[i].v > 0 ? 1 : 0)",
            "count j in 1..N + 1: p[j - 1]@h || q",
        ] {
            let e = parse_expr(text).expect("parses");
            let again = parse_expr(&e.to_string()).expect("printed form parses");
            assert_eq!(e.to_string(), again.to_string());
        }
    }
}
