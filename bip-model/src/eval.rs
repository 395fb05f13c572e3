//! Compiled expressions and their evaluation on a state.
//!
//! Names are resolved to state slots at load time, types are checked (booleans are 0 and 1),
//! and constant subexpressions are folded, so evaluation is a walk over a small tree that
//! reads slots. Errors (division by zero, overflow, an index out of its family) are values,
//! never panics.

#[allow(unused_imports)]
use crate::prelude::*;

use crate::ops::{BinOp, QuantKind};

/// A compiled expression.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    Const(i64),
    /// The value of a state slot: a variable, or a component's location number.
    Slot(u32),
    /// A variable of the component whose transition is being evaluated: slot `base + n`.
    Local(u32),
    /// `comp@loc`: the location slot holds `loc`.
    At(u32, u32),
    /// `family[e]` with a non-constant index, then a variable or location of it.
    Indexed(Box<Indexed>),
    /// A quantified variable, by nesting depth (0 is the outermost quantifier).
    Bound(u32),
    Not(Box<Expr>),
    Neg(Box<Expr>),
    Binary(BinOp, Box<Expr>, Box<Expr>),
    /// `a op b op c …` read left to right, for long chains of arithmetic operators of one
    /// precedence: flat, so that evaluating it does not recurse once per operand.
    Chain(Box<Expr>, Vec<(BinOp, Expr)>),
    Cond(Box<Expr>, Box<Expr>, Box<Expr>),
    Quant(Box<Quant>),
    /// `advance` in the action of a `Time` connector: the time units its step stands for,
    /// evaluated on the state the step leaves (docs/model.md, "Connectors").
    Advance,
}

impl Expr {
    /// True if evaluating the expression can never be a range error, whatever the state:
    /// it reads values and compares them, with no arithmetic (which may overflow or divide
    /// by zero) and no index computed from the state (which may be out of bounds).
    pub fn cannot_fail(&self) -> bool {
        match self {
            Expr::Const(_)
            | Expr::Slot(_)
            | Expr::Local(_)
            | Expr::At(..)
            | Expr::Bound(_)
            | Expr::Advance => true,
            Expr::Not(e) => e.cannot_fail(),
            Expr::Binary(op, a, b) => {
                !matches!(
                    op,
                    BinOp::Add | BinOp::Sub | BinOp::Mul | BinOp::Div | BinOp::Rem
                ) && a.cannot_fail()
                    && b.cannot_fail()
            }
            Expr::Cond(c, a, b) => c.cannot_fail() && a.cannot_fail() && b.cannot_fail(),
            Expr::Quant(q) => q.kind != QuantKind::Sum && q.body.cannot_fail(),
            Expr::Neg(_) | Expr::Chain(..) | Expr::Indexed(_) => false,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Indexed {
    pub index: Expr,
    pub family: u32,
    pub count: u32,
    /// Slot of member 0 and the distance between members (one component's slots).
    pub first_slot: u32,
    pub stride: u32,
    /// Offset of the slot within the component (0 is the location).
    pub offset: u32,
    /// `Some(loc)` for `family[e]@loc`.
    pub at: Option<u32>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Quant {
    pub kind: QuantKind,
    pub lo: i64,
    pub hi: i64,
    pub depth: u32,
    pub body: Expr,
}

/// Quantifiers may nest at most this deep (checked when loading).
pub const MAX_QUANT_DEPTH: usize = 8;

/// What can go wrong while evaluating.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EvalError {
    DivisionByZero,
    Overflow,
    IndexOutOfBounds { family: u32, index: i64, count: u32 },
}

/// What an evaluation reports when it fails: the details, or only the fact.
trait Failure: Sized {
    fn of(e: EvalError) -> Self;
}

impl Failure for EvalError {
    #[inline(always)]
    fn of(e: EvalError) -> Self {
        e
    }
}

impl Failure for () {
    #[inline(always)]
    fn of(_: EvalError) -> Self {}
}

/// The values an expression reads: state slots, the slot base of the component whose own
/// variables `Local` refers to, the quantified variables, and in a `Time` connector's
/// action its step's `advance`.
pub struct Env<'a> {
    pub slots: &'a [i64],
    pub base: u32,
    bound: [i64; MAX_QUANT_DEPTH],
    pub advance: i64,
}

impl<'a> Env<'a> {
    pub fn new(slots: &'a [i64], base: u32) -> Env<'a> {
        Env {
            slots,
            base,
            bound: [0; MAX_QUANT_DEPTH],
            advance: 1,
        }
    }
}

impl Expr {
    pub fn is_const(&self) -> bool {
        matches!(self, Expr::Const(_))
    }

    pub fn eval(&self, env: &mut Env<'_>) -> Result<i64, EvalError> {
        // Evaluation is pure: on the rare failure, evaluating again with the details
        // costs nothing in the common case, where a small error keeps the result in
        // registers.
        match self.eval_as::<()>(env) {
            Ok(v) => Ok(v),
            Err(()) => self.eval_as::<EvalError>(env),
        }
    }

    /// Evaluation with failures of type `F` (the details, or only that it failed).
    fn eval_as<F: Failure>(&self, env: &mut Env<'_>) -> Result<i64, F> {
        Ok(match self {
            Expr::Const(v) => *v,
            Expr::Slot(s) => env.slots[*s as usize],
            Expr::Local(n) => env.slots[(env.base + n) as usize],
            Expr::At(s, loc) => (env.slots[*s as usize] == i64::from(*loc)) as i64,
            Expr::Indexed(ix) => {
                let i = ix.index.eval_as(env)?;
                if i < 0 || i >= i64::from(ix.count) {
                    return Err(F::of(EvalError::IndexOutOfBounds {
                        family: ix.family,
                        index: i,
                        count: ix.count,
                    }));
                }
                let slot =
                    ix.first_slot as usize + i as usize * ix.stride as usize + ix.offset as usize;
                match ix.at {
                    Some(loc) => (env.slots[slot] == i64::from(loc)) as i64,
                    None => env.slots[slot],
                }
            }
            Expr::Bound(d) => env.bound[*d as usize],
            Expr::Advance => env.advance,
            Expr::Not(e) => (e.eval_as(env)? == 0) as i64,
            Expr::Neg(e) => e
                .eval_as(env)?
                .checked_neg()
                .ok_or(F::of(EvalError::Overflow))?,
            Expr::Binary(op, a, b) => match op {
                BinOp::And => (a.eval_as(env)? != 0 && b.eval_as(env)? != 0) as i64,
                BinOp::Or => (a.eval_as(env)? != 0 || b.eval_as(env)? != 0) as i64,
                BinOp::Implies => (a.eval_as(env)? == 0 || b.eval_as(env)? != 0) as i64,
                _ => binary(*op, a.eval_as(env)?, b.eval_as(env)?).map_err(F::of)?,
            },
            Expr::Chain(first, rest) => {
                let mut acc = first.eval_as(env)?;
                for (op, x) in rest {
                    acc = match op {
                        BinOp::And if acc == 0 => return Ok(0),
                        BinOp::Or if acc != 0 => return Ok(1),
                        BinOp::And | BinOp::Or => (x.eval_as(env)? != 0) as i64,
                        _ => binary(*op, acc, x.eval_as(env)?).map_err(F::of)?,
                    };
                }
                acc
            }
            Expr::Cond(c, a, b) => {
                if c.eval_as(env)? != 0 {
                    a.eval_as(env)?
                } else {
                    b.eval_as(env)?
                }
            }
            Expr::Quant(q) => {
                let d = q.depth as usize;
                let mut acc: i64 = match q.kind {
                    QuantKind::Forall => 1,
                    _ => 0,
                };
                for i in q.lo..q.hi {
                    env.bound[d] = i;
                    let v = q.body.eval_as(env)?;
                    match q.kind {
                        QuantKind::Forall if v == 0 => return Ok(0),
                        QuantKind::Exists if v != 0 => return Ok(1),
                        QuantKind::Sum => {
                            acc = acc.checked_add(v).ok_or(F::of(EvalError::Overflow))?
                        }
                        QuantKind::Count => acc += (v != 0) as i64,
                        _ => {}
                    }
                }
                acc
            }
        })
    }

    /// Evaluates a boolean expression.
    pub fn holds(&self, env: &mut Env<'_>) -> Result<bool, EvalError> {
        Ok(self.eval(env)? != 0)
    }

    /// Replaces constant subexpressions by their value where evaluation succeeds; a
    /// subexpression that would fail (a constant division by zero) is left for run time,
    /// where it may never be reached.
    pub fn fold(self) -> Expr {
        let folded = match self {
            Expr::Not(e) => Expr::Not(Box::new(e.fold())),
            Expr::Neg(e) => Expr::Neg(Box::new(e.fold())),
            Expr::Binary(op, a, b) => {
                let (a, b) = (a.fold(), b.fold());
                // short-circuit identities keep guards like `false && x` from costing a read
                match (op, &a, &b) {
                    (BinOp::And, Expr::Const(0), _) | (BinOp::Or, Expr::Const(1), _) => a,
                    (BinOp::And, Expr::Const(1), _) | (BinOp::Or, Expr::Const(0), _) => b,
                    (BinOp::Implies, Expr::Const(0), _) => Expr::Const(1),
                    (BinOp::Implies, Expr::Const(1), _) => b,
                    _ => Expr::Binary(op, Box::new(a), Box::new(b)),
                }
            }
            Expr::Chain(first, rest) => Expr::Chain(
                Box::new(first.fold()),
                rest.into_iter().map(|(op, x)| (op, x.fold())).collect(),
            ),
            Expr::Cond(c, a, b) => match c.fold() {
                Expr::Const(0) => b.fold(),
                Expr::Const(_) => a.fold(),
                c => Expr::Cond(Box::new(c), Box::new(a.fold()), Box::new(b.fold())),
            },
            Expr::Indexed(mut ix) => {
                ix.index = core::mem::replace(&mut ix.index, Expr::Const(0)).fold();
                Expr::Indexed(ix)
            }
            Expr::Quant(mut q) => {
                q.body = core::mem::replace(&mut q.body, Expr::Const(0)).fold();
                Expr::Quant(q)
            }
            e => e,
        };
        if folded.reads_nothing() && !folded.is_const() {
            let mut env = Env::new(&[], 0);
            if let Ok(v) = folded.eval(&mut env) {
                return Expr::Const(v);
            }
        }
        folded
    }

    /// True if the value does not depend on the state or on quantified variables.
    pub fn reads_nothing(&self) -> bool {
        match self {
            Expr::Const(_) => true,
            Expr::Slot(_)
            | Expr::Local(_)
            | Expr::At(..)
            | Expr::Indexed(_)
            | Expr::Bound(_)
            | Expr::Advance => false,
            Expr::Not(e) | Expr::Neg(e) => e.reads_nothing(),
            Expr::Binary(_, a, b) => a.reads_nothing() && b.reads_nothing(),
            Expr::Chain(first, rest) => {
                first.reads_nothing() && rest.iter().all(|(_, x)| x.reads_nothing())
            }
            Expr::Cond(c, a, b) => c.reads_nothing() && a.reads_nothing() && b.reads_nothing(),
            Expr::Quant(q) => q.body.reads_nothing_but_bound(q.depth),
        }
    }

    fn reads_nothing_but_bound(&self, depth: u32) -> bool {
        match self {
            Expr::Bound(d) => *d >= depth,
            Expr::Const(_) => true,
            Expr::Slot(_) | Expr::Local(_) | Expr::At(..) | Expr::Indexed(_) | Expr::Advance => {
                false
            }
            Expr::Not(e) | Expr::Neg(e) => e.reads_nothing_but_bound(depth),
            Expr::Binary(_, a, b) => {
                a.reads_nothing_but_bound(depth) && b.reads_nothing_but_bound(depth)
            }
            Expr::Chain(first, rest) => {
                first.reads_nothing_but_bound(depth)
                    && rest.iter().all(|(_, x)| x.reads_nothing_but_bound(depth))
            }
            Expr::Cond(c, a, b) => {
                c.reads_nothing_but_bound(depth)
                    && a.reads_nothing_but_bound(depth)
                    && b.reads_nothing_but_bound(depth)
            }
            Expr::Quant(q) => q.body.reads_nothing_but_bound(depth),
        }
    }

    /// Calls `f` with every state slot this expression may read, given the slot base for
    /// `Local` reads. Used to know which components an interaction depends on. (`advance`
    /// reads the slots of its connector's `advance` expression, which its reader counts.)
    pub fn for_each_slot(&self, base: u32, f: &mut impl FnMut(u32)) {
        match self {
            Expr::Const(_) | Expr::Bound(_) | Expr::Advance => {}
            Expr::Slot(s) | Expr::At(s, _) => f(*s),
            Expr::Local(n) => f(base + n),
            Expr::Indexed(ix) => {
                ix.index.for_each_slot(base, f);
                for k in 0..ix.count {
                    f(ix.first_slot + k * ix.stride + ix.offset);
                }
            }
            Expr::Not(e) | Expr::Neg(e) => e.for_each_slot(base, f),
            Expr::Binary(_, a, b) => {
                a.for_each_slot(base, f);
                b.for_each_slot(base, f);
            }
            Expr::Chain(first, rest) => {
                first.for_each_slot(base, f);
                for (_, x) in rest {
                    x.for_each_slot(base, f);
                }
            }
            Expr::Cond(c, a, b) => {
                c.for_each_slot(base, f);
                a.for_each_slot(base, f);
                b.for_each_slot(base, f);
            }
            Expr::Quant(q) => q.body.for_each_slot(base, f),
        }
    }
}

/// The arithmetic and comparison operators on integers (booleans are 0 and 1).
#[inline]
pub fn binary(op: BinOp, a: i64, b: i64) -> Result<i64, EvalError> {
    Ok(match op {
        BinOp::Add => a.checked_add(b).ok_or(EvalError::Overflow)?,
        BinOp::Sub => a.checked_sub(b).ok_or(EvalError::Overflow)?,
        BinOp::Mul => a.checked_mul(b).ok_or(EvalError::Overflow)?,
        BinOp::Div => {
            if b == 0 {
                return Err(EvalError::DivisionByZero);
            }
            a.checked_div(b).ok_or(EvalError::Overflow)?
        }
        BinOp::Rem => {
            if b == 0 {
                return Err(EvalError::DivisionByZero);
            }
            a.checked_rem(b).ok_or(EvalError::Overflow)?
        }
        BinOp::Lt => (a < b) as i64,
        BinOp::Le => (a <= b) as i64,
        BinOp::Gt => (a > b) as i64,
        BinOp::Ge => (a >= b) as i64,
        BinOp::Eq => (a == b) as i64,
        BinOp::Ne => (a != b) as i64,
        BinOp::And => (a != 0 && b != 0) as i64,
        BinOp::Or => (a != 0 || b != 0) as i64,
        BinOp::Implies => (a == 0 || b != 0) as i64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(v: i64) -> Box<Expr> {
        Box::new(Expr::Const(v))
    }

    #[test]
    fn arithmetic_errors_are_values() {
        let mut env = Env::new(&[0, i64::MAX], 0);
        let div = Expr::Binary(BinOp::Div, c(1), Box::new(Expr::Slot(0)));
        assert_eq!(div.eval(&mut env), Err(EvalError::DivisionByZero));
        let rem = Expr::Binary(BinOp::Rem, c(i64::MIN), c(-1));
        assert_eq!(rem.eval(&mut env), Err(EvalError::Overflow));
        let add = Expr::Binary(BinOp::Add, Box::new(Expr::Slot(1)), c(1));
        assert_eq!(add.eval(&mut env), Err(EvalError::Overflow));
        let neg = Expr::Neg(c(i64::MIN));
        assert_eq!(neg.eval(&mut env), Err(EvalError::Overflow));
    }

    #[test]
    fn short_circuit_skips_errors() {
        let mut env = Env::new(&[0], 0);
        let bad = Box::new(Expr::Binary(BinOp::Div, c(1), Box::new(Expr::Slot(0))));
        let e = Expr::Binary(BinOp::And, Box::new(Expr::Slot(0)), bad.clone());
        assert_eq!(e.eval(&mut env), Ok(0));
        let e = Expr::Binary(BinOp::Implies, Box::new(Expr::Slot(0)), bad);
        assert_eq!(e.eval(&mut env), Ok(1));
    }

    #[test]
    fn folding_leaves_failing_constants_for_run_time() {
        let e = Expr::Binary(BinOp::Div, c(1), c(0)).fold();
        assert!(matches!(e, Expr::Binary(BinOp::Div, ..)));
        let e = Expr::Binary(BinOp::Add, c(2), c(3)).fold();
        assert_eq!(e, Expr::Const(5));
        let q = Expr::Quant(Box::new(Quant {
            kind: QuantKind::Sum,
            lo: 0,
            hi: 4,
            depth: 0,
            body: Expr::Bound(0),
        }))
        .fold();
        assert_eq!(q, Expr::Const(6));
    }

    #[test]
    fn a_chain_folds_left_to_right() {
        let mut env = Env::new(&[i64::MAX, 0], 0);
        let slot = |s| Expr::Slot(s);
        // MAX + 1 - 1 overflows at its first step, though its value would fit
        let e = Expr::Chain(
            Box::new(slot(0)),
            vec![(BinOp::Add, Expr::Const(1)), (BinOp::Sub, Expr::Const(1))],
        );
        assert_eq!(e.eval(&mut env), Err(EvalError::Overflow));
        let e = Expr::Chain(
            Box::new(slot(0)),
            vec![(BinOp::Sub, Expr::Const(1)), (BinOp::Add, Expr::Const(1))],
        );
        assert_eq!(e.eval(&mut env), Ok(i64::MAX));
        let bad = Expr::Binary(BinOp::Div, c(1), Box::new(slot(1)));
        let e = Expr::Chain(
            Box::new(Expr::Const(1)),
            vec![(BinOp::And, slot(1)), (BinOp::And, bad.clone())],
        );
        assert_eq!(e.eval(&mut env), Ok(0));
        let e = Expr::Chain(
            Box::new(Expr::Const(0)),
            vec![(BinOp::Or, Expr::Const(1)), (BinOp::Or, bad)],
        );
        assert_eq!(e.eval(&mut env), Ok(1));
        let long = Expr::Chain(
            Box::new(Expr::Const(0)),
            (0..100_000).map(|_| (BinOp::Add, Expr::Const(1))).collect(),
        );
        assert_eq!(long.clone().fold(), Expr::Const(100_000));
        assert_eq!(long.eval(&mut env), Ok(100_000));
    }

    #[test]
    fn indexed_reads_check_bounds() {
        let ix = Expr::Indexed(Box::new(Indexed {
            index: Expr::Slot(0),
            family: 0,
            count: 2,
            first_slot: 1,
            stride: 2,
            offset: 1,
            at: None,
        }));
        let mut env = Env::new(&[1, 0, 10, 0, 20], 0);
        assert_eq!(ix.eval(&mut env), Ok(20));
        let mut env = Env::new(&[2, 0, 10, 0, 20], 0);
        assert_eq!(
            ix.eval(&mut env),
            Err(EvalError::IndexOutOfBounds {
                family: 0,
                index: 2,
                count: 2
            })
        );
    }
}
