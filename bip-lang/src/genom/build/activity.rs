//! An activity's atom: `ether` and one location per place its codels run from, the
//! request, interrupt and abort paths (through `stop` if the activity has one), the tick,
//! and one transition per yield of each codel with its error path beside it.

use super::async_codels::{async_vars, none_apart, start_and_return};
use super::{set, text, tr, var, Builder};
use crate::expr::{Assign, Expr};
use crate::genom::check::{ServiceRef, Yield, ETHER};
use crate::genom::names::*;
use crate::genom::tree::{and, assign, name, not};
use crate::syntax::{AtomDef, TransitionDef, TypeDef};

impl<'a, 'd> Builder<'a, 'd> {
    /// True if some service other than `r` interrupts activity `r`.
    fn interrupted_by_others(&self, r: ServiceRef) -> bool {
        self.layer.modules[r.module]
            .services
            .iter()
            .enumerate()
            .any(|(k, s)| k != r.service && s.interrupts.contains(&r.service))
    }

    pub(super) fn activity(&mut self, r: ServiceRef) {
        let s = self.service(r);
        let m = self.module_name(r);
        let has_stop = s.stop.is_some();
        let self_int = s.interrupts_itself(r.service);
        let locs: Vec<&str> = s.locations.iter().map(|&k| s.codels[k].state).collect();
        let mut locations = vec![text(ETHER)];
        locations.extend(locs.iter().map(|l| text(*l)));
        // a task's machine starts pending, released at its task's first period boundary
        // like a requested activity (docs/genom.md, "Task machines"); in an aperiodic
        // task, at once
        let machine = s.machine;
        let aperiodic = self.aperiodic(r);
        let starts = i64::from(machine && s.codel("start").is_some());
        let mut vars = vec![
            var(REQ, TypeDef::Bool, Some(starts)),
            var(PAUSED, TypeDef::Bool, Some(starts * i64::from(!aperiodic))),
        ];
        // the events that wake the module's sleeping aperiodic activities (`wake.rs`)
        let emits = self.emits(r);
        if emits {
            vars.push(var(WOKE, TypeDef::Bool, Some(0)));
        }
        if has_stop {
            vars.push(var(STOPPING, TypeDef::Bool, Some(0)));
        }
        let tracked = self.tracked.contains(&r);
        if tracked {
            vars.push(var(DONE, TypeDef::Bool, Some(0)));
        }
        // async codels run apart from the task (`async_codels.rs`)
        let apart = s.async_codels().count();
        vars.extend(async_vars(apart));
        // leaving a location drops an outcome that waits for the task
        let leave = |mut action: Vec<Assign>| {
            if apart > 0 {
                action.push(set(RETURNED, false));
            }
            action
        };
        let mut ports = Vec::new();
        let mut t = Vec::new();
        // requests
        if !machine {
            ports.push(text("request"));
            t.push(tr(
                ETHER,
                "request",
                ETHER,
                Some(not(name(REQ))),
                vec![set(REQ, true), set(PAUSED, !aperiodic)],
            ));
        }
        if self_int {
            t.push(tr(ETHER, "request", ETHER, Some(name(REQ)), Vec::new()));
            for l in &locs {
                if has_stop {
                    t.push(tr(
                        l,
                        "request",
                        "stop",
                        Some(not(name(STOPPING))),
                        leave(unpause(
                            aperiodic,
                            vec![set(STOPPING, true), set(REQ, true)],
                        )),
                    ));
                    t.push(tr(
                        l,
                        "request",
                        l,
                        Some(name(STOPPING)),
                        unpause(aperiodic, vec![set(REQ, true)]),
                    ));
                } else {
                    t.push(tr(
                        l,
                        "request",
                        ETHER,
                        None,
                        leave(vec![set(REQ, true), set(PAUSED, !aperiodic)]),
                    ));
                }
            }
        }
        // an interrupt or an abort: at `ether` it cancels the pending request; while the
        // activity runs, it takes the stop path (or ends); on the stop path it drops a
        // queued restart. With `requested`, it is enabled only where it has a request to
        // drop or a run to end.
        let ending = |t: &mut Vec<TransitionDef>, port: &str, requested: bool| {
            let at_ether = requested.then(|| name(REQ));
            t.push(tr(
                ETHER,
                port,
                ETHER,
                at_ether,
                vec![set(REQ, false), set(PAUSED, false)],
            ));
            for l in &locs {
                if has_stop {
                    t.push(tr(
                        l,
                        port,
                        "stop",
                        Some(not(name(STOPPING))),
                        leave(unpause(
                            aperiodic,
                            vec![set(STOPPING, true), set(REQ, false)],
                        )),
                    ));
                    let stopping = match requested {
                        true => and(name(STOPPING), name(REQ)),
                        false => name(STOPPING),
                    };
                    t.push(tr(
                        l,
                        port,
                        l,
                        Some(stopping),
                        unpause(aperiodic, vec![set(REQ, false)]),
                    ));
                } else {
                    t.push(tr(
                        l,
                        port,
                        ETHER,
                        None,
                        leave(vec![set(REQ, false), set(PAUSED, false)]),
                    ));
                }
            }
        };
        // interrupts by other services' requests: always enabled, so that a target never
        // holds back the request that interrupts it
        if self.interrupted_by_others(r) {
            ports.push(text("interrupt"));
            ending(&mut t, "interrupt", false);
        }
        // abort, for components of the model (a supervisor, a safety rule): enabled only
        // when there is something to abort, so that it never fires for nothing; nothing
        // aborts a task's machine
        if !machine {
            ports.push(text("abort"));
            ending(&mut t, "abort", true);
        }
        // time: the tick connector's action clears `paused` at the task's period
        ports.push(text("tick"));
        t.push(tr(ETHER, "tick", ETHER, None, Vec::new()));
        for l in &locs {
            t.push(tr(l, "tick", l, None, Vec::new()));
        }
        // codels: one transition per yield, from each place the codel runs from
        for (ci, c) in s.codels.iter().enumerate() {
            ports.push(text(c.state));
            // every codel has an error path: a declared exception, or what the engine does
            // with a codel that panics, yields something undeclared or leaves a range
            ports.push(text(fail_port(c.state)));
            let mut sources: Vec<(&str, Expr, Vec<Assign>)> = Vec::new();
            let number = s.async_number(ci);
            if let Some(n) = number {
                // its outcome, once it has returned and its task has taken it up
                start_and_return(c.state, n, &locs, aperiodic, &mut ports, &mut t);
                sources.push((
                    c.state,
                    and(name(RETURNED), not(name(PAUSED))),
                    vec![set(RETURNED, false)],
                ));
            } else {
                // no codel of the activity runs while one of its async codels does
                let idle = |g: Expr| match apart {
                    0 => g,
                    _ => and(g, none_apart()),
                };
                if c.state == "start" {
                    sources.push((
                        ETHER,
                        idle(and(name(REQ), not(name(PAUSED)))),
                        vec![set(REQ, false)],
                    ));
                }
                if locs.contains(&c.state) {
                    sources.push((c.state, idle(not(name(PAUSED))), Vec::new()));
                }
            }
            let mut end = Vec::new();
            if has_stop {
                end.push(set(STOPPING, false));
            }
            // a queued restart waits for the next period boundary, or none
            end.push(match aperiodic {
                false => assign(name(PAUSED), name(REQ)),
                true => set(PAUSED, false),
            });
            for (from, guard, pre) in &sources {
                for y in &c.yields {
                    let mut action = pre.clone();
                    // every transition but a pause is an event of the module
                    if emits && !matches!(y, Yield::Pause(_)) {
                        action.push(set(WOKE, true));
                    }
                    let to = match *y {
                        Yield::Go(k) => s.codels[k].state,
                        Yield::Pause(k) => {
                            action.push(set(PAUSED, true));
                            s.codels[k].state
                        }
                        Yield::Ether => {
                            if tracked {
                                action.push(set(DONE, true));
                            }
                            action.extend(end.iter().cloned());
                            ETHER
                        }
                    };
                    t.push(tr(from, c.state, to, Some(guard.clone()), action));
                }
                let mut action = pre.clone();
                if emits {
                    action.push(set(WOKE, true));
                }
                action.extend(end.iter().cloned());
                t.push(tr(
                    from,
                    &fail_port(c.state),
                    ETHER,
                    Some(guard.clone()),
                    action,
                ));
            }
        }
        self.wake_transitions(r, &locs, &mut ports, &mut t);
        let atom = AtomDef {
            locations,
            initial: text(ETHER),
            ports,
            vars,
            transitions: t,
            task: None,
        };
        let what = if machine {
            format!("the machine of task `{m}.{}`", s.name)
        } else {
            format!("activity `{m}.{}`", s.name)
        };
        let comp = self.comp(r);
        if !machine {
            self.activity_components.insert(comp.clone());
        }
        self.add_atom(
            activity_atom(m, s.name),
            atom,
            s.def.name.span,
            what.clone(),
        );
        self.add_component(comp, activity_atom(m, s.name), s.def.name.span, what);
    }
}

/// `action`, which sends an activity of an aperiodic task onto its stop path (or finds it
/// there), with its `paused` cleared: the stop path runs at once, as a task without a
/// period runs what is ready, and a request that interrupts is an event of the module.
fn unpause(aperiodic: bool, mut action: Vec<Assign>) -> Vec<Assign> {
    if aperiodic {
        action.push(set(PAUSED, false));
    }
    action
}
