//! Tables: an expression, or the values an action's assignments write, computed once by
//! the tree for every combination of the few slots it reads, then looked up.

use crate::prelude::*;

use crate::eval::Expr;
use crate::model::{Assign, Target};
use crate::radix::{key, Digits};

use super::{ActionCode, FlatCode, Ranges, NO_TABLE};

/// The most entries one table may have, and the most values all of a system's tables may
/// hold.
const MAX_TABLE: u64 = 1024;
const MAX_TABLE_VALUES: usize = 1 << 18;

/// A function of a few slots over every combination of their values: an expression's value
/// (`width` 1), or the values an action's assignments write (`width` of them). The entry of
/// key `k` (the digits `table_digits[digits]`) is `values[start + k × width..][..width]` if
/// `known[k]`; unknown where the expression fails or an assignment leaves its range.
#[derive(Clone, Copy, Debug)]
pub(super) struct Table {
    digits: (u32, u32),
    start: u32,
    known: u32,
    width: u32,
}

/// Appends the slots `e` reads (with repeats) to `out`; false if it reads a family by
/// index or has a quantifier.
fn reads(e: &Expr, out: &mut Vec<(u32, bool)>) -> bool {
    match e {
        Expr::Const(_) => true,
        Expr::Slot(s) | Expr::At(s, _) => {
            out.push((*s, false));
            true
        }
        Expr::Local(n) => {
            out.push((*n, true));
            true
        }
        Expr::Indexed(_) | Expr::Bound(_) | Expr::Quant(_) | Expr::Advance => false,
        Expr::Not(a) | Expr::Neg(a) => reads(a, out),
        Expr::Binary(_, a, b) => reads(a, out) && reads(b, out),
        Expr::Chain(first, rest) => reads(first, out) && rest.iter().all(|(_, x)| reads(x, out)),
        Expr::Cond(c, a, b) => reads(c, out) && reads(a, out) && reads(b, out),
    }
}

impl FlatCode {
    /// Tabulates `e` over the values of the slots it reads, if they take at most
    /// [`MAX_TABLE`] combinations: each entry is what the tree computes there.
    pub(super) fn tabulate(&mut self, e: &Expr, ranges: &Ranges<'_>) -> Option<u32> {
        let mut read = Vec::new();
        if !reads(e, &mut read) {
            return None;
        }
        self.tabulate_fn(&mut read, 1, ranges, |scratch, base, out| {
            match e.eval(&mut crate::eval::Env::new(scratch, base)) {
                Ok(v) => {
                    out.push(v);
                    true
                }
                Err(_) => false,
            }
        })
    }

    /// Tabulates the values an action's assignments write, in order, as a function of the
    /// slots they read before the action runs (an assignment sees the ones before it), if
    /// they take at most [`MAX_TABLE`] combinations. An entry is unknown where an
    /// assignment fails or leaves its target's range, so the action runs there and reports
    /// the error.
    pub(super) fn tabulate_action(
        &mut self,
        action: &[Assign],
        ranges: &Ranges<'_>,
    ) -> Option<u32> {
        let mut read = Vec::new();
        for a in action {
            if !reads(&a.value, &mut read) {
                return None;
            }
        }
        let targets: Vec<(usize, (i64, i64))> = action
            .iter()
            .map(|a| match a.target {
                Target::Local(n) => Some((
                    ranges.slots.len() + n as usize,
                    *ranges.locals.get(n as usize)?,
                )),
                Target::Slot(s) => Some((s as usize, *ranges.slots.get(s as usize)?)),
            })
            .collect::<Option<_>>()?;
        self.tabulate_fn(&mut read, action.len(), ranges, |scratch, base, out| {
            for (a, &(at, (lo, hi))) in action.iter().zip(&targets) {
                match a.value.eval(&mut crate::eval::Env::new(scratch, base)) {
                    Ok(v) if lo <= v && v <= hi => {
                        scratch[at] = v;
                        out.push(v);
                    }
                    _ => return false,
                }
            }
            true
        })
    }

    /// Tabulates `f` over the slots in `read`: for each combination of their values, set in
    /// a scratch state (the slots, then the component's variables from `base`), `f` pushes
    /// the entry's `width` values, or returns false where it has none.
    fn tabulate_fn(
        &mut self,
        read: &mut Vec<(u32, bool)>,
        width: usize,
        ranges: &Ranges<'_>,
        mut f: impl FnMut(&mut [i64], u32, &mut Vec<i64>) -> bool,
    ) -> Option<u32> {
        let d = Digits::new(read, |slot, local| match local {
            false => ranges.slots.get(slot as usize).copied(),
            true => ranges.locals.get(slot as usize).copied(),
        })?;
        let values = d.size.saturating_mul(width as u64);
        if d.size > MAX_TABLE
            || (self.table_values.len() as u64).saturating_add(values) > MAX_TABLE_VALUES as u64
        {
            return None;
        }
        let base = ranges.slots.len() as u32;
        let mut scratch = core::mem::take(&mut self.scratch);
        if scratch.len() < ranges.slots.len() + ranges.locals.len() {
            scratch.resize(ranges.slots.len() + ranges.locals.len(), 0);
        }
        let (start, known) = (self.table_values.len(), self.table_known.len());
        let mut entry = Vec::with_capacity(width);
        for key in 0..d.size {
            // every slot the function reads is set
            d.set(key, &mut scratch, base);
            entry.clear();
            let ok = f(&mut scratch, base, &mut entry) && entry.len() == width;
            entry.resize(width, 0);
            self.table_values.extend_from_slice(&entry);
            self.table_known.push(ok);
        }
        self.scratch = scratch;
        let digits_start = self.table_digits.len();
        self.table_digits.extend_from_slice(&d.digits);
        self.tables.push(Table {
            digits: (digits_start as u32, self.table_digits.len() as u32),
            start: start as u32,
            known: known as u32,
            width: width as u32,
        });
        Some(self.tables.len() as u32 - 1)
    }

    /// The entry of table `t` for the state, or `None` if it is unknown there (the tree or
    /// the assignments must compute it and report the error) or a slot is outside the
    /// range the table was made for.
    #[inline]
    fn entry(&self, t: u32, slots: &[i64], base: u32) -> Option<&[i64]> {
        let table = self.tables[t as usize];
        let digits = &self.table_digits[table.digits.0 as usize..table.digits.1 as usize];
        let key = key(digits, slots, base)?;
        if !self.table_known[(table.known as u64 + key) as usize] {
            return None;
        }
        let first = table.start as usize + key as usize * table.width as usize;
        Some(&self.table_values[first..first + table.width as usize])
    }

    /// The value expression table `t` holds for the state (see [`FlatCode::entry`]).
    #[inline]
    pub(crate) fn lookup(&self, t: u32, slots: &[i64], base: u32) -> Option<i64> {
        self.entry(t, slots, base).map(|v| v[0])
    }

    /// The values the assignments of an action with a table write in the state, in order
    /// (see [`FlatCode::entry`]).
    #[inline]
    pub(crate) fn action_values(
        &self,
        code: ActionCode,
        slots: &[i64],
        base: u32,
    ) -> Option<&[i64]> {
        match code.table {
            NO_TABLE => None,
            t => self.entry(t, slots, base),
        }
    }
}
