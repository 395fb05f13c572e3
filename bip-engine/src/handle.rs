//! Requests from other threads: a [`Handle`] sends them to the engine's thread, and each
//! request gets its replies on a channel of its own.

use std::any::Any;
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::Arc;
use std::time::Duration;

use crate::error::RequestError;
use crate::event::{Event, Reply, Ticket};
use crate::types::Args;

/// A request from a [`Handle`], with where its replies go.
pub(crate) struct RemoteRequest {
    pub service: u32,
    pub args: Box<dyn Any + Send>,
    pub reply: Sender<(Ticket, Reply)>,
}

/// The engine's side: requests to take in, and where to send replies.
pub(crate) struct Remote {
    rx: Receiver<RemoteRequest>,
    tx: Sender<RemoteRequest>,
    waiting: Vec<(Ticket, Sender<(Ticket, Reply)>)>,
}

impl Remote {
    pub(crate) fn new() -> Remote {
        let (tx, rx) = channel();
        Remote {
            rx,
            tx,
            waiting: Vec::new(),
        }
    }

    /// A handle sending to this engine; `services` are (module, service, owned by the
    /// model, what its arguments may be) by service index.
    pub(crate) fn handle(&self, services: Arc<Vec<(String, String, bool, Args)>>) -> Handle {
        Handle {
            tx: self.tx.clone(),
            services,
        }
    }

    /// A request already sent, if any.
    pub(crate) fn try_take(&self) -> Option<RemoteRequest> {
        self.rx.try_recv().ok()
    }

    /// The next request, waiting at most `timeout`.
    pub(crate) fn wait(&self, timeout: Duration) -> Option<RemoteRequest> {
        self.rx.recv_timeout(timeout).ok()
    }

    /// Replies for `ticket` go to `reply`.
    pub(crate) fn register(&mut self, ticket: Ticket, reply: Sender<(Ticket, Reply)>) {
        self.waiting.push((ticket, reply));
    }

    pub(crate) fn deliver(&mut self, e: &Event) {
        let Event::Reply { ticket, reply, .. } = e else {
            return;
        };
        let Some(k) = self.waiting.iter().position(|(t, _)| t == ticket) else {
            return;
        };
        let _ = self.waiting[k].1.send((*ticket, reply.clone()));
        if matches!(reply, Reply::Refused(_) | Reply::Done { .. }) {
            self.waiting.swap_remove(k);
        }
    }
}

/// Sends requests to an engine running on another thread. Cheap to clone.
#[derive(Clone)]
pub struct Handle {
    tx: Sender<RemoteRequest>,
    /// (module, service, owned by the model, what its arguments may be), by service
    /// index.
    services: Arc<Vec<(String, String, bool, Args)>>,
}

/// The replies to one request: `Accepted`, then `Started` (an activity) and `Done`; or
/// `Refused`.
pub struct PendingReply {
    rx: Receiver<(Ticket, Reply)>,
}

impl PendingReply {
    /// The next reply, waiting at most `timeout`; `None` on timeout or when the engine
    /// is gone.
    pub fn next(&self, timeout: Duration) -> Option<(Ticket, Reply)> {
        self.rx.recv_timeout(timeout).ok()
    }

    /// The next reply if there is one already.
    pub fn try_next(&self) -> Option<(Ticket, Reply)> {
        self.rx.try_recv().ok()
    }
}

impl Handle {
    pub fn request<A: Any + Send>(
        &self,
        module: &str,
        service: &str,
        args: A,
    ) -> Result<PendingReply, RequestError> {
        let Some(k) = self
            .services
            .iter()
            .position(|(m, s, _, _)| m == module && s == service)
        else {
            return Err(RequestError::UnknownService(module.into(), service.into()));
        };
        if self.services[k].2 {
            return Err(RequestError::OwnedByModel(module.into(), service.into()));
        }
        self.services[k].3.check(&args)?;
        let (reply, rx) = channel();
        // a closed engine simply never replies
        let _ = self.tx.send(RemoteRequest {
            service: k as u32,
            args: Box::new(args),
            reply,
        });
        Ok(PendingReply { rx })
    }
}
