//! The run-time monitor of the model's bounded response properties (`Response ...
//! within`, `Replies(within)`; docs/engine.md, "Response deadlines"): after every step, each
//! property's [`ResponseWatch`] (the verifier's bounded observer) counts the ticks since
//! its oldest unanswered trigger, and a tick that passes the bound is an
//! [`Event::ResponseLate`].

use alloc::sync::Arc;

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::{Label, Property, RangeError, ResponseSpec, ResponseWatch, State, Step, System};

use super::Engine;
use crate::error::EngineError;
use crate::event::{Event, Ticket};

/// The watches of the model's bounded response properties; empty when it has none, and
/// then a step costs one test.
pub(super) struct Monitor {
    watches: Vec<Watch>,
    /// A timed model's deadline invariants are watched too (`timed.rs`).
    deadlines: bool,
}

struct Watch {
    /// Index into the system's properties.
    property: usize,
    name: Arc<str>,
    /// What a range error in the property is reported in: `property NAME`, as the
    /// verifier says.
    context: String,
    watch: ResponseWatch,
    /// The oldest waiting trigger was reported late: it is not reported again, and the
    /// watch counts on without a bound until it is answered.
    late: bool,
    /// The request accepted in the step on which the waiting trigger happened.
    ticket: Option<Ticket>,
}

impl Monitor {
    pub(super) fn new(system: &System, init: &State) -> Result<Monitor, RangeError> {
        let mut watches = Vec::new();
        for (k, p) in system.properties.iter().enumerate() {
            let Some(spec) = bounded(p) else { continue };
            let context = format!("property {}", p.name);
            watches.push(Watch {
                property: k,
                name: p.name.as_str().into(),
                watch: ResponseWatch::start(system, spec, init, &context)?,
                context,
                late: false,
                ticket: None,
            });
        }
        Ok(Monitor {
            watches,
            deadlines: false,
        })
    }

    /// Watches a timed model's deadline invariants too.
    pub(super) fn with_deadlines(mut self, on: bool) -> Monitor {
        self.deadlines = on;
        self
    }

    /// Watching nothing: for an engine stopped before its first step.
    pub(super) fn none() -> Monitor {
        Monitor {
            watches: Vec::new(),
            deadlines: false,
        }
    }

    pub(super) fn is_empty(&self) -> bool {
        self.watches.is_empty() && !self.deadlines
    }
}

/// The property's trigger, response and bound, if it is a response property with a bound.
fn bounded(p: &Property) -> Option<ResponseSpec<'_>> {
    p.kind.response_spec().filter(|s| s.within.is_some())
}

impl Engine {
    /// Watches the step just committed with `label` (from the gate's previous state to its
    /// state); `ticket` is the request it accepted, if any. A property out of range stops
    /// the engine, as a step does.
    #[inline(never)]
    pub(super) fn monitor_step(
        &mut self,
        label: Label,
        ticket: Option<Ticket>,
    ) -> Result<(), EngineError> {
        self.watch_step(label, ticket).map_err(|e| {
            self.stopped = Some(e.clone());
            EngineError::Range(e)
        })?;
        if self.monitor.deadlines {
            self.watch_deadlines()?;
        }
        Ok(())
    }

    fn watch_step(&mut self, label: Label, ticket: Option<Ticket>) -> Result<(), RangeError> {
        for k in 0..self.monitor.watches.len() {
            let system = self.gate.system();
            let (before, after) = (self.gate.previous(), self.gate.state());
            let step = Step {
                label,
                picks: self.chosen.picks(self.gate.enabled()),
            };
            let w = &mut self.monitor.watches[k];
            let p = &system.properties[w.property];
            let Some(spec) = bounded(p) else { continue };
            let was_waiting = w.watch.waiting.is_some();
            let counted = w.watch.waiting.unwrap_or(0);
            let passed = !w.late
                && w.watch
                    .observe(system, spec, before, step, after, &w.context)?;
            if passed || w.late {
                // watched again without the bound: on the tick that passes it, `observe`
                // left the watch as it was
                let unbounded = ResponseSpec {
                    within: None,
                    ..spec
                };
                w.watch
                    .observe(system, unbounded, before, step, after, &w.context)?;
            }
            if !was_waiting && w.watch.waiting.is_some() {
                w.ticket = ticket;
            }
            w.late = (w.late || passed) && w.watch.waiting.is_some();
            if passed {
                let within = spec.within.unwrap_or(0);
                // the tick that passed the bound stands for one unit, or its advance
                let elapsed = counted + system.time_advance(before, step)?;
                let event = Event::ResponseLate {
                    property: Arc::clone(&w.name),
                    within,
                    elapsed_ticks: elapsed,
                    ticket: w.ticket,
                };
                self.stats.responses_late += 1;
                self.emit(event);
            }
        }
        Ok(())
    }
}
