//! Arithmetic on symbolic values: intervals computed as terms are built (constants fold,
//! overflow conditions vanish where the ranges exclude them), and the conditions under
//! which an operation overflows or divides by zero.

use bip_model::ops::BinOp;
use z3::ast::{Bool, Int};

use super::formula::{and, and2, eq_num, err_or, ff, iff, implies, ite_int, not, num, or, or2, tt};
use super::{width, Sym, Term, HUGE, I64_MAX, I64_MIN};

/// `count(of) + plus op k` as a pseudo-boolean constraint.
pub(super) fn count_cmp(of: &[Bool], plus: i64, op: BinOp, k: i64) -> Bool {
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
pub(super) fn arith(op: BinOp, a: &Sym, b: &Sym) -> Sym {
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
