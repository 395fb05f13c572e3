//! A timed model's deadlines, as generated invariants: a task's job is never active
//! (ready or running) past its deadline. Together they decide `Schedulable` by
//! exploration: the first violated one's counterexample is the shortest run to a miss.

use super::Builder;
use crate::compile::budgets::show_us;
use crate::expr::BinOp;
use crate::genom::names::*;
use crate::genom::timed::Timed;
use crate::genom::tree::{binary, int, or};
use crate::source::Spanned;
use crate::syntax::{ExprDef, PropertyDef};

impl<'a, 'd> Builder<'a, 'd> {
    pub(in super::super) fn deadline_invariants(&self, t: &Timed) -> Vec<PropertyDef> {
        self.timed_task_list(t)
            .iter()
            .map(|task| {
                let (m, name) = self.task_names(task);
                let within = or(
                    self.stage_is(task, STAGE_IDLE),
                    binary(
                        BinOp::Le,
                        self.job_elapsed(task),
                        int(task.times.deadline as i64),
                    ),
                );
                let span = self.layer.modules[task.module].def.tasks[task.task]
                    .name
                    .span;
                PropertyDef::Invariant {
                    name: Spanned::new(
                        deadline_property(m, name, &show_us(task.times.deadline * t.unit_us)),
                        span,
                    ),
                    expr: ExprDef::Built(within),
                }
            })
            .collect()
    }
}
