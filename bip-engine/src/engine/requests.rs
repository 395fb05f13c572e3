//! Requests: queued by [`Engine::request`], served at quiescent points, accepted when the
//! model enables their request interaction and refused with the failing conditions when
//! not (docs/engine.md, "Requests, replies and refusals").

use alloc::sync::Arc;
use core::any::Any;

#[allow(unused_imports)]
use crate::prelude::*;

use super::replies::Cause;
use super::{Engine, Stepped};
use crate::error::{EngineError, RequestError, StepAsError};
use crate::event::{Event, Outcome, Output, Reasons, Refusal, Reply, Ticket};

impl Engine {
    /// Queues a request for `module.service` with arguments its codels can read
    /// ([`crate::Ctx::args`]). The engine serves it at its next quiescent point: the reply
    /// ([`Event::Reply`]) says whether the model accepted it, and later how the activity
    /// ended.
    ///
    /// `()` sends no arguments. Any other value must be of the type the service declares
    /// (docs/model.md, "Data types": `Float` is an `f64`, `Int` an `i64` within its range,
    /// a record or a Rust type a type of that name), or, if it declares none, go to an
    /// activity: a function has no codel to read arguments. Otherwise the request is an
    /// error that names the service and both types.
    pub fn request<A: Any + Send>(
        &mut self,
        module: &str,
        service: &str,
        args: A,
    ) -> Result<Ticket, RequestError> {
        let s = self.request_target(module, service)?;
        self.t.services[s as usize].args.check(&args)?;
        let ticket = self.new_ticket();
        self.requests
            .inbox
            .push_back((ticket, s, Some(Box::new(args))));
        Ok(ticket)
    }

    pub(crate) fn request_target(&self, module: &str, service: &str) -> Result<u32, RequestError> {
        let Some(s) = self.t.service_index(module, service) else {
            return Err(RequestError::UnknownService(module.into(), service.into()));
        };
        if self.t.services[s].owned {
            return Err(RequestError::OwnedByModel(module.into(), service.into()));
        }
        if self.t.services[s].request.is_none() {
            return Err(RequestError::TaskMachine(module.into(), service.into()));
        }
        Ok(s as u32)
    }

    pub(crate) fn new_ticket(&mut self) -> Ticket {
        self.requests.next_ticket += 1;
        Ticket(self.requests.next_ticket)
    }

    #[cfg(feature = "std")]
    pub(crate) fn enqueue(&mut self, ticket: Ticket, service: u32, args: Box<dyn Any + Send>) {
        self.requests.inbox.push_back((ticket, service, Some(args)));
    }

    pub(super) fn serve_request(
        &mut self,
        ticket: Ticket,
        service: u32,
        args: Option<Box<dyn Any + Send>>,
    ) -> Result<Stepped, EngineError> {
        // `request_target` queues no request for a task's machine, which has none
        let request = self.t.services[service as usize].request;
        if let Some(i) = request.filter(|&i| self.gate.enabled().is_enabled(i)) {
            if self.has_codels_at_request(service) {
                return self
                    .serve_at_request(ticket, service, args, false)
                    .map_err(|e| match e {
                        StepAsError::Engine(e) => e,
                        // not forced: no step to diverge from
                        _ => EngineError::Stopped(self.internal_error()),
                    });
            }
            self.take_step_of(i);
            self.accept_request(ticket, service, args)?;
            return Ok(Stepped::Request {
                ticket,
                accepted: true,
            });
        }
        let mask = self.failing(&self.t.services[service as usize].refusals)?;
        let refusal = if mask == 0 {
            Refusal::NotEnabled
        } else {
            Refusal::Conditions(Reasons(mask))
        };
        self.stats.requests_refused += 1;
        let s = &self.t.services[service as usize];
        tracing::info!(target: "bip_engine", ticket = ticket.0, module = s.module.as_str(),
            service = s.name.as_str(), "request refused");
        self.emit(Event::Reply {
            ticket,
            service: Arc::clone(&self.t.services[service as usize].name_ref),
            reply: Reply::Refused(refusal),
        });
        Ok(Stepped::Request {
            ticket,
            accepted: false,
        })
    }

    /// Commits the chosen request step and replies.
    pub(super) fn accept_request(
        &mut self,
        ticket: Ticket,
        service: u32,
        args: Option<Box<dyn Any + Send>>,
    ) -> Result<(), EngineError> {
        self.accept_with(ticket, service, args, Outcome::Ether, None)
    }

    /// Commits the chosen request step and replies; a function or attribute is done at
    /// once, with `outcome` and `output` (its codel's).
    pub(super) fn accept_with(
        &mut self,
        ticket: Ticket,
        service: u32,
        args: Option<Box<dyn Any + Send>>,
        outcome: Outcome,
        output: Option<Output>,
    ) -> Result<(), EngineError> {
        self.stats.requests_accepted += 1;
        self.emit(Event::Reply {
            ticket,
            service: Arc::clone(&self.t.services[service as usize].name_ref),
            reply: Reply::Accepted,
        });
        self.commit(Cause::Request {
            service,
            ticket: Some(ticket),
            args,
        })?;
        if self.t.services[service as usize].activity.is_none() {
            // a function or attribute runs at once
            self.emit(Event::Reply {
                ticket,
                service: Arc::clone(&self.t.services[service as usize].name_ref),
                reply: Reply::Done { outcome, output },
            });
        }
        Ok(())
    }
}
