//! A timed model's expansion (docs/genom.md, "Timed models"): each task of the layer
//! becomes an atom holding its job's stage, the codel that holds its core and that
//! codel's elapsed time units; a codel runs in two steps, its start (zero time, on the
//! task's core) and its finish (today's codel connector, once it has run between its BCET
//! and its WCET); the tick advances time by one unit. Everything is core atoms,
//! connectors and priorities: the verifier and the engine see nothing else.
//!
//! This file holds what the parts share: the codels of a task, in the order its job runs
//! them, and the expressions over a task's state. The parts:
//! - `task.rs`: the task atom, its dispatch (a ready job takes a free core) and its job's
//!   end (with the release deferred by a boundary that passed while it ran);
//! - `codel.rs`: a codel's start, its finish, and the finish that drops its outcome when
//!   its activity was interrupted while it ran;
//! - `tick.rs`: the tick and the release at the tasks' boundaries;
//! - `jump.rs`: how many units the tick stands for, up to the next instant at which
//!   something may happen;
//! - `order.rs`, `preempt.rs`: which of a CPU's tasks comes first, and how a task loses
//!   its core to a more urgent one before its job is done (`Codel`, `Preemptive`);
//! - `priorities.rs`: zero-time steps before time passes, a task's codels in GenoM3's
//!   order, and the CPUs' fixed priorities;
//! - `deadlines.rs`: each task's deadline as an invariant (`Schedulable` by exploration).

mod codel;
mod deadlines;
mod jump;
mod locks;
mod order;
mod preempt;
mod priorities;
mod task;
mod tick;

use super::Builder;
use crate::expr::{BinOp, Expr};
use crate::genom::check::{ServiceRef, ETHER};
use crate::genom::names::*;
use crate::genom::timed::{Timed, TimedTask};
use crate::genom::tree::{and, at, binary, chain, int, member, not};

/// A codel of a task, in the order its job runs them.
#[derive(Clone, Debug)]
struct TaskCodel {
    activity: ServiceRef,
    /// Index among its activity's codels.
    codel: usize,
    bcet: u64,
    wcet: u64,
    /// What it holds while it runs (`locks.rs`).
    locks: Vec<locks::Lock>,
}

/// A task of the layer that runs codels.
struct TimedTaskRef<'t> {
    module: usize,
    task: usize,
    times: &'t TimedTask,
    /// Its activities (its machine first), in declaration order.
    activities: Vec<ServiceRef>,
    /// Its codels, numbered from 1 in this order by the task atom's `codel`.
    codels: Vec<TaskCodel>,
}

impl<'a, 'd> Builder<'a, 'd> {
    /// The tasks that run codels (a task without any never has work), in declaration
    /// order.
    fn timed_task_list<'t>(&self, t: &'t Timed) -> Vec<TimedTaskRef<'t>> {
        let mut out = Vec::new();
        for (mi, m) in self.layer.modules.iter().enumerate() {
            for ti in 0..m.tasks.len() {
                let activities: Vec<ServiceRef> = m
                    .services
                    .iter()
                    .enumerate()
                    .filter(|(_, s)| s.is_activity() && s.task == Some(ti))
                    .map(|(si, _)| ServiceRef {
                        module: mi,
                        service: si,
                    })
                    .collect();
                let codels: Vec<TaskCodel> = activities
                    .iter()
                    .flat_map(|&r| {
                        (0..m.services[r.service].codels.len()).map(move |ci| {
                            let (bcet, wcet) = t.codel(r.module, r.service, ci);
                            let codel = &m.services[r.service].codels[ci];
                            TaskCodel {
                                activity: r,
                                codel: ci,
                                bcet,
                                wcet,
                                locks: locks::codel_locks(m, r.module, codel),
                            }
                        })
                    })
                    .collect();
                if codels.is_empty() {
                    continue;
                }
                out.push(TimedTaskRef {
                    module: mi,
                    task: ti,
                    times: t.task(mi, ti),
                    activities,
                    codels,
                });
            }
        }
        out
    }

    /// A task's module and name.
    fn task_names(&self, task: &TimedTaskRef) -> (&'d str, &'d str) {
        let m = &self.layer.modules[task.module];
        (m.name, m.tasks[task.task].0)
    }

    /// The component of a task.
    fn task_comp(&self, task: &TimedTaskRef) -> String {
        let m = &self.layer.modules[task.module];
        task_component(m.name, m.tasks[task.task].0)
    }

    /// `task.v`, a variable of a task's atom.
    fn task_var(&self, task: &TimedTaskRef, v: &str) -> Expr {
        member(&self.task_comp(task), v)
    }

    /// The task's job is at `stage`.
    fn stage_is(&self, task: &TimedTaskRef, stage: i64) -> Expr {
        binary(BinOp::Eq, self.task_var(task, STAGE), int(stage))
    }

    /// The activity of codel `c` is where the codel runs from, and not paused: the
    /// guards of its transitions in the activity's atom (`activity.rs`), read from
    /// outside.
    fn codel_ready(&self, c: &TaskCodel) -> Expr {
        let s = self.service(c.activity);
        let comp = self.comp(c.activity);
        let state = s.codels[c.codel].state;
        let mut from = Vec::new();
        if state == "start" {
            from.push(and(at(&comp, ETHER), member(&comp, REQ)));
        }
        if s.is_location(state) {
            from.push(at(&comp, state));
        }
        let from = chain(BinOp::Or, from).unwrap_or_else(|| crate::genom::tree::boolean(false));
        and(from, not(member(&comp, PAUSED)))
    }

    /// Codel `c` may start: its activity is ready for it and its conditions hold.
    fn codel_runnable(&self, c: &TaskCodel) -> Expr {
        let ready = self.codel_ready(c);
        match self.holds.get(&(c.activity, c.codel)).cloned().flatten() {
            Some(holds) => and(ready, holds),
            None => ready,
        }
    }

    /// Some codel of the task may start: its job has work.
    fn task_has_work(&self, task: &TimedTaskRef) -> Expr {
        chain(
            BinOp::Or,
            task.codels.iter().map(|c| self.codel_runnable(c)),
        )
        .unwrap_or_else(|| crate::genom::tree::boolean(false))
    }

    /// Codel `k` (counted from 0) of the task runs: it has started and not finished, and
    /// its task holds a core (on a preemptive CPU a started codel may wait, its task
    /// preempted).
    fn codel_runs(&self, t: &Timed, task: &TimedTaskRef, k: usize) -> Expr {
        let started = binary(
            BinOp::Eq,
            self.task_var(task, RUNNING_CODEL),
            int(k as i64 + 1),
        );
        match self.preemption(t, task) {
            crate::syntax::Preemption::Preemptive => {
                and(started, self.stage_is(task, STAGE_RUNNING))
            }
            _ => started,
        }
    }

    /// The codel that holds the task's core has run its WCET: it must finish before time
    /// passes. `None` if that can never be.
    fn at_wcet(&self, task: &TimedTaskRef) -> Option<Expr> {
        chain(
            BinOp::Or,
            task.codels.iter().enumerate().map(|(k, c)| {
                let running = binary(
                    BinOp::Eq,
                    self.task_var(task, RUNNING_CODEL),
                    int(k as i64 + 1),
                );
                if c.wcet == 0 {
                    running
                } else {
                    and(
                        running,
                        binary(BinOp::Ge, self.task_var(task, ELAPSED), int(c.wcet as i64)),
                    )
                }
            }),
        )
    }

    /// Time may pass: no codel has run its WCET.
    fn time_may_pass(&self, tasks: &[TimedTaskRef]) -> Option<Expr> {
        chain(
            BinOp::And,
            tasks.iter().filter_map(|t| self.at_wcet(t)).map(not),
        )
    }
}

impl<'a, 'd> Builder<'a, 'd> {
    /// In a timed model, activity `r` is starting: its `start` codel has started on its
    /// task's core and not finished (the activity is still at `ether` until it does).
    /// `None` in an untimed model, where a codel is an instant.
    pub(in super::super) fn activity_starting(&self, r: ServiceRef) -> Option<Expr> {
        let t = self.timed?;
        let tasks = self.timed_task_list(t);
        tasks.iter().find_map(|task| {
            let k = task.codels.iter().position(|c| {
                c.activity == r && self.service(r).codels[c.codel].state == "start"
            })?;
            Some(binary(
                BinOp::Eq,
                self.task_var(task, RUNNING_CODEL),
                int(k as i64 + 1),
            ))
        })
    }

    /// The time since the release of the task's job, in units: `late · period + (n −
    /// delay) mod period`, derived from the clock (a boundary that passed while the job
    /// ran counts one period, and so does the instant's boundary while its release is
    /// due).
    fn job_elapsed(&self, task: &TimedTaskRef) -> Expr {
        let (p, d) = (task.times.period as i64, task.times.delay as i64);
        let since_boundary = match self.timed.is_some_and(|t| t.hyperperiod > 1) {
            true => binary(
                BinOp::Rem,
                binary(BinOp::Add, member(CLOCK, PHASE), int((p - d).rem_euclid(p))),
                int(p),
            ),
            false => int(0),
        };
        let period_if = |e: Expr| crate::genom::tree::cond(e, int(p), int(0));
        let due_here = and(member(CLOCK, DUE), self.boundary(task));
        let periods = binary(
            BinOp::Add,
            period_if(self.task_var(task, LATE)),
            period_if(due_here),
        );
        binary(BinOp::Add, periods, since_boundary)
    }
}
