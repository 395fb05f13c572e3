//! A timed model's tick and release. The tick: time passes to the next instant at which
//! something may happen (`jump.rs`), the clock's phase counts units modulo the common
//! cycle of the periods, each running codel's elapsed time grows as much, and if the new instant is a period boundary of some task, or a
//! tick of `tick_ms` at which ports age, its release is due. The release, a zero-time
//! step of its own: at each task's boundary (`delay + k * period`) an idle task's paused
//! activities are released and, if it then has work, its job is ready; a busy task's
//! boundary is deferred (`late`) to its job's end; ports age once per tick of `tick_ms`,
//! as in an untimed model.
//!
//! The release is one step for everything the instant's timer does, so that a CPU's
//! priorities decide between jobs released together; it is not ordered against the
//! instant's other zero-time steps (a codel finishing at its WCET, a dispatch, a job's
//! end, a codel start that reads a port's age), so that integer time is exact
//! (docs/model.md, "Why whole units are enough"). The tick's guard: no codel has run its
//! WCET and no release is due.

use super::{Builder, TimedTaskRef};
use crate::expr::{Assign, BinOp, Expr};
use crate::genom::names::*;
use crate::genom::timed::Timed;
use crate::genom::tree::{and, assign, binary, boolean, chain, cond, int, member, name, not, or};
use crate::syntax::{ExprDef, Preemption, Role};

use super::super::{connector, port};

impl<'a, 'd> Builder<'a, 'd> {
    pub(in super::super) fn timed_tick(&mut self, t: &Timed) {
        let tasks = self.timed_task_list(t);
        let mut ports = vec![port(CLOCK, "tick")];
        let mut action: Vec<Assign> = Vec::new();
        let phase = member(CLOCK, PHASE);
        // ports age once per tick of `tick_ms`, every `tick_units` units
        let on_tick = (t.tick_units > 1).then(|| {
            binary(
                BinOp::Eq,
                binary(BinOp::Rem, phase.clone(), int(t.tick_units as i64)),
                int(0),
            )
        });
        let mut aging_ports = Vec::new();
        let mut aging = Vec::new();
        for mi in 0..self.layer.modules.len() {
            self.age_ports(mi, on_tick.as_ref(), &mut aging_ports, &mut aging);
        }
        let jump = self.time_jump(t, &tasks, !aging.is_empty());
        let units = match jump {
            Some(_) => name("advance"),
            None => int(1),
        };
        if t.hyperperiod > 1 {
            let next = binary(BinOp::Add, phase.clone(), units.clone());
            action.push(assign(
                phase.clone(),
                binary(BinOp::Rem, next, int(t.hyperperiod as i64)),
            ));
        }
        for task in &tasks {
            let comp = self.task_comp(task);
            ports.push(port(&comp, "tick"));
            let codel = member(&comp, RUNNING_CODEL);
            let elapsed = member(&comp, ELAPSED);
            let mut grown = binary(BinOp::Add, elapsed.clone(), units.clone());
            // a preempted codel waits
            if self.preemption(t, task) == Preemption::Preemptive {
                grown = cond(self.stage_is(task, STAGE_RUNNING), grown, elapsed.clone());
            }
            action.push(assign(
                elapsed.clone(),
                cond(binary(BinOp::Eq, codel, int(0)), int(0), grown),
            ));
        }
        // the phase, once incremented, is the new instant's number modulo the cycle
        let ages_now = (!aging.is_empty()).then(|| on_tick.clone().unwrap_or(boolean(true)));
        let due = chain(
            BinOp::Or,
            tasks.iter().map(|task| self.boundary(task)).chain(ages_now),
        );
        action.push(assign(member(CLOCK, DUE), due.unwrap_or(boolean(false))));
        let no_release = not(member(CLOCK, DUE));
        let guard = match self.time_may_pass(&tasks) {
            Some(g) => and(g, no_release),
            None => no_release,
        };
        self.push_tick(ports, Some(guard), action, jump);
        self.timed_release(&tasks, aging_ports, aging);
    }

    /// The instant (the clock's phase) is a period boundary of the task.
    pub(super) fn boundary(&self, task: &TimedTaskRef) -> Expr {
        let (p, d) = (task.times.period, task.times.delay);
        if p == 1 {
            boolean(true)
        } else {
            binary(
                BinOp::Eq,
                binary(BinOp::Rem, member(CLOCK, PHASE), int(p as i64)),
                int(d as i64),
            )
        }
    }

    /// The due release of the instant's boundaries, every task's at once, and the aging
    /// of ports (`aging_ports`, `aging`).
    fn timed_release(
        &mut self,
        tasks: &[TimedTaskRef],
        aging_ports: Vec<ExprDef>,
        aging: Vec<Assign>,
    ) {
        let due = member(CLOCK, DUE);
        let mut ports = vec![port(CLOCK, RELEASE)];
        ports.extend(aging_ports);
        let mut action = vec![assign(due.clone(), boolean(false))];
        action.extend(aging);
        for task in tasks {
            let comp = self.task_comp(task);
            ports.push(port(&comp, "tick"));
            ports.extend(task.activities.iter().map(|&r| port(&self.comp(r), "tick")));
            let boundary = self.boundary(task);
            let idle = self.stage_is(task, STAGE_IDLE);
            let late = member(&comp, LATE);
            action.push(assign(
                late.clone(),
                or(late, and(boundary.clone(), not(idle.clone()))),
            ));
            let released = and(boundary, idle);
            action.extend(self.release(task, released.clone()));
            let stage = member(&comp, STAGE);
            action.push(assign(
                stage.clone(),
                cond(
                    and(released, self.task_has_work(task)),
                    int(STAGE_READY),
                    stage,
                ),
            ));
        }
        self.claim(
            RELEASE,
            self.layer_span(),
            "the release at the tasks' period boundaries".into(),
        );
        self.connectors
            .push((connector(RELEASE, ports, Role::Progress), Some(due), action));
    }
}
