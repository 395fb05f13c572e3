//! The translation of compiled expressions into symbolic values, with the same failures
//! and short-circuit rules as `bip_model::eval`.

use bip_model::eval::{Expr, MAX_QUANT_DEPTH};
use bip_model::ops::{BinOp, QuantKind};
use z3::ast::Bool;

use super::arith::arith;
use super::formula::{and, and2, eq_num, err_or, err_when, implies, lit, not, or, or2, tt};
use super::{choose, Sym, Term, I64_MAX, I64_MIN};

/// Where expression translation reads state slots.
pub trait Slots {
    fn slot(&self, slot: u32) -> Sym;
}

/// Translates a compiled expression evaluated with slot base `base` (for `Local` reads).
pub fn translate(e: &Expr, slots: &dyn Slots, base: u32) -> Sym {
    translate_in_step(e, slots, base, None)
}

/// Translates an expression of a step's action, where `advance` reads the step's time
/// units (1 if `advance` is None).
pub fn translate_in_step(e: &Expr, slots: &dyn Slots, base: u32, advance: Option<&Sym>) -> Sym {
    let mut bound = [0i64; MAX_QUANT_DEPTH];
    Translator {
        slots,
        base,
        advance,
    }
    .expr(e, &mut bound)
}

struct Translator<'a> {
    slots: &'a dyn Slots,
    base: u32,
    advance: Option<&'a Sym>,
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
            // a step's advance was checked before its action runs: no error of its own
            Expr::Advance => self.advance.map_or_else(
                || Sym::int(1),
                |a| Sym {
                    err: None,
                    ..a.clone()
                },
            ),
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

/// `v == loc` for a location slot's value.
fn at(v: &Sym, loc: u32) -> Sym {
    Sym::of_bool(v.eq_const(i64::from(loc))).with_err(v.err.clone())
}
