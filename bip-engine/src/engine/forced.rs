//! Taking a given step, if the model allows it now: for replaying a trace through the
//! engine (`crate::replay`).

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::{Label, Step};

use super::replies::Cause;
use super::{Engine, Stepped};
use crate::bind::InterKind;
use crate::error::{EngineError, StepAsError};
use crate::event::{CodelId, Ticket};

impl Engine {
    /// Takes exactly `step`, if the model allows it now: a codel step runs the codel,
    /// whose outcome must lead to this very step (a default codel does what the step
    /// says); a request step is a request from the engine; a time step is a tick. For
    /// replaying a trace through the engine.
    ///
    /// A step taken into a state with a range error (a guard, a `when`, a watched property
    /// that cannot be evaluated there) stops the engine after it:
    /// [`StepAsError::TakenThenStopped`].
    pub(crate) fn step_as(&mut self, step: Step<'_>) -> Result<Stepped, StepAsError> {
        let before = self.stats.steps;
        match self.take_as(step) {
            Err(StepAsError::Engine(EngineError::Range(error))) if self.stats.steps > before => {
                Err(StepAsError::TakenThenStopped(error))
            }
            taken => taken,
        }
    }

    fn take_as(&mut self, step: Step<'_>) -> Result<Stepped, StepAsError> {
        if let Some(e) = &self.stopped {
            return Err(EngineError::Stopped(e.clone()).into());
        }
        let allowed = match step.label {
            Label::Interaction(i) => self
                .gate
                .enabled()
                .steps_of(i)
                .any(|s| s.picks == step.picks),
            Label::Internal { .. } => self.gate.enabled().internal_steps().any(|s| s == step),
        };
        if !allowed {
            return Err(StepAsError::NotAllowed);
        }
        self.forced.clear();
        self.forced.extend_from_slice(step.picks);
        let kind = match step.label {
            Label::Interaction(i) => self.t.kind[i as usize],
            Label::Internal { .. } => InterKind::Progress,
        };
        self.chosen.set_copied(step);
        match kind {
            #[cfg(feature = "std")]
            InterKind::Codel { codel, .. } if self.t.codels[codel as usize].map.apart.is_some() => {
                self.run_outcome(codel, true)
            }
            InterKind::Codel { codel, .. } if self.t.codels[codel as usize].map.timed.is_some() => {
                self.finish_timed(codel, true)
            }
            InterKind::Codel { codel, .. } => self.run_codel(codel, true),
            InterKind::TimedStart { codel } => self.start_timed(codel, true),
            InterKind::Dropped { codel } => self.drop_timed(codel, true),
            #[cfg(feature = "std")]
            InterKind::Start { codel } => self.start_apart(codel, true),
            #[cfg(feature = "std")]
            InterKind::Return { codel } => self.force_return(codel),
            #[cfg(not(feature = "std"))]
            InterKind::Start { .. } | InterKind::Return { .. } => {
                Err(EngineError::Stopped(self.internal_error()).into())
            }
            InterKind::Request { service } if self.has_codels_at_request(service) => {
                let ticket = self.new_ticket();
                self.serve_at_request(ticket, service, None, true)
            }
            InterKind::AtRequestFail { codel } => {
                let ticket = self.new_ticket();
                let service = self.t.codels[codel as usize].service;
                self.serve_at_request(ticket, service, None, true)
            }
            InterKind::Request { service } => {
                let ticket = self.new_ticket();
                self.accept_request(ticket, service, None)?;
                Ok(Stepped::Request {
                    ticket,
                    accepted: true,
                })
            }
            InterKind::Time if self.timed.is_some() => {
                let Label::Interaction(i) = step.label else {
                    return Err(StepAsError::NotAllowed);
                };
                self.fire_timed_tick(i, true)?;
                Ok(Stepped::Tick)
            }
            InterKind::Time => {
                self.commit(Cause::Other)?;
                self.count_tick();
                Ok(Stepped::Tick)
            }
            InterKind::Progress | InterKind::Environment => {
                self.commit(self.progress_cause(step.label))?;
                Ok(Stepped::Other)
            }
        }
    }

    /// What a step with `label` that was just committed was, to the engine (for a step
    /// [`StepAsError::TakenThenStopped`] took).
    pub(crate) fn stepped_by(&self, label: Label) -> Stepped {
        let Label::Interaction(i) = label else {
            return Stepped::Other;
        };
        match self.t.kind[i as usize] {
            InterKind::Codel { codel, fail } => Stepped::Codel {
                codel: CodelId(codel),
                failed: fail,
            },
            InterKind::Request { .. } => Stepped::Request {
                ticket: Ticket(self.requests.next_ticket),
                accepted: true,
            },
            // a validation's failure refuses the request; a function's accepts it
            InterKind::AtRequestFail { codel } => Stepped::Request {
                ticket: Ticket(self.requests.next_ticket),
                accepted: self.t.services[self.t.codels[codel as usize].service as usize].validate
                    != Some(codel),
            },
            InterKind::Time => Stepped::Tick,
            InterKind::Start { .. }
            | InterKind::Return { .. }
            | InterKind::TimedStart { .. }
            | InterKind::Dropped { .. }
            | InterKind::Progress
            | InterKind::Environment => Stepped::Other,
        }
    }

    pub(super) fn forced_is(&self, interaction: u32) -> bool {
        // the forced step is a step of `interaction` if it is enabled among its steps
        self.gate
            .enabled()
            .steps_of(interaction)
            .any(|s| s.picks == &self.forced[..])
    }
}
