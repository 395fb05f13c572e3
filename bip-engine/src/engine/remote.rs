//! The engine's side of [`Handle`]s: requests from other threads, taken in between steps
//! and while the engine waits.

use std::sync::Arc;
use std::time::Duration;

use super::Engine;
use crate::event::ServiceId;
use crate::handle::{Handle, Remote, RemoteRequest};

impl Engine {
    /// A handle for sending requests from other threads while this engine runs
    /// ([`Engine::run_until`] takes them in between steps and while it waits).
    pub fn handle(&mut self) -> Handle {
        let services = Arc::new(
            (0..self.t.services.len() as u32)
                .map(|k| {
                    let (m, s) = self.inspect().service_name(ServiceId(k));
                    let owned = self.request_target(m, s).is_err();
                    let args = self.t.services[k as usize].args.clone();
                    (m.to_string(), s.to_string(), owned, args)
                })
                .collect(),
        );
        self.remote.get_or_insert_with(Remote::new).handle(services)
    }

    pub(super) fn drain_remote(&mut self) {
        while let Some(req) = self.remote.as_ref().and_then(Remote::try_take) {
            self.take_remote(req);
        }
    }

    fn take_remote(&mut self, req: RemoteRequest) {
        let ticket = self.new_ticket();
        if let Some(r) = &mut self.remote {
            r.register(ticket, req.reply);
        }
        self.enqueue(ticket, req.service, req.args);
    }

    /// Waits for a request until the clock reaches `t`.
    pub(super) fn wait_remote(&mut self, t: u64) {
        let now = self.time.clock.now_us();
        if t > now {
            let got = match &self.remote {
                Some(r) => r.wait(Duration::from_micros(t - now)),
                None => None,
            };
            if let Some(req) = got {
                self.take_remote(req);
                return;
            }
        }
        self.time.clock.sleep_until(t);
    }
}
