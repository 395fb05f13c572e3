//! Symbolic values and the translation of compiled expressions into z3 terms.
//!
//! A [`Sym`] is a z3 term (integer or boolean) with the interval its value lies in and the
//! condition under which evaluating it fails (division by zero, overflow, an index outside
//! its family): the same failures `bip_model::eval` reports, with the same short-circuit
//! rules, so that "this guard cannot be evaluated" is part of the encoding and a range error
//! is never hidden. Intervals make constants fold as they are built: a state of numerals
//! gives numerals, and overflow conditions vanish wherever the ranges exclude them.
//!
//! The helpers `and`, `or`, `not`, `ite_*` fold literal operands, so formulas over a concrete
//! state (the initial state of a bounded model check, a state in a test) collapse to
//! literals without asking the solver.
//!
//! This module holds the terms and symbolic values; `formula` the folding helpers,
//! `translate` the translation of expressions, `arith` the arithmetic with its intervals
//! and failure conditions.

mod arith;
mod formula;
mod translate;

use bip_model::ops::BinOp;
use z3::ast::{Bool, Int};

use arith::count_cmp;

pub use formula::{
    and, and2, eq_num, err_formula, err_or, err_when, ff, iff, implies, ite_bool, ite_int, lit,
    not, num, or, or2, tt,
};
pub use translate::{translate, translate_in_step, Slots};

const I64_MIN: i128 = i64::MIN as i128;
const I64_MAX: i128 = i64::MAX as i128;
/// Interval arithmetic saturates here, far beyond any i64 value, so it never overflows.
const HUGE: i128 = 1 << 100;

/// A z3 term: integers (`Int` variables, arithmetic), booleans (`Bool` variables,
/// conditions), or small non-negative integers in binary (locations: one `Bool` per bit,
/// least significant first, so that "at location l" is a conjunction of literals and
/// models without data stay propositional). Compiled expressions treat booleans as 0 and
/// 1; conversions are explicit.
#[derive(Clone, Debug)]
pub enum Term {
    I(Int),
    B(Bool),
    Bits(Vec<Bool>),
    /// How many of these conditions hold, plus a constant (a `count` quantifier): compared
    /// with a constant, it becomes a pseudo-boolean constraint, which z3 reasons about
    /// far better than a sum of if-then-elses.
    Count(std::rc::Rc<Vec<Bool>>, i64),
}

/// A symbolic value: its term, the interval `lo..=hi` it lies in when it does not fail,
/// and the condition under which its evaluation fails (`None`: it never does).
#[derive(Clone, Debug)]
pub struct Sym {
    pub term: Term,
    pub lo: i128,
    pub hi: i128,
    pub err: Option<Bool>,
}

impl Sym {
    pub fn int(v: i64) -> Sym {
        Sym {
            term: Term::I(num(v)),
            lo: v.into(),
            hi: v.into(),
            err: None,
        }
    }

    pub fn boolean(b: bool) -> Sym {
        Sym {
            term: Term::B(Bool::from_bool(b)),
            lo: b.into(),
            hi: b.into(),
            err: None,
        }
    }

    /// A value that always fails (an index known to be outside its family).
    fn failing() -> Sym {
        Sym {
            term: Term::I(num(0)),
            lo: 0,
            hi: 0,
            err: Some(tt()),
        }
    }

    pub fn of_int(term: Int, lo: i128, hi: i128) -> Sym {
        if lo == hi {
            // the value is known: keep the numeral, which folds further
            if let Ok(v) = i64::try_from(lo) {
                return Sym::int(v);
            }
        }
        Sym {
            term: Term::I(term),
            lo,
            hi,
            err: None,
        }
    }

    pub fn of_bool(term: Bool) -> Sym {
        match lit(&term) {
            Some(b) => Sym::boolean(b),
            None => Sym {
                term: Term::B(term),
                lo: 0,
                hi: 1,
                err: None,
            },
        }
    }

    pub fn constant(&self) -> Option<i64> {
        if self.lo == self.hi && self.err.is_none() {
            i64::try_from(self.lo).ok()
        } else {
            None
        }
    }

    /// A small non-negative integer in binary, `width` bits.
    pub fn of_bits(bits: Vec<Bool>, lo: i128, hi: i128) -> Sym {
        if lo == hi {
            if let Ok(v) = i64::try_from(lo) {
                return Sym::int(v);
            }
        }
        Sym {
            term: Term::Bits(bits),
            lo,
            hi,
            err: None,
        }
    }

    /// The value as an integer term (booleans are 0 and 1).
    pub fn int_term(&self) -> Int {
        if let Some(v) = self.constant() {
            return num(v);
        }
        match &self.term {
            Term::I(x) => x.clone(),
            Term::B(b) => ite_int(b, &num(1), &num(0)),
            Term::Bits(bits) => {
                let parts: Vec<Int> = bits
                    .iter()
                    .enumerate()
                    .map(|(k, b)| ite_int(b, &num(1 << k), &num(0)))
                    .collect();
                match parts.len() {
                    0 => num(0),
                    1 => parts[0].clone(),
                    _ => Int::add(&parts),
                }
            }
            Term::Count(of, plus) => {
                let mut parts: Vec<Int> = of.iter().map(|b| ite_int(b, &num(1), &num(0))).collect();
                if *plus != 0 {
                    parts.push(num(*plus));
                }
                match parts.len() {
                    0 => num(0),
                    1 => parts[0].clone(),
                    _ => Int::add(&parts),
                }
            }
        }
    }

    /// The value as a condition (an integer is true when it is not 0).
    pub fn bool_term(&self) -> Bool {
        if let Some(v) = self.constant() {
            return Bool::from_bool(v != 0);
        }
        match &self.term {
            Term::B(b) => b.clone(),
            Term::I(x) => not(&eq_num(x, 0)),
            Term::Bits(bits) => or(bits.iter().cloned()),
            Term::Count(of, plus) => count_cmp(of, *plus, BinOp::Ne, 0),
        }
    }

    /// `self == v`, as literals where possible.
    pub fn eq_const(&self, v: i64) -> Bool {
        if i128::from(v) < self.lo || i128::from(v) > self.hi {
            return ff();
        }
        if let Some(k) = self.constant() {
            return Bool::from_bool(k == v);
        }
        match &self.term {
            Term::I(x) => eq_num(x, v),
            Term::B(b) => match v {
                0 => not(b),
                _ => b.clone(),
            },
            Term::Bits(bits) => {
                and(bits.iter().enumerate().map(
                    |(k, b)| {
                        if v >> k & 1 == 1 {
                            b.clone()
                        } else {
                            not(b)
                        }
                    },
                ))
            }
            Term::Count(of, plus) => count_cmp(of, *plus, BinOp::Eq, v),
        }
    }

    /// The value's `width` bits (a constant or a binary term).
    pub fn bits(&self, width: usize) -> Vec<Bool> {
        if let Some(v) = self.constant() {
            return (0..width)
                .map(|k| Bool::from_bool(v >> k & 1 == 1))
                .collect();
        }
        match &self.term {
            Term::Bits(b) => b.clone(),
            Term::B(b) => {
                let mut out = vec![b.clone()];
                out.resize(width.max(1), ff());
                out
            }
            // not expected: locations are binary or constant
            Term::Count(..) => {
                let x = self.int_term();
                (0..width)
                    .map(|k| eq_num(&x.div(num(1 << k)).modulo(num(2)), 1))
                    .collect()
            }
            Term::I(x) => (0..width)
                .map(|k| {
                    let bit = x.div(num(1 << k)).modulo(num(2));
                    eq_num(&bit, 1)
                })
                .collect(),
        }
    }

    fn is_bool(&self) -> bool {
        matches!(self.term, Term::B(_))
    }

    fn is_bits(&self) -> bool {
        matches!(self.term, Term::Bits(_))
    }

    fn with_err(mut self, err: Option<Bool>) -> Sym {
        self.err = err_or(self.err.take(), err);
        self
    }
}

/// Bits needed for the values `0..=hi`.
pub fn width(hi: i128) -> usize {
    (128 - hi.max(0).leading_zeros()) as usize
}

/// `c ? a : b` on values of either kind.
pub fn choose(c: &Bool, a: &Sym, b: &Sym) -> Sym {
    match lit(c) {
        Some(true) => return a.clone(),
        Some(false) => return b.clone(),
        None => {}
    }
    let (lo, hi) = (a.lo.min(b.lo), a.hi.max(b.hi));
    if (a.is_bits() || b.is_bits()) && lo >= 0 {
        let w = width(hi);
        let (x, y) = (a.bits(w), b.bits(w));
        let bits = x.iter().zip(&y).map(|(p, q)| ite_bool(c, p, q)).collect();
        return Sym::of_bits(bits, lo, hi);
    }
    if a.is_bool() && b.is_bool() {
        let mut s = Sym::of_bool(ite_bool(c, &a.bool_term(), &b.bool_term()));
        s.lo = s.lo.max(lo);
        s.hi = s.hi.min(hi);
        s
    } else {
        Sym::of_int(ite_int(c, &a.int_term(), &b.int_term()), lo, hi)
    }
}

/// A choice among `0..n` in binary: one fresh `Bool` per bit.
#[derive(Clone, Debug)]
pub struct Choice {
    pub bits: Vec<Bool>,
}

impl Choice {
    /// A choice among at most `n` values, named `name.k` per bit.
    pub fn fresh(name: &str, n: usize) -> Choice {
        let w = width(n.saturating_sub(1) as i128);
        Choice {
            bits: (0..w)
                .map(|k| Bool::new_const(format!("{name}.{k}")))
                .collect(),
        }
    }

    /// The choice is `k`.
    pub fn is(&self, k: i64) -> Bool {
        if k < 0 || (self.bits.len() < 63 && k >> self.bits.len() != 0) {
            return ff();
        }
        and(self.bits.iter().enumerate().map(
            |(i, b)| {
                if k >> i & 1 == 1 {
                    b.clone()
                } else {
                    not(b)
                }
            },
        ))
    }

    /// The choice is below `n`.
    pub fn below(&self, n: u64) -> Bool {
        lt_const(&self.bits, n)
    }
}

/// The binary number `bits` (least significant first) is below `n`.
pub fn lt_const(bits: &[Bool], n: u64) -> Bool {
    if bits.len() < 64 && n >> bits.len() != 0 {
        return tt();
    }
    // comparing from the least significant bit up: below(k) says bits 0..=k are below n's
    let mut below = ff();
    for (k, b) in bits.iter().enumerate() {
        below = if n >> k & 1 == 1 {
            or2(&not(b), &below)
        } else {
            and2(&not(b), &below)
        };
    }
    below
}
