//! When a task loses its core before its job is done (docs/model.md, "Preemption"): on a
//! CPU with `preemption: Codel`, a running task between two codels of its job gives its
//! core to a more urgent ready task for which no core is free (each such task, at its
//! first codel boundary: eager); on a CPU with `preemption: Preemptive`, the ready task
//! that comes first takes at once the core of the least urgent running task, if it is
//! more urgent, whose codel then waits with its elapsed time (unless that codel has run
//! its WCET, or the task's job has no work left: it finishes, or ends, first). Both are
//! zero-time steps, before time passes (`priorities.rs`).

use super::order::Urgency;
use super::{Builder, TimedTaskRef};
use crate::expr::{BinOp, Expr};
use crate::genom::names::*;
use crate::genom::timed::Timed;
use crate::genom::tree::{all, and, assign, binary, chain, int, member, not};
use crate::syntax::{Preemption, Role};

use super::super::{connector, port};

const YIELD: &str = "yield";
const PREEMPT: &str = "preempt";
const PREEMPTED: &str = "preempted";

/// The ports a task atom has for losing its core, besides those of every task.
pub(super) fn preemption_ports(p: Preemption) -> &'static [&'static str] {
    match p {
        Preemption::Job => &[],
        Preemption::Codel => &[YIELD],
        Preemption::Preemptive => &[PREEMPT, PREEMPTED],
    }
}

impl<'a, 'd> Builder<'a, 'd> {
    /// When the task's CPU lets it lose its core.
    pub(super) fn preemption(&self, t: &Timed, task: &TimedTaskRef) -> Preemption {
        t.preemption
            .get(task.times.cpu as usize)
            .copied()
            .unwrap_or(Preemption::Job)
    }

    /// The steps by which the task loses its core: its yield between two codels
    /// (`Codel`), or its preemption by each task that may take its core (`Preemptive`).
    pub(super) fn preemptions(&mut self, t: &Timed, task: &TimedTaskRef, tasks: &[TimedTaskRef]) {
        match self.preemption(t, task) {
            Preemption::Job => {}
            Preemption::Codel => self.yield_core(t, task, tasks),
            Preemption::Preemptive => {
                for by in tasks.iter().filter(|by| by.competes(task)) {
                    self.preempt(t, by, task, tasks);
                }
            }
        }
    }

    /// `u` is ready with no core free for it, and more urgent than `task` (`None`: never).
    fn waits_on(
        &self,
        t: &Timed,
        u: &TimedTaskRef,
        task: &TimedTaskRef,
        tasks: &[TimedTaskRef],
    ) -> Option<Expr> {
        let urgent = match self.urgency(t, u, task) {
            Urgency::Never => return None,
            Urgency::Always => None,
            Urgency::When(e) => Some(e),
        };
        // with a core for each, it never waits
        let busy = not(self.core_free(t, u, tasks)?);
        all([self.stage_is(u, STAGE_READY), busy]
            .into_iter()
            .chain(urgent))
    }

    /// Between two codels (none holds the core), the task gives its core to a more urgent
    /// ready task that waits for one (its job end comes first if it has no work left, and
    /// it comes before the start of its next codel: `priorities.rs`).
    fn yield_core(&mut self, t: &Timed, task: &TimedTaskRef, tasks: &[TimedTaskRef]) {
        let Some(waiting) = chain(
            BinOp::Or,
            tasks
                .iter()
                .filter(|u| u.competes(task))
                .filter_map(|u| self.waits_on(t, u, task, tasks)),
        ) else {
            return;
        };
        let comp = self.task_comp(task);
        let guard = all([
            self.stage_is(task, STAGE_RUNNING),
            binary(BinOp::Eq, member(&comp, RUNNING_CODEL), int(0)),
            waiting,
        ]);
        let (m, name) = self.task_names(task);
        let span = self.layer.modules[task.module].def.tasks[task.task]
            .name
            .span;
        let c = yield_connector(m, name);
        self.claim(&c, span, format!("the yield of task `{m}.{name}`"));
        self.connectors.push((
            connector(&c, vec![port(&comp, YIELD)], Role::Progress),
            guard,
            vec![assign(member(&comp, STAGE), int(STAGE_READY))],
        ));
    }

    /// Ready task `by` takes the core of running task `task`: `by` comes first among the
    /// ready tasks (under fixed priorities by the preemptions' priorities, `priorities.rs`),
    /// no core is free for it, it is more urgent than `task`, `task` is the least urgent of
    /// the running tasks competing with it, and `task`'s codel has not run its WCET.
    fn preempt(
        &mut self,
        t: &Timed,
        by: &TimedTaskRef,
        task: &TimedTaskRef,
        tasks: &[TimedTaskRef],
    ) {
        let Some(waiting) = self.waits_on(t, by, task, tasks) else {
            return;
        };
        let mut guard = vec![waiting, self.stage_is(task, STAGE_RUNNING)];
        guard.extend(self.first_ready(t, by, tasks));
        // no running competitor comes after `task`
        for v in tasks.iter().filter(|v| v.competes(task) && v.competes(by)) {
            let running = self.stage_is(v, STAGE_RUNNING);
            let later = match self.is_edf(t, task) {
                true => Some(and(running, self.edf_before(task, v))),
                false => (v.times.priority < task.times.priority).then_some(running),
            };
            guard.extend(later.map(not));
        }
        if let Some(done) = self.at_wcet(task) {
            guard.push(not(done));
        }
        let (bm, bn) = self.task_names(by);
        let (m, name) = self.task_names(task);
        let span = self.layer.modules[by.module].def.tasks[by.task].name.span;
        let c = preempt_connector(bm, bn, m, name);
        self.claim(
            &c,
            span,
            format!("the preemption of task `{m}.{name}` by `{bm}.{bn}`"),
        );
        let (by_comp, comp) = (self.task_comp(by), self.task_comp(task));
        self.connectors.push((
            connector(
                &c,
                vec![port(&by_comp, PREEMPT), port(&comp, PREEMPTED)],
                Role::Progress,
            ),
            all(guard),
            vec![
                assign(member(&by_comp, STAGE), int(STAGE_RUNNING)),
                assign(member(&comp, STAGE), int(STAGE_READY)),
            ],
        ));
    }
}
