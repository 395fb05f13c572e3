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

#[allow(unused_imports)]
use crate::prelude::*;

use crate::eval::{binary, EvalError, Expr};
use crate::model::{Assign, Target};
use crate::ops::BinOp;
use crate::radix::{key, Digit, Digits};

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
    fn holds(&self, slots: &[i64], base: u32) -> bool {
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
fn read(e: &Expr) -> Option<(u32, bool)> {
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
fn conjunction(e: &Expr, out: &mut Vec<Test>) -> bool {
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

/// The most entries one table may have, and the most values all of a system's tables may
/// hold.
const MAX_TABLE: u64 = 1024;
const MAX_TABLE_VALUES: usize = 1 << 18;

/// A function of a few slots over every combination of their values: an expression's value
/// (`width` 1), or the values an action's assignments write (`width` of them). The entry of
/// key `k` (the digits `table_digits[digits]`) is `values[start + k × width..][..width]` if
/// `known[k]`; unknown where the expression fails or an assignment leaves its range.
#[derive(Clone, Copy, Debug)]
struct Table {
    digits: (u32, u32),
    start: u32,
    known: u32,
    width: u32,
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
        Expr::Indexed(_) | Expr::Bound(_) | Expr::Quant(_) => false,
        Expr::Not(a) | Expr::Neg(a) => reads(a, out),
        Expr::Binary(_, a, b) => reads(a, out) && reads(b, out),
        Expr::Chain(first, rest) => reads(first, out) && rest.iter().all(|(_, x)| reads(x, out)),
        Expr::Cond(c, a, b) => reads(c, out) && reads(a, out) && reads(b, out),
    }
}

impl FlatCode {
    /// Tabulates `e` over the values of the slots it reads, if they take at most
    /// [`MAX_TABLE`] combinations: each entry is what the tree computes there.
    fn tabulate(&mut self, e: &Expr, ranges: &Ranges<'_>) -> Option<u32> {
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
    fn tabulate_action(&mut self, action: &[Assign], ranges: &Ranges<'_>) -> Option<u32> {
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

    /// Frees what only making the code needed.
    pub(crate) fn done(&mut self) {
        self.scratch = Vec::new();
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

    /// Runs stack code `ops[start..end]`; `Err` if the expression fails (its tree says how).
    pub(crate) fn run(&self, start: u32, end: u32, slots: &[i64], base: u32) -> Result<i64, ()> {
        // compile() keeps every stack position below STACK; masking the positions tells
        // the compiler so, which drops the bounds checks of the inner loop
        const M: usize = STACK - 1;
        let mut stack = [0i64; STACK];
        let mut sp = 0usize;
        let mut pc = start as usize;
        while pc < end as usize {
            match self.ops[pc] {
                Op::Const(v) => {
                    stack[sp & M] = v;
                    sp += 1;
                }
                Op::Slot(s) => {
                    stack[sp & M] = slots[s as usize];
                    sp += 1;
                }
                Op::Local(n) => {
                    stack[sp & M] = slots[(base + n) as usize];
                    sp += 1;
                }
                Op::At(s, loc) => {
                    stack[sp & M] = (slots[s as usize] == i64::from(loc)) as i64;
                    sp += 1;
                }
                Op::Not => stack[(sp - 1) & M] = (stack[(sp - 1) & M] == 0) as i64,
                Op::Neg => stack[(sp - 1) & M] = stack[(sp - 1) & M].checked_neg().ok_or(())?,
                Op::Bool => stack[(sp - 1) & M] = (stack[(sp - 1) & M] != 0) as i64,
                Op::Bin(op) => {
                    sp -= 1;
                    let (a, b) = (stack[(sp - 1) & M], stack[sp & M]);
                    stack[(sp - 1) & M] = binary(op, a, b).map_err(|_| ())?;
                }
                Op::BinConst(op, b) => {
                    let a = stack[(sp - 1) & M];
                    stack[(sp - 1) & M] = binary(op, a, b).map_err(|_| ())?;
                }
                Op::And(to) => {
                    // a zero left operand is the result
                    if stack[(sp - 1) & M] == 0 {
                        pc = to as usize;
                        continue;
                    }
                    sp -= 1;
                }
                Op::Or(to) => {
                    if stack[(sp - 1) & M] != 0 {
                        stack[(sp - 1) & M] = 1;
                        pc = to as usize;
                        continue;
                    }
                    sp -= 1;
                }
                Op::Implies(to) => {
                    if stack[(sp - 1) & M] == 0 {
                        stack[(sp - 1) & M] = 1;
                        pc = to as usize;
                        continue;
                    }
                    sp -= 1;
                }
                Op::Else(to) => {
                    sp -= 1;
                    if stack[sp & M] == 0 {
                        pc = to as usize;
                        continue;
                    }
                }
                Op::Jump(to) => {
                    pc = to as usize;
                    continue;
                }
            }
            pc += 1;
        }
        Ok(stack[0])
    }
}

/// The deepest stack code may use (a power of two); deeper expressions keep their trees.
const STACK: usize = 16;

/// An instruction of the stack machine. Jumps are to absolute positions in `ops`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Op {
    Const(i64),
    Slot(u32),
    Local(u32),
    At(u32, u32),
    Not,
    Neg,
    /// The top as a boolean (0 or 1).
    Bool,
    /// Pops the right operand and replaces the left one by the result.
    Bin(BinOp),
    /// Replaces the top by the top `op` a constant (a right operand that is a constant).
    BinConst(BinOp, i64),
    /// `a && b`, `a || b`, `a => b` with `a` on top: jumps to the end with the result if
    /// `a` decides it, else pops `a` (then `b` and `Bool` follow).
    And(u32),
    Or(u32),
    Implies(u32),
    /// Pops the condition of `c ? a : b`; jumps to `b` if it is zero.
    Else(u32),
    Jump(u32),
}

/// Appends stack code for `e` to `ops`: its `(start, end)`, or `None` (nothing appended)
/// if `e` reads a family by index, has a quantifier, or needs too deep a stack.
fn compile(e: &Expr, ops: &mut Vec<Op>) -> Option<(u32, u32)> {
    let start = ops.len();
    if emit(e, ops, 1) {
        Some((start as u32, ops.len() as u32))
    } else {
        ops.truncate(start);
        None
    }
}

/// True if `e`'s value is always 0 or 1 (it needs no [`Op::Bool`]).
fn is_boolean(e: &Expr) -> bool {
    use BinOp::*;
    match e {
        Expr::Const(v) => *v == 0 || *v == 1,
        Expr::At(..) | Expr::Not(_) => true,
        Expr::Binary(op, _, _) => matches!(op, Lt | Le | Gt | Ge | Eq | Ne | And | Or | Implies),
        Expr::Chain(_, rest) => rest.iter().all(|(op, _)| matches!(op, And | Or)),
        _ => false,
    }
}

/// Emits code leaving the value of `e` at stack depth `depth`.
fn emit(e: &Expr, ops: &mut Vec<Op>, depth: usize) -> bool {
    if depth > STACK {
        return false;
    }
    let patch = |ops: &mut Vec<Op>, at: usize| {
        let to = ops.len() as u32;
        ops[at] = match ops[at] {
            Op::And(_) => Op::And(to),
            Op::Or(_) => Op::Or(to),
            Op::Implies(_) => Op::Implies(to),
            Op::Else(_) => Op::Else(to),
            Op::Jump(_) => Op::Jump(to),
            op => op,
        };
    };
    match e {
        Expr::Const(v) => ops.push(Op::Const(*v)),
        Expr::Slot(s) => ops.push(Op::Slot(*s)),
        Expr::Local(n) => ops.push(Op::Local(*n)),
        Expr::At(s, loc) => ops.push(Op::At(*s, *loc)),
        Expr::Indexed(_) | Expr::Bound(_) | Expr::Quant(_) => return false,
        Expr::Not(a) | Expr::Neg(a) => {
            if !emit(a, ops, depth) {
                return false;
            }
            ops.push(if matches!(e, Expr::Not(_)) {
                Op::Not
            } else {
                Op::Neg
            });
        }
        Expr::Binary(op @ (BinOp::And | BinOp::Or | BinOp::Implies), a, b) => {
            if !emit(a, ops, depth) {
                return false;
            }
            let at = ops.len();
            ops.push(match op {
                BinOp::And => Op::And(0),
                BinOp::Or => Op::Or(0),
                _ => Op::Implies(0),
            });
            if !emit(b, ops, depth) {
                return false;
            }
            if !is_boolean(b) {
                ops.push(Op::Bool);
            }
            patch(ops, at);
        }
        Expr::Binary(op, a, b) => {
            if !emit(a, ops, depth) {
                return false;
            }
            // a constant right operand goes into the instruction
            match **b {
                Expr::Const(c) => ops.push(Op::BinConst(*op, c)),
                _ => {
                    if !emit(b, ops, depth + 1) {
                        return false;
                    }
                    ops.push(Op::Bin(*op));
                }
            }
        }
        Expr::Chain(first, rest) => {
            if !emit(first, ops, depth) {
                return false;
            }
            for (op, x) in rest {
                if let BinOp::And | BinOp::Or = op {
                    let at = ops.len();
                    ops.push(if *op == BinOp::And {
                        Op::And(0)
                    } else {
                        Op::Or(0)
                    });
                    if !emit(x, ops, depth) {
                        return false;
                    }
                    if !is_boolean(x) {
                        ops.push(Op::Bool);
                    }
                    patch(ops, at);
                    continue;
                }
                match *x {
                    Expr::Const(c) => ops.push(Op::BinConst(*op, c)),
                    _ => {
                        if !emit(x, ops, depth + 1) {
                            return false;
                        }
                        ops.push(Op::Bin(*op));
                    }
                }
            }
        }
        Expr::Cond(c, a, b) => {
            if !emit(c, ops, depth) {
                return false;
            }
            let at_else = ops.len();
            ops.push(Op::Else(0));
            if !emit(a, ops, depth) {
                return false;
            }
            let at_jump = ops.len();
            ops.push(Op::Jump(0));
            patch(ops, at_else);
            if !emit(b, ops, depth) {
                return false;
            }
            patch(ops, at_jump);
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::Env;

    /// No ranges known: nothing is tabulated.
    const UNKNOWN: Ranges<'static> = Ranges {
        slots: &[],
        locals: &[],
    };

    fn b(e: Expr) -> Box<Expr> {
        Box::new(e)
    }

    /// Every state of two slots in -3..=3 (and the base 1 for locals).
    fn states() -> impl Iterator<Item = [i64; 3]> {
        (-3..=3).flat_map(|x| (-3..=3).map(move |y| [x, y, x - y]))
    }

    fn agrees(e: Expr) {
        let mut code = FlatCode::default();
        let GuardCode::Tests { start, end } = code.guard(Some(&e), &UNKNOWN) else {
            panic!("{e:?} has a flat form")
        };
        for s in states() {
            let tree = e.holds(&mut Env::new(&s, 1)).expect("evaluates");
            assert_eq!(code.all_hold(start, end, &s, 1), tree, "{e:?} in {s:?}");
        }
    }

    #[test]
    fn flat_guards_mean_what_their_trees_mean() {
        use Expr::*;
        for op in [
            BinOp::Eq,
            BinOp::Ne,
            BinOp::Lt,
            BinOp::Le,
            BinOp::Gt,
            BinOp::Ge,
        ] {
            agrees(Binary(op, b(Slot(0)), b(Const(1))));
            agrees(Binary(op, b(Const(-1)), b(Local(0))));
            agrees(Not(b(Binary(op, b(Local(1)), b(Const(0))))));
        }
        agrees(Slot(1));
        agrees(Not(b(Local(0))));
        agrees(Not(b(Not(b(Slot(0))))));
        agrees(At(0, 2));
        agrees(Not(b(At(1, 0))));
        agrees(Binary(
            BinOp::And,
            b(Binary(BinOp::And, b(Slot(0)), b(Const(1)))),
            b(Not(b(Slot(1)))),
        ));
    }

    #[test]
    fn other_guards_become_tables_or_stack_code() {
        use Expr::*;
        let mut code = FlatCode::default();
        let others = [
            Binary(BinOp::Or, b(Slot(0)), b(Slot(1))),
            Binary(BinOp::Lt, b(Slot(0)), b(Slot(1))),
            Binary(
                BinOp::And,
                b(Slot(0)),
                b(Binary(BinOp::Or, b(Slot(0)), b(Slot(1)))),
            ),
        ];
        // without the slots' ranges, stack code
        for e in &others {
            let g = code.guard(Some(e), &UNKNOWN);
            assert!(matches!(g, GuardCode::Code { .. }), "{e:?}: {g:?}");
        }
        // with them, tables
        let ranges = Ranges {
            slots: &[(0, 3), (0, 1)],
            locals: &[],
        };
        for e in &others {
            let g = code.guard(Some(e), &ranges);
            assert!(matches!(g, GuardCode::Table(_)), "{e:?}: {g:?}");
        }
        // a constant false guard reads nothing: a table of one entry
        let g = code.guard(Some(&Const(0)), &UNKNOWN);
        assert!(matches!(g, GuardCode::Table(_)), "{g:?}");
        assert_eq!(code.decide(g, &[], 0), Some(false));
        let quantified = Quant(Box::new(crate::eval::Quant {
            kind: crate::ops::QuantKind::Exists,
            lo: 0,
            hi: 2,
            depth: 0,
            body: Bound(0),
        }));
        assert_eq!(code.guard(Some(&quantified), &UNKNOWN), GuardCode::Tree);
        assert_eq!(code.guard(Some(&Const(1)), &UNKNOWN), GuardCode::Always);
        assert_eq!(code.guard(None, &UNKNOWN), GuardCode::Always);
    }

    #[test]
    fn flat_assignments_compute_what_their_trees_compute() {
        use Expr::*;
        let values = [
            Const(7),
            Slot(0),
            Local(1),
            Binary(BinOp::Add, b(Local(0)), b(Const(2))),
            Binary(BinOp::Add, b(Const(-2)), b(Slot(1))),
            Binary(BinOp::Sub, b(Slot(0)), b(Const(3))),
        ];
        for value in values {
            let mut code = FlatCode::default();
            let a = Assign {
                target: Target::Local(0),
                value: value.clone(),
            };
            let c = code.action(core::slice::from_ref(&a), &UNKNOWN);
            let flat = code.assigns(c)[0];
            for s in [[0, 5, -4], [i64::MAX, 1, i64::MIN], [i64::MIN, 0, i64::MAX]] {
                let tree = value.eval(&mut Env::new(&s, 1));
                let Some(r) = flat.eval(&code, &s, 1) else {
                    panic!("{value:?} has a flat form")
                };
                assert_eq!(r.map(|(_, v)| v), tree, "{value:?} in {s:?}");
                assert_eq!(flat.slot(1), 1, "the target, after the base");
            }
        }
        // `x - i64::MIN` has no flat form (its negation overflows), nor has `x * 2`
        let mut code = FlatCode::default();
        let action = [
            Assign {
                target: Target::Slot(0),
                value: Binary(BinOp::Sub, b(Slot(0)), b(Const(i64::MIN))),
            },
            Assign {
                target: Target::Slot(0),
                value: Binary(BinOp::Mul, b(Slot(0)), b(Const(2))),
            },
        ];
        let c = code.action(&action, &UNKNOWN);
        let ops = code.ops.len();
        assert!(code.assigns(c)[0].eval(&code, &[1], 0).is_none());
        assert!(matches!(code.assigns(c)[1].value, Value::Code { .. }) && ops > 0);
    }

    /// A random expression over slots 0..3 (locals from base 1), without families or
    /// quantifiers, with every operator.
    fn random_expr(rng: &mut crate::Rng, depth: u32) -> Expr {
        use Expr::*;
        if depth == 0 || rng.chance(25) {
            return match rng.below(4) {
                0 => Const(rng.range(-3, 3)),
                1 => Slot(rng.below(3) as u32),
                2 => Local(rng.below(2) as u32),
                _ => At(rng.below(3) as u32, rng.below(3) as u32),
            };
        }
        let ops = [
            BinOp::Mul,
            BinOp::Div,
            BinOp::Rem,
            BinOp::Add,
            BinOp::Sub,
            BinOp::Lt,
            BinOp::Le,
            BinOp::Gt,
            BinOp::Ge,
            BinOp::Eq,
            BinOp::Ne,
            BinOp::And,
            BinOp::Or,
            BinOp::Implies,
        ];
        let groups: [&[BinOp]; 4] = [
            &[BinOp::Add, BinOp::Sub],
            &[BinOp::Mul, BinOp::Div, BinOp::Rem],
            &[BinOp::And],
            &[BinOp::Or],
        ];
        match rng.below(6) {
            5 => {
                let group = groups[rng.below(groups.len())];
                let rest = (0..2 + rng.below(3))
                    .map(|_| (group[rng.below(group.len())], random_expr(rng, depth - 1)))
                    .collect();
                Chain(b(random_expr(rng, depth - 1)), rest)
            }
            0 => Not(b(random_expr(rng, depth - 1))),
            1 => Neg(b(random_expr(rng, depth - 1))),
            2 => Cond(
                b(random_expr(rng, depth - 1)),
                b(random_expr(rng, depth - 1)),
                b(random_expr(rng, depth - 1)),
            ),
            _ => Binary(
                ops[rng.below(ops.len())],
                b(random_expr(rng, depth - 1)),
                b(random_expr(rng, depth - 1)),
            ),
        }
    }

    #[test]
    fn stack_code_computes_what_the_tree_computes() {
        let mut rng = crate::Rng::new(7);
        let extremes = [i64::MIN, -1, 0, 1, 2, i64::MAX];
        let (mut failures, mut values) = (0, 0);
        for _ in 0..20_000 {
            let e = random_expr(&mut rng, 5);
            let mut code = FlatCode::default();
            let (start, end) = compile(&e, &mut code.ops).expect("no family, no quantifier");
            for _ in 0..8 {
                let mut s = [0i64; 3];
                for v in &mut s {
                    *v = if rng.chance(20) {
                        extremes[rng.below(extremes.len())]
                    } else {
                        rng.range(-2, 2)
                    };
                }
                let tree = e.eval(&mut Env::new(&s, 1));
                let run = code.run(start, end, &s, 1);
                assert_eq!(run.ok(), tree.ok(), "{e:?} in {s:?}");
                if tree.is_err() {
                    failures += 1;
                } else {
                    values += 1;
                }
            }
        }
        // both outcomes were exercised
        assert!(failures > 1_000 && values > 100_000, "{failures} {values}");
    }

    /// Slots 0..3 with small ranges, and locals from base 3 (the slots' count).
    const SMALL_SLOTS: [(i64, i64); 3] = [(-2, 2), (0, 1), (0, 2)];
    const SMALL_LOCALS: [(i64, i64); 2] = [(0, 1), (-1, 1)];
    const SMALL: Ranges<'static> = Ranges {
        slots: &SMALL_SLOTS,
        locals: &SMALL_LOCALS,
    };

    /// Every state of [`SMALL`]: the three slots, then the two locals.
    fn small_states() -> impl Iterator<Item = [i64; 5]> {
        (-2..=2).flat_map(|x| {
            (0..=1).flat_map(move |y| {
                (0..=2).flat_map(move |z| {
                    (0..=1).flat_map(move |l0| (-1..=1).map(move |l1| [x, y, z, l0, l1]))
                })
            })
        })
    }

    #[test]
    fn tables_hold_what_the_tree_computes() {
        let ranges = SMALL;
        let mut rng = crate::Rng::new(11);
        let (mut tabulated, mut failures, mut values, mut outside) = (0, 0, 0, 0);
        for _ in 0..5_000 {
            let e = random_expr(&mut rng, 4);
            let mut code = FlatCode::default();
            let Some(t) = code.tabulate(&e, &ranges) else {
                continue;
            };
            tabulated += 1;
            // every state in range: the table's entry, or none where the tree fails
            for s in small_states() {
                let tree = e.eval(&mut Env::new(&s, 3));
                assert_eq!(code.lookup(t, &s, 3), tree.ok(), "{e:?} in {s:?}");
                match tree {
                    Ok(_) => values += 1,
                    Err(_) => failures += 1,
                }
            }
            // outside the ranges, the tree decides
            if crate::radix::key(&code.table_digits, &[0, 0, 0, 0, 0], 3).is_some()
                && crate::radix::key(&code.table_digits, &[3, 0, 0, 0, 0], 3).is_none()
            {
                assert_eq!(code.lookup(t, &[3, 0, 0, 0, 0], 3), None, "{e:?}");
                outside += 1;
            }
        }
        assert!(tabulated > 2_000 && failures > 1_000 && values > 100_000);
        assert!(
            outside > 500,
            "only {outside} tables looked up outside their ranges"
        );
        // an expression over more combinations than a table may hold is not tabulated
        let wide = [(0, 1000), (0, 1000)];
        let e = Expr::Binary(BinOp::Mul, b(Expr::Slot(0)), b(Expr::Slot(1)));
        let ranges = Ranges {
            slots: &wide,
            locals: &[],
        };
        assert_eq!(FlatCode::default().tabulate(&e, &ranges), None);
        assert!(matches!(
            FlatCode::default().guard(Some(&e), &ranges),
            GuardCode::Code { .. }
        ));
    }

    #[test]
    fn action_tables_hold_what_the_assignments_write() {
        let (slots, locals, ranges) = (SMALL_SLOTS, SMALL_LOCALS, SMALL);
        let mut rng = crate::Rng::new(13);
        let (mut tabulated, mut failures, mut values) = (0, 0, 0);
        for _ in 0..3_000 {
            let n = 2 + rng.below(2);
            let action: Vec<Assign> = (0..n)
                .map(|_| Assign {
                    target: match rng.below(2) {
                        0 => Target::Slot(rng.below(3) as u32),
                        _ => Target::Local(rng.below(2) as u32),
                    },
                    value: random_expr(&mut rng, 3),
                })
                .collect();
            let mut code = FlatCode::default();
            let c = code.action(&action, &ranges);
            if c.table == NO_TABLE {
                continue;
            }
            tabulated += 1;
            for start in small_states() {
                // the assignments in order, each seeing the ones before
                let mut s = start;
                let mut want = Some(Vec::new());
                for a in &action {
                    let (at, (lo, hi)) = match a.target {
                        Target::Slot(k) => (k as usize, slots[k as usize]),
                        Target::Local(k) => (3 + k as usize, locals[k as usize]),
                    };
                    match a.value.eval(&mut Env::new(&s, 3)) {
                        Ok(v) if lo <= v && v <= hi => {
                            s[at] = v;
                            if let Some(w) = &mut want {
                                w.push(v);
                            }
                        }
                        _ => {
                            want = None;
                            break;
                        }
                    }
                }
                let got = code.action_values(c, &start, 3).map(<[i64]>::to_vec);
                assert_eq!(got, want, "{action:?} from {start:?}");
                match want {
                    Some(_) => values += 1,
                    None => failures += 1,
                }
            }
        }
        assert!(tabulated > 1_000 && failures > 10_000 && values > 10_000);
        // one assignment has no action table (its value has its own form)
        let one = [Assign {
            target: Target::Slot(0),
            value: Expr::Binary(BinOp::Mul, b(Expr::Slot(0)), b(Expr::Slot(1))),
        }];
        let mut code = FlatCode::default();
        assert_eq!(code.action(&one, &ranges).table, NO_TABLE);
    }
}
