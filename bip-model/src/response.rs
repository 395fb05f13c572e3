//! What a response property watches for (docs/model.md, "Response and liveness"): whether
//! a state or a step is a trigger or a response. The verifier's cycle search and bounded
//! observer and a run-time monitor ask these, so that all mean the same thing.

#[allow(unused_imports)]
use crate::prelude::*;

use crate::model::{Happens, RangeError, Role, StepPattern};
use crate::state::State;
use crate::steps::{Label, OwnedStep, Step};
use crate::system::System;

impl System {
    /// True if `happens` is a state condition that holds in `state`; a step pattern never
    /// happens in a state alone.
    pub fn happens_in(
        &self,
        happens: &Happens,
        state: &State,
        context: &str,
    ) -> Result<bool, RangeError> {
        match happens {
            Happens::State(e) => self.holds(e, state, context),
            Happens::Step(_) => Ok(false),
        }
    }

    /// True if `happens` is a step pattern that the step from `before` to `after` matches;
    /// a state condition never happens on a step alone.
    pub fn happens_on(
        &self,
        happens: &Happens,
        before: &State,
        step: Step<'_>,
        after: &State,
        context: &str,
    ) -> Result<bool, RangeError> {
        let Happens::Step(patterns) = happens else {
            return Ok(false);
        };
        for p in patterns {
            if self.matches(p, before, step.label, after, context)? {
                return Ok(true);
            }
        }
        Ok(false)
    }

    fn matches(
        &self,
        p: &StepPattern,
        before: &State,
        label: Label,
        after: &State,
        context: &str,
    ) -> Result<bool, RangeError> {
        if !p.connectors.is_empty() {
            let Label::Interaction(i) = label else {
                return Ok(false);
            };
            if !p
                .connectors
                .contains(&self.interactions[i as usize].connector)
            {
                return Ok(false);
            }
        }
        if let Some(e) = &p.before {
            if !self.holds(e, before, context)? {
                return Ok(false);
            }
        }
        match &p.after {
            Some(e) => self.holds(e, after, context),
            None => Ok(true),
        }
    }
}

/// A response property's trigger, response and bound, as the compiled property holds them.
#[derive(Clone, Copy, Debug)]
pub struct ResponseSpec<'a> {
    pub trigger: &'a Happens,
    pub response: &'a Happens,
    pub within: Option<u64>,
}

impl System {
    /// True if `path` (steps from the initial state, each with the state it leads to; a
    /// lasso if `loop_start` is given) shows that `spec` fails: for a lasso, a trigger
    /// waits when the cycle starts or comes on it, and the cycle has no response and, in a
    /// model with time, a tick, or its states are timelocked ([`System::time_can_pass`]:
    /// time cannot pass from them); for a finite path, a tick past the bound on the last step,
    /// or a trigger still waiting in a last state that has no step.
    pub fn shows_unanswered(
        &self,
        spec: ResponseSpec<'_>,
        path: &[(OwnedStep, State)],
        loop_start: Option<usize>,
        context: &str,
    ) -> Result<bool, RangeError> {
        let init = self.initial_state();
        let state_at = |k: usize| if k == 0 { &init } else { &path[k - 1].1 };
        let trig = |k: usize| -> Result<bool, RangeError> {
            self.happens_in(spec.trigger, state_at(k), context)
        };
        let resp = |k: usize| -> Result<bool, RangeError> {
            self.happens_in(spec.response, state_at(k), context)
        };
        let step_trig = |k: usize| -> Result<bool, RangeError> {
            let (s, after) = &path[k];
            self.happens_on(spec.trigger, state_at(k), s.as_step(), after, context)
        };
        let step_resp = |k: usize| -> Result<bool, RangeError> {
            let (s, after) = &path[k];
            self.happens_on(spec.response, state_at(k), s.as_step(), after, context)
        };
        let tick = |k: usize| self.role(path[k].0.label) == Role::Time;
        let mut watch = ResponseWatch::start(self, spec, &init, context)?;
        let end = loop_start.unwrap_or(path.len());
        for k in 0..end {
            let (s, after) = &path[k];
            if watch.observe(self, spec, state_at(k), s.as_step(), after, context)? {
                return Ok(loop_start.is_none() && k + 1 == path.len());
            }
        }
        let waiting = watch.waiting;
        let Some(start) = loop_start else {
            let mut steps = crate::steps::Steps::new();
            let last = state_at(path.len());
            self.enabled_steps(last, &mut steps)?;
            return Ok(waiting.is_some() && steps.is_empty());
        };
        if start >= path.len() || path[path.len() - 1].1 != *state_at(start) {
            return Ok(false);
        }
        let mut triggered = waiting.is_some();
        let mut ticked = !self.has_time();
        for k in start..path.len() {
            if step_resp(k)? || resp(k + 1)? {
                return Ok(false);
            }
            triggered |= step_trig(k)? || trig(k + 1)?;
            ticked |= tick(k);
        }
        // a cycle without a tick goes on forever only where time cannot pass at all
        if triggered && !ticked && self.time_can_pass(state_at(start))? == Some(false) {
            ticked = true;
        }
        Ok(triggered && ticked && !resp(start)?)
    }
}

/// A response property watched along a run, step by step, as the verifier's bounded
/// observer counts: the ticks since the oldest trigger not yet answered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ResponseWatch {
    /// The ticks since the oldest unanswered trigger, if one waits.
    pub waiting: Option<u64>,
}

impl ResponseWatch {
    /// The watch in the run's first state.
    pub fn start(
        system: &System,
        spec: ResponseSpec<'_>,
        init: &State,
        context: &str,
    ) -> Result<Self, RangeError> {
        let waiting = (system.happens_in(spec.trigger, init, context)?
            && !system.happens_in(spec.response, init, context)?)
        .then_some(0);
        Ok(ResponseWatch { waiting })
    }

    /// Watches one step; true if it is a tick that passes the bound of a trigger still
    /// waiting (the watch then stays as it was).
    pub fn observe(
        &mut self,
        system: &System,
        spec: ResponseSpec<'_>,
        before: &State,
        step: Step<'_>,
        after: &State,
        context: &str,
    ) -> Result<bool, RangeError> {
        if let Some(c) = self.waiting {
            if system.role(step.label) == Role::Time {
                if spec.within == Some(c) {
                    return Ok(true);
                }
                self.waiting = Some(c + 1);
            }
        }
        if system.happens_on(spec.response, before, step, after, context)?
            || system.happens_in(spec.response, after, context)?
        {
            self.waiting = None;
        } else if self.waiting.is_none()
            && (system.happens_on(spec.trigger, before, step, after, context)?
                || system.happens_in(spec.trigger, after, context)?)
        {
            self.waiting = Some(0);
        }
        Ok(false)
    }
}

impl crate::model::PropertyKind {
    /// The trigger, response and bound of a response property.
    pub fn response_spec(&self) -> Option<ResponseSpec<'_>> {
        match self {
            crate::model::PropertyKind::Response {
                trigger,
                response,
                within,
            } => Some(ResponseSpec {
                trigger,
                response,
                within: *within,
            }),
            _ => None,
        }
    }
}
