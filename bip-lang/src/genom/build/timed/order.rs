//! The order of a CPU's tasks: which tasks compete for the same cores, which of two ready
//! tasks takes a free core first, and when a ready task is urgent enough to take a running
//! task's core (`preempt.rs`). Under fixed priorities the order is the tasks' `priority`,
//! static, and the dispatch's order among ready tasks is a chain of priorities
//! (`priorities.rs`); under EDF it is the absolute deadlines' (release + D, in the same
//! order as D − elapsed now), which changes with time, so it is written into guards.

use super::{Builder, TimedTaskRef};
use crate::expr::{BinOp, Expr};
use crate::genom::names::*;
use crate::genom::timed::Timed;
use crate::genom::tree::{and, binary, not};

/// Whether a ready task may take a running task's core.
pub(super) enum Urgency {
    /// Never: its fixed priority is not higher.
    Never,
    /// Always: its fixed priority is higher.
    Always,
    /// While this holds: its absolute deadline is strictly earlier (EDF).
    When(Expr),
}

impl TimedTaskRef<'_> {
    /// Two distinct tasks that compete for the same cores: the same CPU, pinned to the
    /// same core or both global.
    pub(super) fn competes(&self, other: &TimedTaskRef) -> bool {
        (self.module, self.task) != (other.module, other.task)
            && self.times.cpu == other.times.cpu
            && self.times.core == other.times.core
    }

    /// Declared before `other`.
    fn declared_before(&self, other: &TimedTaskRef) -> bool {
        (self.module, self.task) < (other.module, other.task)
    }
}

impl<'a, 'd> Builder<'a, 'd> {
    /// Whether the task's CPU orders its tasks by earliest deadline.
    pub(super) fn is_edf(&self, t: &Timed, task: &TimedTaskRef) -> bool {
        t.edf.get(task.times.cpu as usize).copied().unwrap_or(false)
    }

    /// Under EDF, `first` comes before `then`: an earlier absolute deadline, ties in
    /// declaration order.
    pub(super) fn edf_before(&self, first: &TimedTaskRef, then: &TimedTaskRef) -> Expr {
        let op = match first.declared_before(then) {
            true => BinOp::Le,
            false => BinOp::Lt,
        };
        binary(op, self.time_left(first), self.time_left(then))
    }

    /// Under EDF, no ready task competing with `task` comes before it: each a guard's
    /// conjunct (none under fixed priorities, whose order is the dispatch's priorities).
    pub(super) fn first_ready(
        &self,
        t: &Timed,
        task: &TimedTaskRef,
        tasks: &[TimedTaskRef],
    ) -> Vec<Expr> {
        if !self.is_edf(t, task) {
            return Vec::new();
        }
        tasks
            .iter()
            .filter(|other| other.competes(task))
            .map(|other| {
                not(and(
                    self.stage_is(other, STAGE_READY),
                    self.edf_before(other, task),
                ))
            })
            .collect()
    }

    /// When ready task `t` may take the core of running task `u`, which competes with it.
    pub(super) fn urgency(&self, timed: &Timed, t: &TimedTaskRef, u: &TimedTaskRef) -> Urgency {
        if self.is_edf(timed, t) {
            Urgency::When(binary(BinOp::Lt, self.time_left(t), self.time_left(u)))
        } else if t.times.priority > u.times.priority {
            Urgency::Always
        } else {
            Urgency::Never
        }
    }
}
