//! Replies to requests, by following the activities' life cycles through the committed
//! step's picks (docs/genom.md, section 2, the activity atom).

use core::any::Any;

#[allow(unused_imports)]
use crate::prelude::*;

use super::Engine;
use crate::bind::PortKind;
use crate::event::{CodelId, Event, Fault, FaultKind, Outcome, Reply, ServiceId, Ticket};

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
    Other,
}

impl Engine {
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
            let Some(a) = self.t.services[svc as usize].activity.as_mut() else {
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
            let mut replies: [Option<(Ticket, Outcome)>; 3] = [None, None, None];
            let mut n = 0;
            let mut reply = |t: Option<Ticket>, o: Outcome| {
                if let Some(t) = t {
                    replies[n] = Some((t, o));
                    n += 1;
                }
            };
            match kind {
                PortKind::Request => {
                    let (ticket, args) = if req_service == Some(svc) {
                        (req_ticket.take(), req_args.take())
                    } else {
                        (None, None)
                    };
                    if !from_ether && !stopping_before {
                        reply(a.current.take(), Outcome::Interrupted);
                        a.current_args = None;
                    }
                    if req_before {
                        reply(a.pending.take(), Outcome::Interrupted);
                    }
                    a.pending = ticket;
                    a.pending_args = args;
                }
                PortKind::Interrupt | PortKind::Abort => {
                    if !from_ether && !stopping_before {
                        reply(a.current.take(), Outcome::Interrupted);
                        a.current_args = None;
                    }
                    if req_before {
                        reply(a.pending.take(), Outcome::Interrupted);
                        a.pending_args = None;
                    }
                }
                PortKind::Run(_) => {
                    if from_ether {
                        a.current = a.pending.take();
                        a.current_args = a.pending_args.take();
                    }
                    if to_ether {
                        reply(a.current.take(), Outcome::Ether);
                        a.current_args = None;
                    }
                }
                PortKind::Fail(_) => {
                    if from_ether {
                        a.current = a.pending.take();
                        a.current_args = a.pending_args.take();
                    }
                    let o = error.take().unwrap_or(Outcome::Fault(Fault {
                        codel: CodelId(u32::MAX),
                        kind: FaultKind::Replayed,
                    }));
                    reply(a.current.take(), o);
                    a.current_args = None;
                }
                PortKind::Tick => {}
            }
            // taken in place: moving the array out would copy all three outcomes
            for r in &mut replies[..n] {
                if let Some((ticket, o)) = r.take() {
                    self.emit(Event::Reply {
                        ticket,
                        service: ServiceId(svc),
                        reply: Reply::Done(o),
                    });
                }
            }
        }
    }
}
