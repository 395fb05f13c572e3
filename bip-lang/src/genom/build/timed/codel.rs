//! A codel in a timed model: its start takes its task's core for it (zero time), and its
//! finish, today's codel connector and its error path, frees the core once the codel has
//! run at least its BCET (the tick cannot pass its WCET). Its conditions gate the start,
//! never the finish: a codel that holds a core always ends. If its activity is
//! interrupted or aborted while it runs, it still holds the core until it finishes, and
//! its outcome is dropped (the activity is already on its stop path, or done).

use super::{Builder, TaskCodel, TimedTaskRef};
use crate::expr::{Assign, BinOp, Expr};
use crate::genom::names::*;
use crate::genom::timed::Timed;
use crate::genom::tree::{all, and, assign, binary, int, member, not};
use crate::syntax::Role;

use super::super::{connector, port};

impl<'a, 'd> Builder<'a, 'd> {
    pub(super) fn codels(&mut self, t: &Timed, task: &TimedTaskRef, tasks: &[TimedTaskRef]) {
        let comp = self.task_comp(task);
        let codel = member(&comp, RUNNING_CODEL);
        let elapsed = member(&comp, ELAPSED);
        let free_core: Vec<Assign> = vec![
            assign(codel.clone(), int(0)),
            assign(elapsed.clone(), int(0)),
        ];
        for (k, c) in task.codels.iter().enumerate() {
            let number = int(k as i64 + 1);
            let s = self.service(c.activity);
            let m = self.module_name(c.activity);
            let state = s.codels[c.codel].state;
            let span = s.codels[c.codel].def.state.span;
            // the start, once its locks are free (`locks.rs`)
            let guard = all([
                self.stage_is(task, STAGE_RUNNING),
                binary(BinOp::Eq, codel.clone(), int(0)),
                self.codel_runnable(c),
            ]
            .into_iter()
            .chain(self.locks_free(task, k, tasks))
            .chain(self.no_earlier_waits(task, k)));
            let start = start_connector(m, s.name, state);
            self.claim(
                &start,
                span,
                format!("the start of codel `{state}` of `{m}.{}`", s.name),
            );
            self.connectors.push((
                connector(&start, vec![port(&comp, "start")], Role::Progress),
                guard,
                vec![assign(codel.clone(), number.clone())],
            ));
            // the finish: its run and error path, once it has run its BCET
            let finishing = ran_bcet(self.codel_runs(t, task, k), &elapsed, c);
            for name in [
                codel_connector(m, s.name, state),
                fail_connector(m, s.name, state),
            ] {
                let Some((def, guard, action)) = self
                    .connectors
                    .iter_mut()
                    .find(|(d, _, _)| d.name.value == name)
                else {
                    continue;
                };
                def.ports.push(port(&comp, "finish"));
                *guard = Some(finishing.clone());
                action.splice(0..0, free_core.iter().cloned());
            }
            // the finish of a codel whose activity left it while it ran (nothing
            // requests, interrupts or aborts a task's machine)
            if s.machine {
                continue;
            }
            let dropped = dropped_connector(m, s.name, state);
            self.claim(
                &dropped,
                span,
                format!("the dropped outcome of codel `{state}` of `{m}.{}`", s.name),
            );
            self.connectors.push((
                connector(&dropped, vec![port(&comp, "finish")], Role::Progress),
                Some(and(finishing, not(self.codel_ready(c)))),
                free_core.clone(),
            ));
        }
    }
}

/// `running` (the codel holds the core) and it has run its BCET.
fn ran_bcet(running: Expr, elapsed: &Expr, c: &TaskCodel) -> Expr {
    if c.bcet == 0 {
        running
    } else {
        and(
            running,
            binary(BinOp::Ge, elapsed.clone(), int(c.bcet as i64)),
        )
    }
}
