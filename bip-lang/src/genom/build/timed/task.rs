//! A task's atom, its dispatch and its job's end.
//!
//! The atom has one location; its variables are its job's `stage` (idle, ready,
//! running), the `codel` that holds its core (0: none) with its elapsed units `x` (0
//! whenever no codel runs), and `late` (a period boundary passed while its job was
//! unfinished). Nothing else is stored: which cores are busy is read from the stages.

use super::preempt::preemption_ports;
use super::{Builder, TimedTaskRef};
use crate::expr::{Assign, BinOp, Expr};
use crate::genom::names::*;
use crate::genom::timed::Timed;
use crate::genom::tree::{all, and, assign, binary, boolean, chain, cond, int, member, not};
use crate::source::ConstExpr;
use crate::syntax::{AtomDef, Role, TypeDef};

use super::super::{connector, port, text, tr, var};

/// The ports of a task's atom, each a self-loop: the steps' guards and actions are the
/// connectors'.
const TASK_PORTS: [&str; 5] = ["tick", "dispatch", "done", "start", "finish"];

impl<'a, 'd> Builder<'a, 'd> {
    /// A timed model's tasks: their atoms, dispatch, job ends, codel starts and finishes,
    /// and the priorities between them.
    pub(in super::super) fn timed_tasks(&mut self, t: &Timed) {
        let tasks = self.timed_task_list(t);
        self.refuse_spins(t, &tasks);
        for task in &tasks {
            self.task_atom(t, task);
            self.dispatch(t, task, &tasks);
            self.job_done(task);
            self.codels(t, task, &tasks);
            self.preemptions(t, task, &tasks);
        }
    }

    fn task_atom(&mut self, t: &Timed, task: &TimedTaskRef) {
        let ports: Vec<&str> = TASK_PORTS
            .iter()
            .chain(preemption_ports(self.preemption(t, task)))
            .copied()
            .collect();
        let m = &self.layer.modules[task.module];
        let (name, _) = m.tasks[task.task];
        let span = m.def.tasks[task.task].name.span;
        let max_wcet = task.codels.iter().map(|c| c.wcet).max().unwrap_or(0);
        let int_var = |n: &str, hi: u64| {
            var(
                n,
                TypeDef::Int(ConstExpr::int(0), ConstExpr::int(hi as i64)),
                Some(0),
            )
        };
        let atom = AtomDef {
            locations: vec![text("on")],
            initial: text("on"),
            ports: ports.iter().map(|p| text(*p)).collect(),
            vars: vec![
                int_var(STAGE, STAGE_RUNNING as u64),
                int_var(RUNNING_CODEL, task.codels.len() as u64),
                int_var(ELAPSED, max_wcet),
                var(LATE, TypeDef::Bool, Some(0)),
            ],
            transitions: ports
                .iter()
                .map(|p| tr("on", p, "on", None, Vec::new()))
                .collect(),
            task: None,
        };
        let what = format!("task `{}.{name}`", m.name);
        let atom_name = task_atom(m.name, name);
        self.add_atom(atom_name.clone(), atom, span, what.clone());
        self.add_component(task_component(m.name, name), atom_name, span, what);
    }

    /// A core the task may take is free: its pinned core runs no other task, or fewer
    /// than its CPU's cores run its CPU's tasks. `None`: always.
    pub(super) fn core_free(
        &self,
        t: &Timed,
        task: &TimedTaskRef,
        tasks: &[TimedTaskRef],
    ) -> Option<Expr> {
        let cpu = task.times.cpu;
        let rivals = tasks.iter().filter(|u| {
            u.times.cpu == cpu
                && (u.module, u.task) != (task.module, task.task)
                && (task.times.core.is_none() || u.times.core == task.times.core)
        });
        let running = |u: &TimedTaskRef| self.stage_is(u, STAGE_RUNNING);
        match task.times.core {
            Some(_) => chain(BinOp::And, rivals.map(|u| not(running(u)))),
            None => {
                let cores = t.cores.get(cpu as usize).copied().unwrap_or(1);
                let rivals: Vec<&TimedTaskRef> = rivals.collect();
                // with a core for each, a task never waits
                if rivals.len() < cores as usize {
                    return None;
                }
                let count = chain(
                    BinOp::Add,
                    rivals.iter().map(|u| cond(running(u), int(1), int(0))),
                )?;
                Some(binary(BinOp::Lt, count, int(i64::from(cores))))
            }
        }
    }

    /// A ready job takes a free core, in zero time; the CPU's priorities choose among
    /// ready jobs (`priorities.rs`), or under EDF the guard: no ready job competing for
    /// the same cores has an earlier absolute deadline (release + D, in the same order as
    /// D − elapsed now), ties in declaration order.
    fn dispatch(&mut self, t: &Timed, task: &TimedTaskRef, tasks: &[TimedTaskRef]) {
        let comp = self.task_comp(task);
        let mut guard = self.stage_is(task, STAGE_READY);
        if let Some(free) = self.core_free(t, task, tasks) {
            guard = and(guard, free);
        }
        for first in self.first_ready(t, task, tasks) {
            guard = and(guard, first);
        }
        let action = vec![assign(member(&comp, STAGE), int(STAGE_RUNNING))];
        let m = &self.layer.modules[task.module];
        let (name, span) = (m.tasks[task.task].0, m.def.tasks[task.task].name.span);
        let c = dispatch_connector(m.name, name);
        self.claim(
            &c,
            span,
            format!("the dispatch of task `{}.{name}`", m.name),
        );
        self.connectors.push((
            connector(&c, vec![port(&comp, "dispatch")], Role::Progress),
            Some(guard),
            action,
        ));
    }

    /// The units left until the deadline of the task's job.
    pub(super) fn time_left(&self, task: &TimedTaskRef) -> Expr {
        let deadline = int(task.times.deadline as i64);
        binary(BinOp::Sub, deadline, self.job_elapsed(task))
    }

    /// The job is done once none of its task's codels runs or may start: the task frees
    /// its core. If a period boundary passed while it ran, that boundary's release
    /// happens now, and the task is ready again if it has work.
    fn job_done(&mut self, task: &TimedTaskRef) {
        let comp = self.task_comp(task);
        let guard = all([
            self.stage_is(task, STAGE_RUNNING),
            binary(BinOp::Eq, member(&comp, RUNNING_CODEL), int(0)),
            not(self.task_has_work(task)),
        ]);
        let late = member(&comp, LATE);
        let mut action: Vec<Assign> = self.release(task, late.clone());
        let stage = member(&comp, STAGE);
        action.push(assign(
            stage.clone(),
            cond(late.clone(), int(STAGE_READY), int(STAGE_IDLE)),
        ));
        action.push(assign(late, boolean(false)));
        // released, but nothing to do: idle
        action.push(assign(
            stage.clone(),
            cond(
                and(
                    binary(BinOp::Eq, stage.clone(), int(STAGE_READY)),
                    not(self.task_has_work(task)),
                ),
                int(STAGE_IDLE),
                stage,
            ),
        ));
        let mut ports = vec![port(&comp, "done")];
        ports.extend(task.activities.iter().map(|&r| port(&self.comp(r), "tick")));
        let m = &self.layer.modules[task.module];
        let (name, span) = (m.tasks[task.task].0, m.def.tasks[task.task].name.span);
        let c = done_connector(m.name, name);
        self.claim(&c, span, format!("the job end of task `{}.{name}`", m.name));
        self.connectors
            .push((connector(&c, ports, Role::Progress), guard, action));
    }

    /// Releases the task's paused activities where `when` holds (a period boundary's
    /// release, as the untimed tick's).
    pub(super) fn release(&self, task: &TimedTaskRef, when: Expr) -> Vec<Assign> {
        task.activities
            .iter()
            .map(|&r| {
                let paused = member(&self.comp(r), PAUSED);
                assign(paused.clone(), and(paused, not(when.clone())))
            })
            .collect()
    }
}
