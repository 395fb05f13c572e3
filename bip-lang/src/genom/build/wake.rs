//! Aperiodic tasks (docs/genom.md, "Aperiodic tasks"). A task without a period runs its
//! activities' codels as soon as they are ready, and `pause::s` in one of them waits
//! for an *event* of its module, as GenoM3 defines it: a transition of another activity
//! of the module that is not a pause (a plain yield, `ether`, an error), or the request
//! of a function or attribute.
//!
//! Each activity of a module with a *sleeper* (an activity of an aperiodic task that
//! may pause) records its events in its own `woke`; the module's wake connector, above
//! every other step, then clears every sleeper's `paused` (and every `woke`) at once.
//! A function's or attribute's request clears the sleepers' `paused` in its own step.

use super::{connector, port, set, tr, Builder};
use crate::expr::Expr;
use crate::genom::check::{ServiceRef, Yield, ETHER};
use crate::genom::names::*;
use crate::genom::tree::{member, or};
use crate::syntax::{ExprDef, Role, Text, TransitionDef};

impl<'a, 'd> Builder<'a, 'd> {
    /// True if activity `r` runs in a task without a period.
    pub(super) fn aperiodic(&self, r: ServiceRef) -> bool {
        let m = &self.layer.modules[r.module];
        m.services[r.service]
            .task
            .is_some_and(|t| m.tasks[t].1.is_none())
    }

    /// The activities of module `mi` that sleep until an event: those of an aperiodic
    /// task with a `pause::` yield.
    pub(super) fn sleepers(&self, mi: usize) -> Vec<usize> {
        let m = &self.layer.modules[mi];
        (0..m.services.len())
            .filter(|&k| {
                let s = &m.services[k];
                s.is_activity()
                    && self.aperiodic(ServiceRef {
                        module: mi,
                        service: k,
                    })
                    && s.codels
                        .iter()
                        .any(|c| c.yields.iter().any(|y| matches!(y, Yield::Pause(_))))
            })
            .collect()
    }

    /// True if activity `r`'s events wake some other activity of its module.
    pub(super) fn emits(&self, r: ServiceRef) -> bool {
        self.sleepers(r.module).iter().any(|&k| k != r.service)
    }

    /// The `wake` port of activity `r` and its transitions, if its module has sleepers
    /// that it wakes or that are woken: at every location, a self-loop that forgets the
    /// activity's event and, for a sleeper, ends its pause.
    pub(super) fn wake_transitions(
        &self,
        r: ServiceRef,
        locs: &[&str],
        ports: &mut Vec<Text>,
        t: &mut Vec<TransitionDef>,
    ) {
        let emits = self.emits(r);
        let sleeps = self.sleepers(r.module).contains(&r.service);
        if !emits && !sleeps {
            return;
        }
        ports.push(super::text(WAKE));
        let mut action = Vec::new();
        if emits {
            action.push(set(WOKE, false));
        }
        if sleeps {
            action.push(set(PAUSED, false));
        }
        for l in std::iter::once(&ETHER).chain(locs) {
            t.push(tr(l, WAKE, l, None, action.clone()));
        }
    }

    /// The wake ports of module `mi`'s sleepers but those of `except` (activities
    /// already in the connector), which a function's or attribute's request takes: its
    /// execution is an event.
    pub(super) fn sleeper_ports(&self, mi: usize, except: &[usize]) -> Vec<ExprDef> {
        self.sleepers(mi)
            .into_iter()
            .filter(|k| !except.contains(k))
            .map(|k| {
                let c = self.comp(ServiceRef {
                    module: mi,
                    service: k,
                });
                port(&c, WAKE)
            })
            .collect()
    }

    /// Module `mi`'s wake connector, if some activity of it wakes another: every
    /// emitter's and sleeper's `wake` port, enabled when some emitter has an event.
    pub(super) fn wake(&mut self, mi: usize) {
        let m = &self.layer.modules[mi];
        let sleepers = self.sleepers(mi);
        let mut ports = Vec::new();
        let mut events: Vec<Expr> = Vec::new();
        for k in 0..m.services.len() {
            let r = ServiceRef {
                module: mi,
                service: k,
            };
            if !m.services[k].is_activity() {
                continue;
            }
            let emits = self.emits(r);
            if !emits && !sleepers.contains(&k) {
                continue;
            }
            let c = self.comp(r);
            ports.push(port(&c, WAKE));
            if emits {
                events.push(member(&c, WOKE));
            }
        }
        let Some(guard) = events.into_iter().reduce(or) else {
            return;
        };
        let name = wake_connector(m.name);
        self.claim(
            &name,
            m.def.name.span,
            format!("the wake-up of module `{}`'s aperiodic tasks", m.name),
        );
        self.wakes.push(name.clone());
        self.connectors.push((
            connector(&name, ports, Role::Progress),
            Some(guard),
            Vec::new(),
        ));
    }
}
