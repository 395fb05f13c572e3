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

use bip_model::eval::{Expr, MAX_QUANT_DEPTH};
use bip_model::ops::{BinOp, QuantKind};
use z3::ast::{Bool, Int};

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

pub fn tt() -> Bool {
    Bool::from_bool(true)
}

pub fn ff() -> Bool {
    Bool::from_bool(false)
}

pub fn lit(b: &Bool) -> Option<bool> {
    b.as_bool()
}

pub fn num(v: i64) -> Int {
    Int::from_i64(v)
}

/// Conjunction, folding literals.
pub fn and(items: impl IntoIterator<Item = Bool>) -> Bool {
    let mut keep = Vec::new();
    for b in items {
        match lit(&b) {
            Some(true) => {}
            Some(false) => return ff(),
            None => keep.push(b),
        }
    }
    match keep.len() {
        0 => tt(),
        1 => keep.pop().unwrap_or_else(tt),
        _ => Bool::and(&keep),
    }
}

/// Disjunction, folding literals.
pub fn or(items: impl IntoIterator<Item = Bool>) -> Bool {
    let mut keep = Vec::new();
    for b in items {
        match lit(&b) {
            Some(false) => {}
            Some(true) => return tt(),
            None => keep.push(b),
        }
    }
    match keep.len() {
        0 => ff(),
        1 => keep.pop().unwrap_or_else(ff),
        _ => Bool::or(&keep),
    }
}

pub fn not(b: &Bool) -> Bool {
    match lit(b) {
        Some(v) => Bool::from_bool(!v),
        None => b.not(),
    }
}

pub fn implies(a: &Bool, b: &Bool) -> Bool {
    or([not(a), b.clone()])
}

pub fn and2(a: &Bool, b: &Bool) -> Bool {
    and([a.clone(), b.clone()])
}

pub fn or2(a: &Bool, b: &Bool) -> Bool {
    or([a.clone(), b.clone()])
}

pub fn iff(a: &Bool, b: &Bool) -> Bool {
    match (lit(a), lit(b)) {
        (Some(x), Some(y)) => Bool::from_bool(x == y),
        (Some(true), None) => b.clone(),
        (Some(false), None) => not(b),
        (None, Some(true)) => a.clone(),
        (None, Some(false)) => not(a),
        (None, None) => a.iff(b),
    }
}

pub fn ite_int(c: &Bool, a: &Int, b: &Int) -> Int {
    match lit(c) {
        Some(true) => a.clone(),
        Some(false) => b.clone(),
        None => {
            if a.as_i64().is_some() && a.as_i64() == b.as_i64() {
                a.clone()
            } else {
                c.ite(a, b)
            }
        }
    }
}

pub fn ite_bool(c: &Bool, a: &Bool, b: &Bool) -> Bool {
    match (lit(c), lit(a), lit(b)) {
        (Some(true), _, _) => a.clone(),
        (Some(false), _, _) => b.clone(),
        (_, Some(true), Some(true)) => tt(),
        (_, Some(false), Some(false)) => ff(),
        (_, Some(true), Some(false)) => c.clone(),
        (_, Some(false), Some(true)) => not(c),
        (_, Some(true), None) => or2(c, b),
        (_, Some(false), None) => and2(&not(c), b),
        (_, None, Some(true)) => or2(&not(c), a),
        (_, None, Some(false)) => and2(c, a),
        _ => c.ite(a, b),
    }
}

/// `x == v`, folded when `x` is a numeral.
pub fn eq_num(x: &Int, v: i64) -> Bool {
    match x.as_i64() {
        Some(k) => Bool::from_bool(k == v),
        None => x.eq(v),
    }
}

/// Either failure condition.
pub fn err_or(a: Option<Bool>, b: Option<Bool>) -> Option<Bool> {
    match (a, b) {
        (None, b) => b,
        (a, None) => a,
        (Some(a), Some(b)) => nonfalse(or2(&a, &b)),
    }
}

/// A failure condition that only counts when `cond` holds.
pub fn err_when(cond: &Bool, e: Option<Bool>) -> Option<Bool> {
    e.and_then(|e| nonfalse(and2(cond, &e)))
}

fn nonfalse(b: Bool) -> Option<Bool> {
    (lit(&b) != Some(false)).then_some(b)
}

/// A failure condition as a formula.
pub fn err_formula(e: &Option<Bool>) -> Bool {
    e.clone().unwrap_or_else(ff)
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

/// Where expression translation reads state slots.
pub trait Slots {
    fn slot(&self, slot: u32) -> Sym;
}

/// Translates a compiled expression evaluated with slot base `base` (for `Local` reads).
pub fn translate(e: &Expr, slots: &dyn Slots, base: u32) -> Sym {
    let mut bound = [0i64; MAX_QUANT_DEPTH];
    Translator { slots, base }.expr(e, &mut bound)
}

struct Translator<'a> {
    slots: &'a dyn Slots,
    base: u32,
}

impl Translator<'_> {
    fn expr(&self, e: &Expr, bound: &mut [i64; MAX_QUANT_DEPTH]) -> Sym {
        match e {
            Expr::Const(v) => Sym::int(*v),
            Expr::Slot(s) => self.slots.slot(*s),
            Expr::Local(n) => self.slots.slot(self.base + n),
            Expr::At(s, loc) => at(&self.slots.slot(*s), *loc),
            Expr::Indexed(ix) => {
                let i = self.expr(&ix.index, bound);
                let count = i128::from(ix.count);
                let member = |k: i64| {
                    let slot =
                        ix.first_slot as i64 + k * i64::from(ix.stride) + i64::from(ix.offset);
                    let v = self.slots.slot(slot as u32);
                    match ix.at {
                        Some(loc) => at(&v, loc),
                        None => v,
                    }
                };
                if let Some(k) = i.constant() {
                    if k < 0 || i128::from(k) >= count {
                        return Sym::failing();
                    }
                    return member(k);
                }
                let lo = i.lo.max(0);
                let hi = i.hi.min(count - 1);
                if lo > hi {
                    return Sym::failing().with_err(i.err);
                }
                let it = i.int_term();
                let out_of_range =
                    (i.lo < 0 || i.hi >= count).then(|| or([it.lt(0), it.ge(count as i64)]));
                let err = err_or(i.err.clone(), out_of_range);
                let members: Vec<(i64, Sym)> =
                    (lo as i64..=hi as i64).map(|k| (k, member(k))).collect();
                let mut out = members[members.len() - 1].1.clone();
                for (k, m) in members[..members.len() - 1].iter().rev() {
                    out = choose(&eq_num(&it, *k), m, &out);
                }
                out.with_err(err)
            }
            Expr::Bound(d) => Sym::int(bound[*d as usize]),
            Expr::Not(a) => {
                let a = self.expr(a, bound);
                let err = a.err.clone();
                Sym::of_bool(not(&a.bool_term())).with_err(err)
            }
            Expr::Neg(a) => {
                let a = self.expr(a, bound);
                let err = err_or(
                    a.err.clone(),
                    (a.lo <= I64_MIN).then(|| eq_num(&a.int_term(), i64::MIN)),
                );
                let t = a.int_term().unary_minus();
                Sym::of_int(t, (-a.hi).max(I64_MIN), (-a.lo).min(I64_MAX)).with_err(err)
            }
            Expr::Binary(op, a, b) => {
                let a = self.expr(a, bound);
                self.binary(*op, a, b, bound)
            }
            Expr::Chain(first, rest) => {
                let mut acc = self.expr(first, bound);
                for (op, x) in rest {
                    acc = self.binary(*op, acc, x, bound);
                }
                acc
            }
            Expr::Cond(c, a, b) => {
                let c = self.expr(c, bound);
                let cb = c.bool_term();
                match lit(&cb) {
                    Some(true) => self.expr(a, bound).with_err(c.err),
                    Some(false) => self.expr(b, bound).with_err(c.err),
                    None => {
                        let a = self.expr(a, bound);
                        let b = self.expr(b, bound);
                        let err = err_or(
                            c.err.clone(),
                            err_or(
                                err_when(&cb, a.err.clone()),
                                err_when(&not(&cb), b.err.clone()),
                            ),
                        );
                        choose(&cb, &a, &b).with_err(err)
                    }
                }
            }
            Expr::Quant(q) => self.quant(q, bound),
        }
    }

    /// `a op b`, with `a` already translated.
    fn binary(&self, op: BinOp, a: Sym, b: &Expr, bound: &mut [i64; MAX_QUANT_DEPTH]) -> Sym {
        match op {
            // short-circuit operators evaluate `b` only when needed, so its failure counts
            // only then
            BinOp::And | BinOp::Or | BinOp::Implies => {
                let av = a.bool_term();
                let needs_b = match op {
                    BinOp::Or => not(&av),
                    _ => av.clone(),
                };
                if lit(&needs_b) == Some(false) {
                    let v = !matches!(op, BinOp::And);
                    return Sym::boolean(v).with_err(a.err);
                }
                let b = self.expr(b, bound);
                let bv = b.bool_term();
                let v = match op {
                    BinOp::And => and2(&av, &bv),
                    BinOp::Or => or2(&av, &bv),
                    _ => implies(&av, &bv),
                };
                let err = err_or(a.err.clone(), err_when(&needs_b, b.err.clone()));
                Sym::of_bool(v).with_err(err)
            }
            _ => {
                let b = self.expr(b, bound);
                let err = err_or(a.err.clone(), b.err.clone());
                arith(op, &a, &b).with_err(err)
            }
        }
    }

    fn quant(&self, q: &bip_model::eval::Quant, bound: &mut [i64; MAX_QUANT_DEPTH]) -> Sym {
        let d = q.depth as usize;
        let mut bodies = Vec::new();
        for i in q.lo..q.hi {
            bound[d] = i;
            bodies.push(self.expr(&q.body, bound));
        }
        match q.kind {
            QuantKind::Forall | QuantKind::Exists => {
                let forall = q.kind == QuantKind::Forall;
                // evaluation stops at the first body that decides: a failure counts only if
                // every body before it was evaluated and did not decide
                let mut undecided = tt();
                let mut err: Option<Bool> = None;
                let mut vals = Vec::with_capacity(bodies.len());
                for b in &bodies {
                    let v = b.bool_term();
                    err = err_or(err, err_when(&undecided, b.err.clone()));
                    let goes_on = if forall { v.clone() } else { not(&v) };
                    undecided = and2(&undecided, &goes_on);
                    vals.push(v);
                    if lit(&undecided) == Some(false) {
                        break;
                    }
                }
                let v = if forall { and(vals) } else { or(vals) };
                Sym::of_bool(v).with_err(err)
            }
            QuantKind::Sum => {
                let mut acc = Sym::int(0);
                let mut err = None;
                for b in &bodies {
                    err = err_or(err, b.err.clone());
                    acc = arith(BinOp::Add, &acc, b);
                    err = err_or(err, acc.err.take());
                }
                acc.with_err(err)
            }
            QuantKind::Count => {
                let mut terms = Vec::new();
                let mut err = None;
                let mut lo = 0i128;
                for b in &bodies {
                    err = err_or(err, b.err.clone());
                    let v = b.bool_term();
                    match lit(&v) {
                        Some(true) => lo += 1,
                        Some(false) => {}
                        None => terms.push(v),
                    }
                }
                let hi = lo + terms.len() as i128;
                if terms.is_empty() {
                    return Sym::int(lo as i64).with_err(err);
                }
                Sym {
                    term: Term::Count(std::rc::Rc::new(terms), lo as i64),
                    lo,
                    hi,
                    err: None,
                }
                .with_err(err)
            }
        }
    }
}

/// `count(of) + plus op k` as a pseudo-boolean constraint.
fn count_cmp(of: &[Bool], plus: i64, op: BinOp, k: i64) -> Bool {
    let n = of.len() as i64;
    let k = k - plus;
    // decide on the bounds 0..=n first; pseudo-boolean bounds are i32
    let (lo_ok, hi_ok) = match op {
        BinOp::Eq => (k >= 0 && k <= n, true),
        BinOp::Ne => (true, true),
        BinOp::Le => (k >= 0, k < n),
        BinOp::Lt => (k > 0, k <= n),
        BinOp::Ge => (k <= n, k > 0),
        BinOp::Gt => (k < n, k >= 0),
        _ => (true, true),
    };
    let fits = i32::try_from(k).is_ok() && i32::try_from(n).is_ok();
    let weighted: Vec<(&Bool, i32)> = of.iter().map(|b| (b, 1)).collect();
    match op {
        BinOp::Eq if !lo_ok => ff(),
        BinOp::Ne if !(k >= 0 && k <= n) => tt(),
        BinOp::Le | BinOp::Lt if !lo_ok => ff(),
        BinOp::Le | BinOp::Lt if !hi_ok => tt(),
        BinOp::Ge | BinOp::Gt if !lo_ok => ff(),
        BinOp::Ge | BinOp::Gt if !hi_ok => tt(),
        _ if !fits => {
            // out of pseudo-boolean range: plain arithmetic
            let parts: Vec<Int> = of.iter().map(|b| ite_int(b, &num(1), &num(0))).collect();
            let sum = Int::add(&parts);
            match op {
                BinOp::Eq => sum.eq(k),
                BinOp::Ne => not(&sum.eq(k)),
                BinOp::Le => sum.le(k),
                BinOp::Lt => sum.lt(k),
                BinOp::Ge => sum.ge(k),
                _ => sum.gt(k),
            }
        }
        BinOp::Eq => Bool::pb_eq(&weighted, k as i32),
        BinOp::Ne => not(&Bool::pb_eq(&weighted, k as i32)),
        BinOp::Le => Bool::pb_le(&weighted, k as i32),
        BinOp::Lt => Bool::pb_le(&weighted, k as i32 - 1),
        BinOp::Ge => Bool::pb_ge(&weighted, k as i32),
        _ => Bool::pb_ge(&weighted, k as i32 + 1),
    }
}

/// `v == loc` for a location slot's value.
fn at(v: &Sym, loc: u32) -> Sym {
    Sym::of_bool(v.eq_const(i64::from(loc))).with_err(v.err.clone())
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

fn clamp(v: i128) -> i128 {
    v.clamp(-HUGE, HUGE)
}

/// An integer result with interval `lo..=hi` (mathematical): outside i64 it overflows.
fn checked(t: Int, lo: i128, hi: i128) -> Sym {
    let (lo, hi) = (clamp(lo), clamp(hi));
    if lo > I64_MAX || hi < I64_MIN {
        return Sym::failing();
    }
    let overflow = (lo < I64_MIN || hi > I64_MAX).then(|| or([t.lt(i64::MIN), t.gt(i64::MAX)]));
    let mut s = Sym::of_int(t, lo.max(I64_MIN), hi.min(I64_MAX));
    s.err = overflow;
    s
}

/// The non-short-circuit operators, on values that did not fail (the caller adds their
/// failure conditions).
fn arith(op: BinOp, a: &Sym, b: &Sym) -> Sym {
    if let (Some(x), Some(y)) = (a.constant(), b.constant()) {
        return match bip_model::eval::binary(op, x, y) {
            Ok(v) => match op {
                BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne => {
                    Sym::boolean(v != 0)
                }
                _ => Sym::int(v),
            },
            Err(_) => Sym::failing(),
        };
    }
    match op {
        BinOp::Eq | BinOp::Ne => {
            let eq = if a.is_bool() && b.is_bool() {
                iff(&a.bool_term(), &b.bool_term())
            } else if a.hi < b.lo || b.hi < a.lo {
                ff()
            } else if let Some(k) = b.constant() {
                a.eq_const(k)
            } else if let Some(k) = a.constant() {
                b.eq_const(k)
            } else if a.is_bits() && b.is_bits() {
                let w = width(a.hi.max(b.hi));
                and(a.bits(w).iter().zip(&b.bits(w)).map(|(x, y)| iff(x, y)))
            } else {
                a.int_term().eq(b.int_term())
            };
            Sym::of_bool(if op == BinOp::Eq { eq } else { not(&eq) })
        }
        BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge
            if matches!(a.term, Term::Count(..)) && b.constant().is_some() =>
        {
            let (Term::Count(of, plus), Some(k)) = (&a.term, b.constant()) else {
                unreachable!("checked by the guard")
            };
            Sym::of_bool(count_cmp(of, *plus, op, k))
        }
        BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge
            if matches!(b.term, Term::Count(..)) && a.constant().is_some() =>
        {
            let (Term::Count(of, plus), Some(k)) = (&b.term, a.constant()) else {
                unreachable!("checked by the guard")
            };
            // k op count  <=>  count op' k
            let flipped = match op {
                BinOp::Lt => BinOp::Gt,
                BinOp::Le => BinOp::Ge,
                BinOp::Gt => BinOp::Lt,
                _ => BinOp::Le,
            };
            Sym::of_bool(count_cmp(of, *plus, flipped, k))
        }
        BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge => {
            // decide on the intervals when they do not overlap
            let (x, y) = (a.int_term(), b.int_term());
            let known = match op {
                BinOp::Lt => decide(a.hi < b.lo, a.lo >= b.hi),
                BinOp::Le => decide(a.hi <= b.lo, a.lo > b.hi),
                BinOp::Gt => decide(a.lo > b.hi, a.hi <= b.lo),
                _ => decide(a.lo >= b.hi, a.hi < b.lo),
            };
            Sym::of_bool(known.map(Bool::from_bool).unwrap_or_else(|| match op {
                BinOp::Lt => x.lt(&y),
                BinOp::Le => x.le(&y),
                BinOp::Gt => x.gt(&y),
                _ => x.ge(&y),
            }))
        }
        BinOp::Add => checked(
            Int::add(&[a.int_term(), b.int_term()]),
            a.lo + b.lo,
            a.hi + b.hi,
        ),
        BinOp::Sub => checked(
            Int::sub(&[a.int_term(), b.int_term()]),
            a.lo - b.hi,
            a.hi - b.lo,
        ),
        BinOp::Mul => {
            let c = [a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi];
            let lo = c.iter().copied().min().unwrap_or(0);
            let hi = c.iter().copied().max().unwrap_or(0);
            checked(Int::mul(&[a.int_term(), b.int_term()]), lo, hi)
        }
        BinOp::Div | BinOp::Rem => division(op, a, b),
        BinOp::And | BinOp::Or | BinOp::Implies => {
            let (x, y) = (a.bool_term(), b.bool_term());
            Sym::of_bool(match op {
                BinOp::And => and2(&x, &y),
                BinOp::Or => or2(&x, &y),
                _ => implies(&x, &y),
            })
        }
    }
}

fn decide(yes: bool, no: bool) -> Option<bool> {
    if yes {
        Some(true)
    } else if no {
        Some(false)
    } else {
        None
    }
}

/// Truncated division and remainder (Rust's `/` and `%`), with their failures: a zero
/// divisor, and `i64::MIN / -1` (and `% -1`), which overflow.
fn division(op: BinOp, a: &Sym, b: &Sym) -> Sym {
    let (x, y) = (a.int_term(), b.int_term());
    let zero = (b.lo <= 0 && b.hi >= 0).then(|| eq_num(&y, 0));
    let min_by_minus_one = (a.lo <= I64_MIN && b.lo <= -1 && b.hi >= -1)
        .then(|| and([eq_num(&x, i64::MIN), eq_num(&y, -1)]));
    let err = err_or(zero, min_by_minus_one);
    let amax = a.lo.abs().max(a.hi.abs());
    let bmax = b.lo.abs().max(b.hi.abs());
    let (t, lo, hi) = if op == BinOp::Div {
        let t = if a.lo >= 0 && b.lo > 0 {
            x.div(&y)
        } else {
            // z3's div is Euclidean; truncate by dividing magnitudes
            let ax = ite_int(&x.ge(0), &x, &x.unary_minus());
            let ay = ite_int(&y.ge(0), &y, &y.unary_minus());
            let q = ax.div(&ay);
            let same_sign = iff(&x.ge(0), &y.gt(0));
            ite_int(&same_sign, &q, &q.unary_minus())
        };
        let (lo, hi) = if a.lo >= 0 && b.lo > 0 {
            (a.lo / b.hi.max(1), a.hi / b.lo.max(1))
        } else {
            (-amax, amax)
        };
        (t, lo, hi)
    } else {
        let m = bmax.saturating_sub(1).max(0);
        let t = if a.lo >= 0 {
            x.modulo(&y)
        } else {
            // the remainder takes the sign of the dividend
            let r = x.unary_minus().modulo(&y);
            ite_int(&x.ge(0), &x.modulo(&y), &r.unary_minus())
        };
        let lo = if a.lo >= 0 { 0 } else { -m.min(amax) };
        let hi = if a.hi <= 0 { 0 } else { m.min(amax) };
        (t, lo, hi)
    };
    let mut s = Sym::of_int(t, lo.max(I64_MIN), hi.min(I64_MAX));
    s.err = err;
    s
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
