//! Codel locks in a timed model (docs/model.md, "Codel locks"): GenoM3 runs two codels of
//! a component apart only when they access no common ids member or port, and a port is
//! one lock for its writer and its readers in every component. A codel holds a lock on
//! each ids member and port it names (`uses` and `writes`) while it holds its core; its
//! start waits until no codel of another task holds one of them, its task keeping its
//! core meanwhile (a spin: a job does not give the core back to wait; refused where a
//! holder could be preempted by its waiter, `refuse_spins`). The
//! start is urgent like every start, so the lock is taken the moment it is free, and the
//! codel's duration counts from then.
//!
//! Nothing is stored: a task's lock holdings are read from its running codel.

use super::{Builder, TaskCodel, TimedTaskRef};
use crate::diag::ModelError;
use crate::expr::{BinOp, Expr};
use crate::genom::check::{Codel, Module, PortRef};
use crate::genom::names::*;
use crate::genom::timed::Timed;
use crate::genom::tree::{binary, chain, int, not};
use crate::syntax::Preemption;

/// What a codel locks: an out port (which an in port connected to it stands for), an in
/// port that no connection names, or an ids member of a module (modelled or not: a
/// GenoM3 component's ids are not the model's ids fields).
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) enum Lock {
    Port(PortRef),
    InPort { module: usize, port: usize },
    Ids { module: usize, member: String },
}

/// The locks of codel `c` of module `module`: each name of its `uses` and `writes`, once.
pub(super) fn codel_locks(m: &Module, module: usize, c: &Codel) -> Vec<Lock> {
    let mut out: Vec<Lock> = Vec::new();
    for name in c.def.uses.iter().chain(&c.def.writes) {
        let name = name.as_str();
        let lock = if let Some(port) = m.ports.iter().position(|&p| p == name) {
            Lock::Port(PortRef { module, port })
        } else if let Some(port) = m.in_ports.iter().position(|p| p.name == name) {
            match m.in_ports[port].reads {
                Some(out_port) => Lock::Port(out_port),
                None => Lock::InPort { module, port },
            }
        } else {
            Lock::Ids {
                module,
                member: name.to_string(),
            }
        };
        if !out.contains(&lock) {
            out.push(lock);
        }
    }
    out
}

fn shares(a: &TaskCodel, b: &TaskCodel) -> bool {
    a.locks.iter().any(|l| b.locks.contains(l))
}

impl<'a, 'd> Builder<'a, 'd> {
    /// Refuses two tasks that compete for the cores of a `Preemptive` CPU and share a
    /// lock: a task that waits for a lock keeps its core in this model (a spin, exact
    /// where codels run to completion), so a holder preempted mid-codel could not resume
    /// on the core its waiter keeps, and the model would show misses that a sleeping
    /// mutex does not have (docs/model.md, "Codel locks").
    pub(super) fn refuse_spins(&mut self, t: &Timed, tasks: &[TimedTaskRef]) {
        for (i, a) in tasks.iter().enumerate() {
            if self.preemption(t, a) != Preemption::Preemptive {
                continue;
            }
            for b in tasks[i + 1..].iter().filter(|b| b.competes(a)) {
                let shared = b.codels.iter().find_map(|cb| {
                    let lock = cb
                        .locks
                        .iter()
                        .find(|l| a.codels.iter().any(|ca| ca.locks.contains(l)))?;
                    Some((cb, lock))
                });
                let Some((cb, lock)) = shared else { continue };
                let (am, an) = self.task_names(a);
                let (bm, bn) = self.task_names(b);
                let m = &self.layer.modules[cb.activity.module];
                let codel = &m.services[cb.activity.service].codels[cb.codel];
                let cpu = match self.def.cpus.get(a.times.cpu as usize) {
                    Some(c) => format!("the preemptive CPU `{}`", c.name.as_str()),
                    None => "the model's one CPU (preemptive: the model declares no `cpus`)".into(),
                };
                self.errors.push(
                    ModelError::new(
                        format!(
                            "tasks `{am}.{an}` and `{bm}.{bn}` share `{}` on {cpu}, whose lock waits the model does not have yet",
                            self.lock_name(lock)
                        ),
                        codel.def.state.span,
                    )
                    .with_help(
                        "a task waiting for a lock keeps its core here, so a holder preempted mid-codel could not resume: give the CPU `preemption: Codel` (codels run to completion, as GenoM3's) or `Job`, or pin the two tasks to different cores (docs/model.md, \"Codel locks\")",
                    ),
                );
            }
        }
    }

    /// A lock in the user's names: `m.p` for a port, `m.member` for an ids member.
    fn lock_name(&self, lock: &Lock) -> String {
        let modules = &self.layer.modules;
        match lock {
            Lock::Port(p) => format!(
                "{}.{}",
                modules[p.module].name, modules[p.module].ports[p.port]
            ),
            Lock::InPort { module, port } => {
                format!(
                    "{}.{}",
                    modules[*module].name, modules[*module].in_ports[*port].name
                )
            }
            Lock::Ids { module, member } => format!("{}.{member}", modules[*module].name),
        }
    }

    /// Codel `k` of `task` may take its locks: no other task's running codel holds one of
    /// them. `None`: nothing can hold them.
    pub(super) fn locks_free(
        &self,
        task: &TimedTaskRef,
        k: usize,
        tasks: &[TimedTaskRef],
    ) -> Option<Expr> {
        let mine = &task.codels[k];
        let held = tasks
            .iter()
            .filter(|u| (u.module, u.task) != (task.module, task.task))
            .flat_map(|u| {
                u.codels
                    .iter()
                    .enumerate()
                    .filter(|(_, theirs)| shares(mine, theirs))
                    .map(move |(j, _)| {
                        binary(
                            BinOp::Eq,
                            self.task_var(u, RUNNING_CODEL),
                            int(j as i64 + 1),
                        )
                    })
            });
        chain(BinOp::Or, held).map(not)
    }

    /// Codel `k` of `task` is not held back by a codel of an earlier activity of its task
    /// that may run but waits for its locks: the job runs its activities in order, and
    /// one that waits holds the task (GenoM3's task waits on the lock). `None`: no earlier
    /// codel takes locks. (An earlier codel free to start is ahead of `k` by the
    /// priorities already.)
    pub(super) fn no_earlier_waits(&self, task: &TimedTaskRef, k: usize) -> Option<Expr> {
        let mine = &task.codels[k];
        let earlier = task.codels[..k]
            .iter()
            .filter(|c| c.activity != mine.activity && !c.locks.is_empty())
            .map(|c| not(self.codel_runnable(c)));
        chain(BinOp::And, earlier)
    }
}
