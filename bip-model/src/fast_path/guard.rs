//! Guards as conjunctions of tests of one slot against a constant (`!paused`,
//! `antenna@ether`, `level > RESERVE`): the most common guards, decided without the tree.

use crate::prelude::*;

use crate::eval::Expr;
use crate::ops::BinOp;

/// `slot op value`; the slot is relative to the component's variables if `local`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Test {
    slot: u32,
    local: bool,
    op: Cmp,
    value: i64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Cmp {
    Eq,
    Ne,
    Lt,
    Le,
    Gt,
    Ge,
}

impl Cmp {
    fn of(op: BinOp) -> Option<Cmp> {
        Some(match op {
            BinOp::Eq => Cmp::Eq,
            BinOp::Ne => Cmp::Ne,
            BinOp::Lt => Cmp::Lt,
            BinOp::Le => Cmp::Le,
            BinOp::Gt => Cmp::Gt,
            BinOp::Ge => Cmp::Ge,
            _ => return None,
        })
    }

    /// `!(a op b)` as `a op' b`.
    fn negated(self) -> Cmp {
        match self {
            Cmp::Eq => Cmp::Ne,
            Cmp::Ne => Cmp::Eq,
            Cmp::Lt => Cmp::Ge,
            Cmp::Le => Cmp::Gt,
            Cmp::Gt => Cmp::Le,
            Cmp::Ge => Cmp::Lt,
        }
    }

    /// `a op b` as `b op' a`.
    fn swapped(self) -> Cmp {
        match self {
            Cmp::Eq | Cmp::Ne => self,
            Cmp::Lt => Cmp::Gt,
            Cmp::Le => Cmp::Ge,
            Cmp::Gt => Cmp::Lt,
            Cmp::Ge => Cmp::Le,
        }
    }
}

impl Test {
    #[inline]
    pub(super) fn holds(&self, slots: &[i64], base: u32) -> bool {
        let at = if self.local {
            base + self.slot
        } else {
            self.slot
        };
        let v = slots[at as usize];
        match self.op {
            Cmp::Eq => v == self.value,
            Cmp::Ne => v != self.value,
            Cmp::Lt => v < self.value,
            Cmp::Le => v <= self.value,
            Cmp::Gt => v > self.value,
            Cmp::Ge => v >= self.value,
        }
    }
}

/// A slot an expression reads directly: `(slot, local)`.
pub(super) fn read(e: &Expr) -> Option<(u32, bool)> {
    match e {
        Expr::Slot(s) => Some((*s, false)),
        Expr::Local(n) => Some((*n, true)),
        _ => None,
    }
}

/// The one test `e` is, if it is one.
fn test_of(e: &Expr) -> Option<Test> {
    let test = |(slot, local): (u32, bool), op, value| Test {
        slot,
        local,
        op,
        value,
    };
    match e {
        // a slot as a condition: non-zero
        Expr::Slot(_) | Expr::Local(_) => Some(test(read(e)?, Cmp::Ne, 0)),
        Expr::At(s, loc) => Some(test((*s, false), Cmp::Eq, i64::from(*loc))),
        Expr::Not(inner) => {
            let t = test_of(inner)?;
            Some(Test {
                op: t.op.negated(),
                ..t
            })
        }
        Expr::Binary(op, a, b) => {
            let op = Cmp::of(*op)?;
            match (read(a), &**b, &**a, read(b)) {
                (Some(r), Expr::Const(v), _, _) => Some(test(r, op, *v)),
                (_, _, Expr::Const(v), Some(r)) => Some(test(r, op.swapped(), *v)),
                _ => None,
            }
        }
        _ => None,
    }
}

/// Appends the tests of `e` if it is a conjunction of tests (tests cannot fail, so their
/// order does not matter); false if it is not.
pub(super) fn conjunction(e: &Expr, out: &mut Vec<Test>) -> bool {
    match e {
        Expr::Const(v) => *v != 0,
        Expr::Binary(BinOp::And, a, b) => conjunction(a, out) && conjunction(b, out),
        _ => match test_of(e) {
            Some(t) => {
                out.push(t);
                true
            }
            None => false,
        },
    }
}
