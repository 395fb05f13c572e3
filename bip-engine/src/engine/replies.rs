//! Replies to requests, by following the activities' life cycles through the committed
//! step's picks (docs/genom.md, section 2, the activity atom).

use alloc::sync::Arc;
use core::any::Any;

#[allow(unused_imports)]
use crate::prelude::*;

use super::Engine;
use crate::bind::PortKind;
use crate::event::{Event, Fault, FaultKind, Outcome, Output, Reply, Ticket};
use bip_model::Label;

/// Why a step is committed, for replies.
pub(super) enum Cause {
    Request {
        service: u32,
        ticket: Option<Ticket>,
        args: Option<Box<dyn Any + Send>>,
    },
    Codel {
        /// The outcome of a failed codel (exception or fault).
        error: Option<Outcome>,
    },
    /// A pending request of `service` sends its interrupts again.
    Interrupts {
        service: u32,
    },
    Other,
}

impl Engine {
    /// Why a progress step of `label` is committed: a pending request's interrupts, or
    /// another step of the model.
    pub(super) fn progress_cause(&self, label: Label) -> Cause {
        match label {
            Label::Interaction(i) => self.t.interrupts_of[i as usize]
                .map_or(Cause::Other, |service| Cause::Interrupts { service }),
            Label::Internal { .. } => Cause::Other,
        }
    }

    /// Follows the activities' life cycles through the step's picks to reply to the
    /// requests they serve (docs/genom.md, section 2, the activity atom).
    pub(super) fn track(&mut self, cause: Cause) {
        let (mut req_ticket, mut req_args, req_service, mut error) = match cause {
            Cause::Request {
                service,
                ticket,
                args,
            } => (ticket, args, Some(service), None),
            Cause::Codel { error, .. } => (None, None, None, error),
            Cause::Interrupts { service } => (None, None, Some(service), None),
            Cause::Other => (None, None, None, None),
        };
        for k in 0..self.chosen.picks(self.gate.enabled()).len() {
            let p = self.chosen.picks(self.gate.enabled())[k];
            // a tick, a codel that neither starts nor ends its activity, another component
            if !self.t.moves_request(p) {
                continue;
            }
            let Some(svc) = self.t.activity_of[p.component as usize] else {
                continue;
            };
            let tr = &self.gate.system().atom_of(p.component).transitions[p.transition as usize];
            let Some(port) = tr.port else { continue };
            let Some(a) = self.t.services[svc as usize].activity.as_ref() else {
                continue;
            };
            let kind = match a.port_kind.get(port as usize).copied().flatten() {
                Some(PortKind::Tick) | None => continue,
                Some(kind) => kind,
            };
            let from_ether = tr.from == a.ether;
            let to_ether = tr.to == a.ether;
            // the step is committed: what held before it is in the state before
            let slots = self.gate.previous().slots();
            let req_before = slots[a.req_slot as usize] != 0;
            let stopping_before = a.stopping_slot.is_some_and(|sl| slots[sl as usize] != 0);
            let mut replies: [Option<(Ticket, Reply)>; 3] = [None, None, None];
            let mut n = 0;
            let mut reply = |t: Option<Ticket>, r: Reply| {
                if let Some(t) = t {
                    replies[n] = Some((t, r));
                    n += 1;
                }
            };
            let done = |outcome: Outcome, output: Option<Output>| Reply::Done { outcome, output };
            // what ends the activity of another request: a request (the service's own,
            // which replaces it, or one that interrupts it), or the model's abort rule
            let cut = match kind {
                PortKind::Abort => Some(Outcome::Aborted),
                PortKind::Request | PortKind::Interrupt => Some(Outcome::Interrupted {
                    by: req_service.map(|s| Arc::clone(&self.t.services[s as usize].name_ref)),
                }),
                _ => None,
            };
            let Some(a) = self.t.services[svc as usize].activity.as_mut() else {
                continue;
            };
            match (kind, cut) {
                (_, Some(cut)) => {
                    if !from_ether && !stopping_before {
                        reply(a.current.take(), done(cut.clone(), a.output.take()));
                        a.current_args = None;
                    }
                    if req_before {
                        reply(a.pending.take(), done(cut, None));
                        a.pending_args = None;
                    }
                    if kind == PortKind::Request {
                        let (ticket, args) = if req_service == Some(svc) {
                            (req_ticket.take(), req_args.take())
                        } else {
                            (None, None)
                        };
                        a.pending = ticket;
                        a.pending_args = args;
                    }
                }
                (PortKind::Run(_), None) => {
                    if from_ether {
                        a.current = a.pending.take();
                        a.current_args = a.pending_args.take();
                        reply(a.current, Reply::Started);
                    }
                    if to_ether {
                        reply(a.current.take(), done(Outcome::Ether, a.output.take()));
                        a.current_args = None;
                    }
                }
                (PortKind::Fail(c), None) => {
                    if from_ether {
                        a.current = a.pending.take();
                        a.current_args = a.pending_args.take();
                        reply(a.current, Reply::Started);
                    }
                    let o = error.take().unwrap_or_else(|| {
                        Outcome::Fault(Fault {
                            codel: Arc::clone(&self.t.codels[c as usize].name),
                            kind: FaultKind::Replayed,
                        })
                    });
                    reply(a.current.take(), done(o, a.output.take()));
                    a.current_args = None;
                }
                _ => {}
            }
            // taken in place: moving the array out would copy all three replies
            for r in &mut replies[..n] {
                if let Some((ticket, reply)) = r.take() {
                    let service = Arc::clone(&self.t.services[svc as usize].name_ref);
                    self.emit(Event::Reply {
                        ticket,
                        service,
                        reply,
                    });
                }
            }
        }
    }
}
