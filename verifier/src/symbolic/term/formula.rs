//! Formulas over z3 booleans and integers that fold literal operands as they are built, so
//! that formulas over a concrete state collapse to literals without asking the solver; and
//! the failure conditions of symbolic values, combined the same way.

use z3::ast::{Bool, Int};

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
