//! A timed model's tick: one time unit passes. The clock's phase counts units modulo the
//! common cycle of the periods; each running codel's elapsed time grows by one; at a
//! task's period boundary (`delay + k * period`) an idle task's paused activities are
//! released and, if it then has work, its job is ready; a busy task's boundary is
//! deferred (`late`) to its job's end. Ports age once per tick of `tick_ms`, as in an
//! untimed model. The tick's guard: no codel has run its WCET.

use super::Builder;
use crate::expr::{Assign, BinOp};
use crate::genom::names::*;
use crate::genom::timed::Timed;
use crate::genom::tree::{and, assign, binary, boolean, cond, int, member, not, or};

use super::super::port;

impl<'a, 'd> Builder<'a, 'd> {
    pub(in super::super) fn timed_tick(&mut self, t: &Timed) {
        let tasks = self.timed_task_list(t);
        let mut ports = vec![port(CLOCK, "tick")];
        let mut action: Vec<Assign> = Vec::new();
        let phase = member(CLOCK, PHASE);
        if t.hyperperiod > 1 {
            let next = binary(BinOp::Add, phase.clone(), int(1));
            action.push(assign(
                phase.clone(),
                binary(BinOp::Rem, next, int(t.hyperperiod as i64)),
            ));
        }
        for task in &tasks {
            let comp = self.task_comp(task);
            ports.push(port(&comp, "tick"));
            ports.extend(task.activities.iter().map(|&r| port(&self.comp(r), "tick")));
            let (p, d) = (task.times.period, task.times.delay);
            // the phase, once incremented, is the unit's number modulo the cycle
            let boundary = if p == 1 {
                boolean(true)
            } else {
                binary(
                    BinOp::Eq,
                    binary(BinOp::Rem, phase.clone(), int(p as i64)),
                    int(d as i64),
                )
            };
            let idle = self.stage_is(task, STAGE_IDLE);
            let late = member(&comp, LATE);
            action.push(assign(
                late.clone(),
                or(late, and(boundary.clone(), not(idle.clone()))),
            ));
            let released = and(boundary.clone(), idle.clone());
            action.extend(self.release(task, released.clone()));
            let codel = member(&comp, RUNNING_CODEL);
            let elapsed = member(&comp, ELAPSED);
            action.push(assign(
                elapsed.clone(),
                cond(
                    binary(BinOp::Eq, codel, int(0)),
                    int(0),
                    binary(BinOp::Add, elapsed, int(1)),
                ),
            ));
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
        // ports age once per tick of `tick_ms`, every `tick_units` units
        let on_tick = (t.tick_units > 1).then(|| {
            binary(
                BinOp::Eq,
                binary(BinOp::Rem, phase.clone(), int(t.tick_units as i64)),
                int(0),
            )
        });
        for mi in 0..self.layer.modules.len() {
            self.age_ports(mi, on_tick.as_ref(), &mut ports, &mut action);
        }
        let guard = self.time_may_pass(&tasks);
        self.push_tick(ports, guard, action);
    }
}
