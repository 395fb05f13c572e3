//! Which module processes are there: the engine's view, so that a run of a module whose
//! process is gone or hung fails at once (its activity's error path) instead of waiting
//! for its deadline again, a request to it is refused with the reason, and a process that
//! comes back rejoins.
//!
//! A module process holds a zenoh liveliness token per module (`<prefix>/alive/<module>`):
//! zenoh withdraws it when the process's session closes (it died) or its lease expires (it
//! is cut off), and the engine hears it at once. A hung process keeps its token until its
//! lease expires; its first run past its deadline marks it absent. While a module is
//! absent, a thread asks its process for its codels (`hello`) every [`PROBE_EVERY`]; the
//! first answer with the codels the engine expects makes it present again.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Duration;

use zenoh::sample::SampleKind;
use zenoh::Wait;

use crate::network::NetworkError;
use crate::wire::{keys, Answer, Message};

/// How often an absent module's process is asked whether it is back.
pub const PROBE_EVERY: Duration = Duration::from_millis(100);

/// What the engine knows of one module's process.
#[derive(Default)]
struct ModuleState {
    /// `Service.codel`, in the engine's numbering: what a returning process must run.
    codels: Vec<String>,
    /// Why it cannot run codels now (`None`: it is there).
    absent: Option<String>,
    /// Bumped whenever the process may have changed (left, came, missed a deadline): its
    /// proxy then sends it every port's data again.
    epoch: u64,
}

/// The engine's view of its module processes, shared by the proxies of the remote
/// modules and the request server.
#[derive(Clone, Default)]
pub struct Presence {
    modules: Arc<Mutex<HashMap<String, ModuleState>>>,
}

impl Presence {
    fn lock(&self) -> MutexGuard<'_, HashMap<String, ModuleState>> {
        // a panic elsewhere never leaves the map half-written: each change is one
        // assignment
        self.modules.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Why module `module`'s process cannot run its codels now; `None` when it is there
    /// (or the module is not one of the engine's remote modules).
    pub fn absent(&self, module: &str) -> Option<String> {
        self.lock().get(module).and_then(|m| m.absent.clone())
    }

    /// A number that changes whenever the module's process may have changed.
    pub(crate) fn epoch(&self, module: &str) -> u64 {
        self.lock().get(module).map_or(0, |m| m.epoch)
    }

    pub(crate) fn expect(&self, module: &str, codels: Vec<String>) {
        self.lock().entry(module.to_string()).or_default().codels = codels;
    }

    /// Marks the module absent, for `why`, unless it is already.
    pub(crate) fn mark_absent(&self, module: &str, why: String) {
        let mut map = self.lock();
        let m = map.entry(module.to_string()).or_default();
        m.epoch += 1;
        if m.absent.is_none() {
            tracing::warn!(target: "bip_zenoh", module, "module process absent: {why}");
            m.absent = Some(why);
        }
    }

    fn changed(&self, module: &str) {
        if let Some(m) = self.lock().get_mut(module) {
            m.epoch += 1;
        }
    }

    pub(crate) fn mark_present(&self, module: &str) {
        let mut map = self.lock();
        if let Some(m) = map.get_mut(module) {
            if m.absent.take().is_some() {
                tracing::info!(target: "bip_zenoh", module, "module process back");
                m.epoch += 1;
            }
        }
    }

    /// The absent modules and the codels their processes must run.
    fn absent_modules(&self) -> Vec<(String, Vec<String>)> {
        self.lock()
            .iter()
            .filter(|(_, m)| m.absent.is_some())
            .map(|(k, m)| (k.clone(), m.codels.clone()))
            .collect()
    }
}

/// The watch of a layer's module processes: the liveliness subscriber and the thread
/// that probes absent ones; both end when it is dropped.
pub(crate) struct Watch {
    _subscriber: zenoh::pubsub::Subscriber<()>,
    stop: Arc<AtomicBool>,
    prober: Option<JoinHandle<()>>,
}

impl Watch {
    pub(crate) fn start(
        session: &zenoh::Session,
        prefix: &str,
        presence: &Presence,
    ) -> Result<Watch, NetworkError> {
        let alive = keys::alive(prefix, "*");
        let start = keys::alive(prefix, "");
        let seen = presence.clone();
        let subscriber = session
            .liveliness()
            .declare_subscriber(alive.as_str())
            .callback(move |sample| {
                let key = sample.key_expr().as_str();
                let Some(module) = key.get(start.len()..) else {
                    return;
                };
                match sample.kind() {
                    SampleKind::Delete => seen.mark_absent(
                        module,
                        "its process left the network (it ended, or its zenoh lease expired)"
                            .into(),
                    ),
                    SampleKind::Put => seen.changed(module),
                }
            })
            .wait()
            .map_err(|e| NetworkError::Open(format!("cannot watch `{alive}`: {e}")))?;
        let stop = Arc::new(AtomicBool::new(false));
        let prober = {
            let (stop, presence, session) = (Arc::clone(&stop), presence.clone(), session.clone());
            let prefix = prefix.to_string();
            std::thread::spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    std::thread::sleep(PROBE_EVERY);
                    for (module, codels) in presence.absent_modules() {
                        let key = keys::hello(&prefix, &module);
                        match crate::network::query(&session, &key, &Message::Hello, PROBE_EVERY) {
                            Ok(Answer::Hello { codels: c, .. }) if c == codels => {
                                presence.mark_present(&module)
                            }
                            Ok(Answer::Hello { codels: c, .. }) => presence.lock().entry(module).or_default().absent = Some(format!(
                                "its process runs other codels now: {c:?}, the engine expects {codels:?}"
                            )),
                            _ => {}
                        }
                    }
                }
            })
        };
        Ok(Watch {
            _subscriber: subscriber,
            stop,
            prober: Some(prober),
        })
    }
}

impl Drop for Watch {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.prober.take() {
            let _ = t.join();
        }
    }
}
