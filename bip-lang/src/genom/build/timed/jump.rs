//! How far a timed model's tick jumps: to the next instant at which something other than
//! the passing of time may happen, so that an idle stretch of a period, or a codel's run
//! up to its BCET, is one step instead of one per unit. The next such instant is the
//! nearest of: a period boundary of any task, a tick of `tick_ms` at which ports age, the
//! BCET of a running codel (from there it may finish at any unit, so time then passes
//! one unit at a time), and the first unit past a ready or running job's deadline (so
//! that a miss is shown at its first unit). In between, only requests may happen, and a
//! request may come at the jump's either end, before any other step of that instant: what
//! a request does is seen only at the instant's steps (a release, a finish, a start),
//! none of which the jump passes over.

use super::{Builder, TimedTaskRef};
use crate::expr::{BinOp, Expr};
use crate::genom::names::*;
use crate::genom::timed::Timed;
use crate::genom::tree::{and, binary, cond, int, member, not};

/// The smaller of two unit counts.
fn min(a: Expr, b: Expr) -> Expr {
    cond(binary(BinOp::Lt, a.clone(), b.clone()), a, b)
}

/// The least of unit counts, as a balanced tree of `min`s: each `min` writes both its
/// operands twice, so a chain would grow as 2^n with n counts, a balanced tree as n^2
/// (RobNav's fifteen counts: 32,768 copies against 225).
fn least(mut counts: Vec<Expr>) -> Option<Expr> {
    if counts.len() <= 1 {
        return counts.pop();
    }
    let right = counts.split_off(counts.len() / 2);
    Some(min(least(counts)?, least(right)?))
}

impl<'a, 'd> Builder<'a, 'd> {
    /// The units the tick stands for, evaluated on the state it leaves; `None`: always
    /// one (a task of a one-unit period has a boundary at every unit).
    pub(super) fn time_jump(
        &self,
        t: &Timed,
        tasks: &[TimedTaskRef],
        ports_age: bool,
    ) -> Option<Expr> {
        if t.hyperperiod <= 1 || (ports_age && t.tick_units == 1) {
            return None;
        }
        let phase = member(CLOCK, PHASE);
        // `(d + p − 1 − n mod p) mod p + 1`: the units to the next instant ≡ d (mod p)
        let to_next = |p: u64, d: u64| {
            let r = binary(BinOp::Rem, phase.clone(), int(p as i64));
            let back = binary(BinOp::Sub, int((d + p - 1) as i64), r);
            binary(BinOp::Add, binary(BinOp::Rem, back, int(p as i64)), int(1))
        };
        if tasks.iter().any(|task| task.times.period == 1) {
            return None;
        }
        let mut candidates: Vec<Expr> = tasks
            .iter()
            .map(|task| to_next(task.times.period, task.times.delay))
            .collect();
        if ports_age {
            candidates.push(to_next(t.tick_units, 0));
        }
        let far = int(t.hyperperiod as i64);
        for task in tasks {
            let x = self.task_var(task, ELAPSED);
            // the running codel's BCET, else one unit (or none running: no bound)
            let mut codel_bound = far.clone();
            for (k, c) in task.codels.iter().enumerate().rev() {
                let bound = if c.bcet == 0 {
                    int(1)
                } else {
                    let bcet = int(c.bcet as i64);
                    cond(
                        binary(BinOp::Lt, x.clone(), bcet.clone()),
                        binary(BinOp::Sub, bcet, x.clone()),
                        int(1),
                    )
                };
                codel_bound = cond(self.codel_runs(t, task, k), bound, codel_bound);
            }
            candidates.push(codel_bound);
            // the first unit past the deadline of an active job not yet past it
            let elapsed = self.job_elapsed(task);
            let deadline = int(task.times.deadline as i64);
            let before = and(
                not(self.stage_is(task, STAGE_IDLE)),
                binary(BinOp::Le, elapsed.clone(), deadline.clone()),
            );
            let to_miss = binary(BinOp::Sub, binary(BinOp::Add, deadline, int(1)), elapsed);
            candidates.push(cond(before, to_miss, far.clone()));
        }
        least(candidates)
    }
}
