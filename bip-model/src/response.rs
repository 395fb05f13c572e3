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

/// Whether a property's trigger and response happen at one point of a run: in the run's
/// first state, or on a step, which counts with the state it leads to (a step into a state
/// where a state condition holds is where that condition happens).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Happenings {
    pub trigger: bool,
    pub response: bool,
}

impl Happenings {
    /// Whether a trigger waits after this point, if one waited before it: the response
    /// counts before the trigger, so a point that is both answers itself (and answers
    /// whatever waited); a trigger while one waits changes nothing. This is the one rule
    /// every method applies: the verifier's bounded observer and cycle search, its
    /// symbolic encoding, the engine's monitor and replay.
    pub fn waits_after(self, waited: bool) -> bool {
        !self.response && (waited || self.trigger)
    }

    /// A trigger starts a new wait here.
    pub fn starts_wait(self, waited: bool) -> bool {
        !waited && self.waits_after(waited)
    }
}

impl System {
    /// Where `spec`'s trigger and response happen in the run's first state `init`. Both
    /// are evaluated, whatever the first says: a range error in either is the property's.
    pub fn happenings_in(
        &self,
        spec: ResponseSpec<'_>,
        init: &State,
        context: &str,
    ) -> Result<Happenings, RangeError> {
        let trigger = self.happens_in(spec.trigger, init, context)?;
        let response = self.happens_in(spec.response, init, context)?;
        Ok(Happenings { trigger, response })
    }

    /// Where `spec`'s trigger and response happen on the step from `before` to `after`,
    /// counting the state it leads to. All four (each on the step and in `after`) are
    /// evaluated: a range error in any is the property's.
    pub fn happenings_on(
        &self,
        spec: ResponseSpec<'_>,
        before: &State,
        step: Step<'_>,
        after: &State,
        context: &str,
    ) -> Result<Happenings, RangeError> {
        let on = self.happens_on_step(spec, before, step, after, context)?;
        let into = self.happenings_in(spec, after, context)?;
        Ok(Happenings {
            trigger: on.trigger || into.trigger,
            response: on.response || into.response,
        })
    }

    /// Where `spec`'s step patterns happen on the step alone (state conditions never do).
    fn happens_on_step(
        &self,
        spec: ResponseSpec<'_>,
        before: &State,
        step: Step<'_>,
        after: &State,
        context: &str,
    ) -> Result<Happenings, RangeError> {
        let trigger = self.happens_on(spec.trigger, before, step, after, context)?;
        let response = self.happens_on(spec.response, before, step, after, context)?;
        Ok(Happenings { trigger, response })
    }

    /// The first range error in evaluating `spec` along `path` (steps from the initial
    /// state, each with the state it leads to), and the number of steps to the state where
    /// it is met: a state where the trigger or response cannot be evaluated, or the state
    /// a step starts from on which they cannot be (the place the explicit method reports).
    pub fn first_range_error(
        &self,
        spec: ResponseSpec<'_>,
        path: &[(OwnedStep, State)],
        context: &str,
    ) -> Option<(usize, RangeError)> {
        let init = self.initial_state();
        let state_at = |k: usize| if k == 0 { &init } else { &path[k - 1].1 };
        for k in 0..=path.len() {
            if let Err(e) = self.happenings_in(spec, state_at(k), context) {
                return Some((k, e));
            }
            if let Some((s, after)) = path.get(k) {
                if let Err(e) = self.happens_on_step(spec, state_at(k), s.as_step(), after, context)
                {
                    return Some((k, e));
                }
            }
        }
        None
    }

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
        let mut watch = ResponseWatch::start(self, spec, &init, context)?;
        let end = loop_start.unwrap_or(path.len());
        for k in 0..end {
            let (s, after) = &path[k];
            if watch.observe(self, spec, state_at(k), s.as_step(), after, context)? {
                return Ok(loop_start.is_none() && k + 1 == path.len());
            }
        }
        let Some(start) = loop_start else {
            let mut steps = crate::steps::Steps::new();
            let last = state_at(path.len());
            self.enabled_steps(last, &mut steps)?;
            return Ok(watch.waiting.is_some() && steps.is_empty());
        };
        if start >= path.len() || path[path.len() - 1].1 != *state_at(start) {
            return Ok(false);
        }
        // around the cycle, the wait must go on at every step, and time pass
        let mut waiting = watch.waiting.is_some();
        let mut ticked = !self.has_time();
        for (k, (s, after)) in path.iter().enumerate().skip(start) {
            let h = self.happenings_on(spec, state_at(k), s.as_step(), after, context)?;
            if h.response {
                return Ok(false);
            }
            waiting = h.waits_after(waiting);
            ticked |= self.role(s.label) == Role::Time;
        }
        // a cycle without a tick goes on forever only where time cannot pass at all
        if waiting && !ticked && self.time_can_pass(state_at(start))? == Some(false) {
            ticked = true;
        }
        Ok(waiting && ticked)
    }
}

/// A response property watched along a run, step by step, as the verifier's bounded
/// observer counts: the time units since the oldest trigger not yet answered (each tick
/// counts its `advance`, [`System::time_advance`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ResponseWatch {
    /// The time units since the oldest unanswered trigger, if one waits.
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
        let h = system.happenings_in(spec, init, context)?;
        Ok(ResponseWatch {
            waiting: h.waits_after(false).then_some(0),
        })
    }

    /// Watches one step; true if it is a tick that takes the time since a trigger still
    /// waiting past the bound (the watch then stays as it was).
    pub fn observe(
        &mut self,
        system: &System,
        spec: ResponseSpec<'_>,
        before: &State,
        step: Step<'_>,
        after: &State,
        context: &str,
    ) -> Result<bool, RangeError> {
        let h = system.happenings_on(spec, before, step, after, context)?;
        if let Some(c) = self.waiting {
            let units = system.time_advance(before, step)?;
            if units > 0 {
                let after = c.saturating_add(units);
                if spec.within.is_some_and(|k| after > k) {
                    return Ok(true);
                }
                self.waiting = Some(after);
            }
        }
        if !h.waits_after(self.waiting.is_some()) {
            self.waiting = None;
        } else if h.starts_wait(self.waiting.is_some()) {
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
