//! Requests from other threads: a [`Handle`] sends them to the engine's thread, and each
//! request gets its replies on a channel of its own.

use std::any::Any;
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError, Sender};
use std::sync::Arc;
use std::time::Duration;

use crate::engine::Engine;
use crate::error::RequestError;
use crate::event::{Event, Reply, Ticket};

struct RemoteRequest {
    service: u32,
    args: Box<dyn Any + Send>,
    reply: Sender<(Ticket, Reply)>,
}

/// The engine's side: requests to take in, and where to send replies.
pub(crate) struct Remote {
    rx: Receiver<RemoteRequest>,
    tx: Sender<RemoteRequest>,
    waiting: Vec<(Ticket, Sender<(Ticket, Reply)>)>,
}

impl Remote {
    pub(crate) fn deliver(&mut self, e: &Event) {
        let Event::Reply { ticket, reply, .. } = e else {
            return;
        };
        let Some(k) = self.waiting.iter().position(|(t, _)| t == ticket) else {
            return;
        };
        let _ = self.waiting[k].1.send((*ticket, reply.clone()));
        if matches!(reply, Reply::Refused(_) | Reply::Done(_)) {
            self.waiting.swap_remove(k);
        }
    }
}

/// Sends requests to an engine running on another thread. Cheap to clone.
#[derive(Clone)]
pub struct Handle {
    tx: Sender<RemoteRequest>,
    /// (module, service, owned by the model), by service index.
    services: Arc<Vec<(String, String, bool)>>,
}

/// The replies to one request: `Accepted` then `Done`, or `Refused`.
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
            .position(|(m, s, _)| m == module && s == service)
        else {
            return Err(RequestError::UnknownService(module.into(), service.into()));
        };
        if self.services[k].2 {
            return Err(RequestError::OwnedByModel(module.into(), service.into()));
        }
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

impl Engine {
    /// A handle for sending requests from other threads while this engine runs
    /// ([`Engine::run_until`] takes them in between steps and while it waits).
    pub fn handle(&mut self) -> Handle {
        let services = Arc::new(
            (0..)
                .map_while(|k| {
                    let id = crate::ServiceId(k);
                    (k < self.service_count() as u32).then(|| {
                        let (m, s) = self.service_name(id);
                        let owned = self.request_target(m, s).is_err();
                        (m.to_string(), s.to_string(), owned)
                    })
                })
                .collect(),
        );
        let remote = self.remote.get_or_insert_with(|| {
            let (tx, rx) = channel();
            Remote {
                rx,
                tx,
                waiting: Vec::new(),
            }
        });
        Handle {
            tx: remote.tx.clone(),
            services,
        }
    }

    pub(crate) fn drain_remote(&mut self) {
        loop {
            let Some(r) = &mut self.remote else { return };
            let req = match r.rx.try_recv() {
                Ok(req) => req,
                Err(_) => return,
            };
            self.take_remote(req);
        }
    }

    fn take_remote(&mut self, req: RemoteRequest) {
        let ticket = self.new_ticket();
        if let Some(r) = &mut self.remote {
            r.waiting.push((ticket, req.reply));
        }
        self.enqueue(ticket, req.service, req.args);
    }

    /// Waits for a request until the clock reaches `t`.
    pub(crate) fn wait_remote(&mut self, t: u64) {
        let now = self.now_us();
        if t > now {
            let got = match &self.remote {
                Some(r) => r.rx.recv_timeout(Duration::from_micros(t - now)),
                None => Err(RecvTimeoutError::Disconnected),
            };
            if let Ok(req) = got {
                self.take_remote(req);
                return;
            }
        }
        self.sleep_clock_until(t);
    }
}
