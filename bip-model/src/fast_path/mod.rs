//! Flat forms of the guards and actions the step relation evaluates most often.
//!
//! Most guards a model (and every GenoM expansion) writes are conjunctions of tests of one
//! slot against a constant: a flag (`!paused`), a location (`antenna@ether`), a bound
//! (`level > RESERVE`). Most assignments write a constant, a slot, or a slot plus a
//! constant. Walking the expression tree for these costs several times the test itself,
//! so they are compiled once, with the system, into the flat forms below. The other
//! expressions without families or quantifiers (a GenoM tick's `paused && n % 2 != 0`,
//! `age < 3 ? age + 1 : 3`) are tabulated when the slots they read take few values in all
//! (a flag and a counter modulo 2: four entries, each computed once by the tree), and
//! otherwise become code for a small stack machine; the rest keeps the tree ([`Expr`]). A
//! flat form means exactly what its expression means: tests cannot fail, and where a table
//! has no entry (the tree failed there) or stack code fails, the caller evaluates the tree,
//! which gives the error's details.
//!
//! This module holds the code's container ([`FlatCode`]), what a guard and an action
//! compile to, and the flat assignments; the forms themselves are in its submodules: the
//! conjunctions of tests (`guard`), the tables (`table`) and the stack machine (`stack`).

#[allow(unused_imports)]
use crate::prelude::*;

mod guard;
mod stack;
mod table;
#[cfg(test)]
mod tests;

use crate::eval::{EvalError, Expr};
use crate::model::{Assign, Target};
use crate::ops::BinOp;
use crate::radix::Digit;

use guard::{conjunction, read, Test};
use stack::{compile, Op};
use table::Table;

/// How a guard is evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum GuardCode {
    /// No guard, or one that folded to true.
    Always,
    /// Every test in `tests[start..end]` holds.
    Tests { start: u32, end: u32 },
    /// Stack code `ops[start..end]` computes a non-zero value.
    Code { start: u32, end: u32 },
    /// Table `tables[n]` holds a non-zero value.
    Table(u32),
    /// The expression tree.
    Tree,
}

/// The value an assignment writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Value {
    Const(i64),
    /// A slot plus a constant (0 for a copy).
    Offset {
        slot: u32,
        local: bool,
        add: i64,
    },
    /// Stack code `ops[start..end]`.
    Code {
        start: u32,
        end: u32,
    },
    /// Table `tables[n]`.
    Table(u32),
    /// The assignment's expression tree.
    Tree,
}

/// An assignment, in flat form if its value has one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct FlatAssign {
    target: Target,
    value: Value,
}

fn value_of(e: &Expr, code: &mut FlatCode, ranges: &Ranges<'_>) -> Value {
    let offset = |(slot, local): (u32, bool), add| Value::Offset { slot, local, add };
    let flat = match e {
        Expr::Const(v) => Some(Value::Const(*v)),
        Expr::Slot(_) | Expr::Local(_) => read(e).map(|r| offset(r, 0)),
        Expr::Binary(BinOp::Add, a, b) => match (read(a), &**b, &**a, read(b)) {
            (Some(r), Expr::Const(v), _, _) | (_, _, Expr::Const(v), Some(r)) => {
                Some(offset(r, *v))
            }
            _ => None,
        },
        // `x - v` as `x + (-v)` unless `-v` overflows
        Expr::Binary(BinOp::Sub, a, b) => match (read(a), &**b) {
            (Some(r), Expr::Const(v)) => v.checked_neg().map(|add| offset(r, add)),
            _ => None,
        },
        _ => None,
    };
    if let Some(v) = flat {
        return v;
    }
    if let Some(t) = code.tabulate(e, ranges) {
        return Value::Table(t);
    }
    match compile(e, &mut code.ops) {
        Some((start, end)) => Value::Code { start, end },
        None => Value::Tree,
    }
}

impl FlatAssign {
    /// The value written, if it is a constant.
    pub(crate) fn constant(&self) -> Option<i64> {
        match self.value {
            Value::Const(v) => Some(v),
            _ => None,
        }
    }

    /// The slot written.
    #[inline]
    pub(crate) fn slot(&self, base: u32) -> u32 {
        match self.target {
            Target::Local(n) => base + n,
            Target::Slot(s) => s,
        }
    }

    /// The slot written and the value, or the error the expression would give; `None` if
    /// the expression tree must be evaluated.
    #[inline]
    pub(crate) fn eval(
        &self,
        code: &FlatCode,
        slots: &[i64],
        base: u32,
    ) -> Option<Result<(u32, i64), EvalError>> {
        let value = match self.value {
            Value::Const(v) => v,
            Value::Offset { slot, local, add } => {
                let at = if local { base + slot } else { slot };
                match slots[at as usize].checked_add(add) {
                    Some(v) => v,
                    None => return Some(Err(EvalError::Overflow)),
                }
            }
            // on failure the tree tells which error
            Value::Code { start, end } => code.run(start, end, slots, base).ok()?,
            Value::Table(t) => code.lookup(t, slots, base)?,
            Value::Tree => return None,
        };
        Some(Ok((self.slot(base), value)))
    }
}

/// A value computed on a state (a time step's `advance`), in flat form if it has one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct ValueCode(Value);

impl ValueCode {
    /// The value on `slots`; `None` if the expression tree must be evaluated (it has no
    /// flat form, or fails: the tree says how).
    #[inline]
    pub(crate) fn eval(self, code: &FlatCode, slots: &[i64]) -> Option<i64> {
        match self.0 {
            Value::Const(v) => Some(v),
            Value::Offset { slot, add, .. } => slots[slot as usize].checked_add(add),
            Value::Code { start, end } => code.run(start, end, slots, 0).ok(),
            Value::Table(t) => code.lookup(t, slots, 0),
            Value::Tree => None,
        }
    }
}

/// Where an action's assignments are in [`FlatCode`], one per assignment in order, and
/// its table of the values they write, if it has one ([`NO_TABLE`] if not).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct ActionCode {
    start: u32,
    end: u32,
    table: u32,
}

/// An action without a table.
const NO_TABLE: u32 = u32::MAX;

impl ActionCode {
    /// True for an action without assignments (most transitions of a GenoM layer).
    #[inline(always)]
    pub(crate) fn is_empty(self) -> bool {
        self.start == self.end
    }

    /// True if a table holds the values the action writes ([`FlatCode::action_values`]).
    pub(crate) fn has_table(self) -> bool {
        self.table != NO_TABLE
    }
}

/// The ranges of the values an expression may read: the state's slots, and the variables
/// of the component whose transition it belongs to (read as [`Expr::Local`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ranges<'a> {
    pub slots: &'a [(i64, i64)],
    pub locals: &'a [(i64, i64)],
}

/// The flat forms of a system's guards and actions, in one table each.
#[derive(Clone, Debug, Default)]
pub(crate) struct FlatCode {
    tests: Vec<Test>,
    assigns: Vec<FlatAssign>,
    ops: Vec<Op>,
    tables: Vec<Table>,
    table_digits: Vec<Digit>,
    table_values: Vec<i64>,
    table_known: Vec<bool>,
    /// While the code is made: the state tables are computed on, one for every table
    /// (it has a slot per slot of the system, too many to allocate per table);
    /// [`FlatCode::done`] frees it.
    scratch: Vec<i64>,
}

impl FlatCode {
    /// Frees what only making the code needed.
    pub(crate) fn done(&mut self) {
        self.scratch = Vec::new();
    }

    pub(crate) fn guard(&mut self, guard: Option<&Expr>, ranges: &Ranges<'_>) -> GuardCode {
        let Some(e) = guard else {
            return GuardCode::Always;
        };
        let start = self.tests.len();
        if !conjunction(e, &mut self.tests) {
            self.tests.truncate(start);
            if let Some(t) = self.tabulate(e, ranges) {
                return GuardCode::Table(t);
            }
            return match compile(e, &mut self.ops) {
                Some((start, end)) => GuardCode::Code { start, end },
                None => GuardCode::Tree,
            };
        }
        if self.tests.len() == start {
            return GuardCode::Always;
        }
        GuardCode::Tests {
            start: start as u32,
            end: self.tests.len() as u32,
        }
    }

    /// A value's flat form (an expression read on the state alone, not a component's).
    pub(crate) fn value(&mut self, e: &Expr, ranges: &Ranges<'_>) -> ValueCode {
        ValueCode(value_of(e, self, ranges))
    }

    pub(crate) fn action(&mut self, action: &[Assign], ranges: &Ranges<'_>) -> ActionCode {
        let start = self.assigns.len() as u32;
        for a in action {
            let value = value_of(&a.value, self, ranges);
            self.assigns.push(FlatAssign {
                target: a.target,
                value,
            });
        }
        // an action of several assignments is tabulated as a whole, if it can be (one
        // assignment has its own table, if any)
        let table = match action.len() {
            0 | 1 => None,
            _ => self.tabulate_action(action, ranges),
        };
        ActionCode {
            start,
            end: self.assigns.len() as u32,
            table: table.unwrap_or(NO_TABLE),
        }
    }

    /// The verdict of a guard, or `None` if its tree must decide (it has no flat form,
    /// or its stack code failed and the tree gives the error's details).
    #[inline(always)]
    pub(crate) fn decide(&self, code: GuardCode, slots: &[i64], base: u32) -> Option<bool> {
        match code {
            GuardCode::Always => Some(true),
            GuardCode::Tests { start, end } => Some(self.all_hold(start, end, slots, base)),
            GuardCode::Code { start, end } => {
                self.run(start, end, slots, base).ok().map(|v| v != 0)
            }
            GuardCode::Table(t) => self.lookup(t, slots, base).map(|v| v != 0),
            GuardCode::Tree => None,
        }
    }

    /// True if every test of a [`GuardCode::Tests`] holds.
    #[inline]
    pub(crate) fn all_hold(&self, start: u32, end: u32, slots: &[i64], base: u32) -> bool {
        self.tests[start as usize..end as usize]
            .iter()
            .all(|t| t.holds(slots, base))
    }

    pub(crate) fn assigns(&self, code: ActionCode) -> &[FlatAssign] {
        &self.assigns[code.start as usize..code.end as usize]
    }
}
