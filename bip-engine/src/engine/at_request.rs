//! Codels that run at a request (docs/genom.md, "Codels at the request"): a service's
//! `validate` codel, whose failure refuses the request (a step of the model that changes
//! nothing), and a function's codel, whose success is the request's step and whose
//! failure, an exception or a fault, is the step that accepts the request with that
//! outcome. The model chooses among those steps; the engine takes the one the codel's
//! return names, as for any codel.

use alloc::sync::Arc;
use core::any::Any;

#[allow(unused_imports)]
use crate::prelude::*;

use super::codels::CodelEnd;
use super::replies::Cause;
use super::{Engine, Stepped};
use crate::codel::Body;
use crate::error::{EngineError, StepAsError};
use crate::event::{Event, Fault, FaultKind, Outcome, Refusal, Reply, Ticket};

impl Engine {
    /// Whether a request of `service` runs codels before its step.
    #[inline]
    pub(super) fn has_codels_at_request(&self, service: u32) -> bool {
        let s = &self.t.services[service as usize];
        s.validate.is_some() || s.function.is_some()
    }

    /// Serves a request of `service`, whose request the model accepts now, by running its
    /// codels at the request and taking the step their outcome names. With `forced`, the
    /// step must be the one in `self.forced` (a replay).
    pub(super) fn serve_at_request(
        &mut self,
        ticket: Ticket,
        service: u32,
        args: Option<Box<dyn Any + Send>>,
        forced: bool,
    ) -> Result<Stepped, StepAsError> {
        let s = &self.t.services[service as usize];
        let (validate, function, request) = (s.validate, s.function, s.request);
        let Some(request) = request else {
            return Err(StepAsError::NotAllowed);
        };
        self.runner.request_args = args;
        self.runner.request_output = None;
        if let Some(v) = validate {
            if let CodelEnd::Failed(outcome) = self.run_at_request(v, forced) {
                return self.refuse_by_validation(ticket, service, v, outcome, forced);
            }
        }
        let error = match function {
            None => {
                self.take_forced_or(request, forced)?;
                None
            }
            Some(f) => match self.run_at_request(f, forced) {
                CodelEnd::Yielded { yield_k }
                    if self.take_run_step(f as usize, yield_k, forced) =>
                {
                    None
                }
                CodelEnd::Yielded { .. } if forced => return Err(StepAsError::Diverged),
                // its writes are not a step of the model: its error path
                CodelEnd::Yielded { .. } => Some(Outcome::Fault(Fault {
                    codel: Arc::clone(&self.t.codels[f as usize].name),
                    kind: FaultKind::NotAllowed,
                })),
                CodelEnd::Failed(o) => Some(o),
            },
        };
        if let (Some(error), Some(f)) = (&error, function) {
            self.take_forced_or(self.t.codels[f as usize].map.fail, forced)?;
            self.report_error(f as usize, error);
        }
        let args = self.runner.request_args.take();
        let output = self.runner.request_output.take();
        self.accept_with(
            ticket,
            service,
            args,
            error.unwrap_or(Outcome::Ether),
            output,
        )?;
        Ok(Stepped::Request {
            ticket,
            accepted: true,
        })
    }

    /// Runs codel `c` at a request: its ids staged, the request's arguments and output at
    /// hand, its outcome judged as any codel's (a default codel's: the forced step's, or
    /// the policy's).
    fn run_at_request(&mut self, c: u32, forced: bool) -> CodelEnd {
        let ck = c as usize;
        self.stage_ids(ck);
        let t0 = self.time.clock.now_us();
        let end = match self.runner.bodies[ck] {
            Body::Default => self.default_end(ck, forced),
            _ => {
                let service = self.t.codels[ck].service as usize;
                let result = self.call_codel(ck, service, false, t0);
                self.classify(ck, result)
            }
        };
        let took = self.time.clock.now_us().saturating_sub(t0);
        self.stats.codels += 1;
        self.check_budgets(ck, t0, took, false);
        end
    }

    /// The validation `v` of `service` failed with `outcome`: its refusal step, and the
    /// reply.
    fn refuse_by_validation(
        &mut self,
        ticket: Ticket,
        service: u32,
        v: u32,
        outcome: Outcome,
        forced: bool,
    ) -> Result<Stepped, StepAsError> {
        self.take_forced_or(self.t.codels[v as usize].map.fail, forced)?;
        self.report_error(v as usize, &outcome);
        self.runner.request_args = None;
        self.stats.requests_refused += 1;
        self.commit(Cause::Other)?;
        self.emit(Event::Reply {
            ticket,
            service: Arc::clone(&self.t.services[service as usize].name_ref),
            reply: Reply::Refused(Refusal::Validation(outcome)),
        });
        Ok(Stepped::Request {
            ticket,
            accepted: false,
        })
    }

    /// Chooses a step of interaction `i`: the forced one (which must be one of them), or
    /// one by the policy.
    fn take_forced_or(&mut self, i: u32, forced: bool) -> Result<(), StepAsError> {
        if !forced {
            self.take_step_of(i);
        } else {
            let step = self
                .gate
                .enabled()
                .steps_of(i)
                .find(|s| s.picks == &self.forced[..]);
            if step.is_none() {
                return Err(StepAsError::Diverged);
            }
            self.chosen.set(self.gate.enabled(), step);
        }
        if self.chosen.picks(self.gate.enabled()).is_empty() {
            // the request's outcomes share its guard, so this cannot happen; report it
            return Err(StepAsError::Engine(EngineError::Stopped(
                self.internal_error(),
            )));
        }
        Ok(())
    }
}
