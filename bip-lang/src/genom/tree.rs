//! The expressions the expansion generates, as syntax trees with no position (a user's
//! subtree placed inside one keeps its own), and chains of one operator kept shallow.

use crate::expr::{Assign, BinOp, Expr, ExprKind, Ident, UnOp};
use crate::source::Span;

/// Operands a chain folds one after the other before it starts another fold: a chain up
/// to this long prints as `a && b && …`, a longer one as such folds combined in a balanced
/// tree, so that a generated chain over hundreds of activities is at most a few dozen
/// levels deep.
const FOLD: usize = 32;

pub fn name(n: &str) -> Expr {
    Expr::generated(ExprKind::Name(n.to_string()))
}

fn ident(n: &str) -> Ident {
    Ident {
        name: n.to_string(),
        span: Span::NONE,
    }
}

pub fn int(v: i64) -> Expr {
    Expr::generated(ExprKind::Int(v))
}

pub fn boolean(b: bool) -> Expr {
    Expr::generated(ExprKind::Bool(b))
}

/// `comp.var`
pub fn member(comp: &str, var: &str) -> Expr {
    Expr::generated(ExprKind::Member(Box::new(name(comp)), ident(var)))
}

/// `comp@loc`
pub fn at(comp: &str, loc: &str) -> Expr {
    Expr::generated(ExprKind::At(Box::new(name(comp)), ident(loc)))
}

pub fn not(e: Expr) -> Expr {
    Expr::generated(ExprKind::Unary(UnOp::Not, Box::new(e)))
}

pub fn binary(op: BinOp, a: Expr, b: Expr) -> Expr {
    Expr::generated(ExprKind::Binary(op, Box::new(a), Box::new(b)))
}

pub fn and(a: Expr, b: Expr) -> Expr {
    binary(BinOp::And, a, b)
}

pub fn or(a: Expr, b: Expr) -> Expr {
    binary(BinOp::Or, a, b)
}

/// `c ? a : b`
pub fn cond(c: Expr, a: Expr, b: Expr) -> Expr {
    Expr::generated(ExprKind::Cond(Box::new(c), Box::new(a), Box::new(b)))
}

pub fn assign(target: Expr, value: Expr) -> Assign {
    Assign { target, value }
}

/// `a ⊕ b ⊕ …` in order, for an associative `op`; `None` for no operand.
pub fn chain(op: BinOp, parts: impl IntoIterator<Item = Expr>) -> Option<Expr> {
    let mut folds: Vec<Expr> = Vec::new();
    let mut current: Option<(Expr, usize)> = None;
    for p in parts {
        current = Some(match current.take() {
            None => (p, 1),
            Some((acc, n)) if n < FOLD => (binary(op, acc, p), n + 1),
            Some((acc, _)) => {
                folds.push(acc);
                (p, 1)
            }
        });
    }
    folds.extend(current.map(|(acc, _)| acc));
    // pair neighbours until one is left: the folds' order is kept
    while folds.len() > 1 {
        let mut paired = Vec::with_capacity(folds.len().div_ceil(2));
        let mut it = folds.into_iter();
        while let Some(a) = it.next() {
            paired.push(match it.next() {
                Some(b) => binary(op, a, b),
                None => a,
            });
        }
        folds = paired;
    }
    folds.pop()
}

/// `a && b && …`; `None` for no operand.
pub fn all(parts: impl IntoIterator<Item = Expr>) -> Option<Expr> {
    chain(BinOp::And, parts)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn depth(e: &Expr) -> usize {
        match &e.kind {
            ExprKind::Binary(_, a, b) => 1 + depth(a).max(depth(b)),
            _ => 1,
        }
    }

    #[test]
    fn short_chains_fold_like_the_parser_and_long_ones_stay_shallow() {
        let names = |n: usize| (0..n).map(|k| name(&format!("x{k}")));
        assert!(all(names(0)).is_none());
        assert_eq!(all(names(3)).expect("three").to_string(), "x0 && x1 && x2");
        let long = all(names(1000)).expect("a thousand");
        assert!(depth(&long) <= FOLD + 6, "depth {}", depth(&long));
        let printed = long.to_string();
        let order: Vec<String> = printed
            .split(" && ")
            .map(|s| s.trim_matches(|c| c == '(' || c == ')').to_string())
            .collect();
        assert_eq!(
            order,
            names(1000).map(|e| e.to_string()).collect::<Vec<_>>()
        );
    }
}
