//! A timed model's generated priorities: what takes no time comes before time passes
//! (the boundaries' release, dispatches, codel starts, job ends, a pending activity's
//! interrupts; a codel's finish is not among them: between its BCET and its WCET it may
//! finish now or later, and the tick's guard keeps it from passing its WCET); a task's
//! codels start in GenoM3's order (its machine, then its activities in declaration
//! order); between two codels a task's yield to a more urgent one comes before its next
//! start, and its job's end before both; and among the ready tasks competing for a core,
//! the higher `priority` takes it, by dispatch or by preemption (on an EDF CPU, the
//! guards order them: `order.rs`). Steps of different tasks are not ordered otherwise: they run in parallel. Nor are
//! requests: a client's request may come at any moment, between any two steps of an
//! instant (docs/model.md, "Why whole units are enough").

use super::{Builder, TimedTaskRef};
use crate::genom::names::*;
use crate::genom::timed::Timed;
use crate::genom::tree::name;
use crate::syntax::{ExprDef, PriorityDef};

fn pr(low: &str, high: &str) -> PriorityDef {
    PriorityDef {
        low: ExprDef::Built(name(low)),
        high: ExprDef::Built(name(high)),
        when: None,
    }
}

impl<'a, 'd> Builder<'a, 'd> {
    /// A connector of that name has been generated (its name claimed).
    fn has_connector(&self, name: &str) -> bool {
        self.names.contains_key(name)
    }

    pub(in super::super) fn timed_priorities(&self, t: &Timed) -> Vec<PriorityDef> {
        let tasks = self.timed_task_list(t);
        let mut urgent: Vec<String> = Vec::new();
        for m in &self.recipe.modules {
            for s in &m.services {
                urgent.extend(s.interrupt.clone());
            }
        }
        // the instant's release, in any order among its other zero-time steps
        urgent.push(RELEASE.to_string());
        let mut out = Vec::new();
        for task in &tasks {
            let (m, name) = self.task_names(task);
            urgent.push(dispatch_connector(m, name));
            urgent.push(done_connector(m, name));
            // a task's starts, activity by activity in its order
            let levels: Vec<Vec<String>> = task
                .activities
                .iter()
                .map(|&r| {
                    let s = self.service(r);
                    s.codels
                        .iter()
                        .map(|c| start_connector(m, s.name, c.state))
                        .collect()
                })
                .collect();
            for pair in levels.windows(2) {
                for low in &pair[1] {
                    for high in &pair[0] {
                        out.push(pr(low, high));
                    }
                }
            }
            // between two codels, the job's end, then a yield to a more urgent task, then
            // the next codel's start
            let yielding = yield_connector(m, name);
            if self.has_connector(&yielding) {
                for start in levels.iter().flatten() {
                    out.push(pr(start, &yielding));
                }
                out.push(pr(&yielding, &done_connector(m, name)));
                urgent.push(yielding);
            }
            urgent.extend(levels.into_iter().flatten());
        }
        // a preempted core goes to the ready task that comes first: under fixed
        // priorities, the preemptions by a higher one come first (EDF: their guards); and
        // a task whose job has no work left ends it before it could be preempted
        let mut preemptions: Vec<(&TimedTaskRef, String)> = Vec::new();
        for by in &tasks {
            for task in tasks.iter().filter(|u| u.competes(by)) {
                let (bm, bn) = self.task_names(by);
                let (m, name) = self.task_names(task);
                let c = preempt_connector(bm, bn, m, name);
                if self.has_connector(&c) {
                    out.push(pr(&c, &done_connector(m, name)));
                    preemptions.push((by, c));
                }
            }
        }
        for (low_by, low) in &preemptions {
            for (high_by, high) in &preemptions {
                let fixed = !self.is_edf(t, low_by);
                if fixed
                    && high_by.competes(low_by)
                    && low_by.times.priority < high_by.times.priority
                {
                    out.push(pr(low, high));
                }
            }
        }
        urgent.extend(preemptions.into_iter().map(|(_, c)| c));
        for high in &urgent {
            out.push(pr(TICK, high));
        }
        // a free core goes to the ready task of highest priority that may take it (EDF
        // CPUs order their ready tasks in the dispatch's guard, `task.rs`: the order
        // changes with time)
        for a in &tasks {
            for b in &tasks {
                let competes = a.times.cpu == b.times.cpu
                    && a.times.core == b.times.core
                    && !t.edf.get(a.times.cpu as usize).copied().unwrap_or(false)
                    && a.times.priority < b.times.priority;
                if competes {
                    let (am, an) = self.task_names(a);
                    let (bm, bn) = self.task_names(b);
                    out.push(pr(&dispatch_connector(am, an), &dispatch_connector(bm, bn)));
                }
            }
        }
        out
    }
}
