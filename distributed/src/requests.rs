//! Requests and replies over the network: a client in another process (a supervisor, a
//! ground station, `bip-rover-controller --request`) sends a request to a service of the
//! layer, its arguments typed by the model, and receives each of its replies as the
//! engine gives them (docs/distributed.md, "Requests").

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use bip_engine::{Handle, Refusal, Reply, System};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use zenoh::Wait;

use crate::codec::Types;
use crate::network::NetworkError;
use crate::presence::Presence;
use crate::wire::keys;

/// A client's request: the arguments, absent for a service that takes none.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServiceRequest {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub args: Option<Value>,
}

/// One reply to a client's request, as the engine gave it, or why it was not made.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "reply")]
pub enum ServiceReply {
    Accepted {
        ticket: u64,
    },
    /// The model does not allow it now: the conditions that fail, as the model writes
    /// them (none when a connector or priority of the model forbids it).
    Refused {
        ticket: u64,
        reasons: Vec<String>,
    },
    Started {
        ticket: u64,
    },
    /// The activity ended: `outcome` in words (`ether`, `exception e_blocked`, `fault:
    /// ...`), and its output, if it gave one.
    Done {
        ticket: u64,
        outcome: String,
        output: Option<Value>,
    },
    /// The request was not made: unreadable, an unknown service, arguments of another
    /// type.
    Error {
        message: String,
    },
    /// The request was not made: the process of the service's module is absent (gone,
    /// hung, cut off), why.
    Unavailable {
        reason: String,
    },
}

impl ServiceReply {
    /// The request's last reply: nothing follows it.
    pub fn is_last(&self) -> bool {
        !matches!(
            self,
            ServiceReply::Accepted { .. } | ServiceReply::Started { .. }
        )
    }
}

impl std::fmt::Display for ServiceReply {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ServiceReply::Accepted { ticket } => write!(f, "#{ticket} accepted"),
            ServiceReply::Refused { ticket, reasons } if reasons.is_empty() => write!(
                f,
                "#{ticket} refused: its conditions hold, but a connector or a priority of the model forbids it now"
            ),
            ServiceReply::Refused { ticket, reasons } => {
                write!(f, "#{ticket} refused: {}", reasons.join(", "))
            }
            ServiceReply::Started { ticket } => write!(f, "#{ticket} started"),
            ServiceReply::Done {
                ticket,
                outcome,
                output: None,
            } => write!(f, "#{ticket} done: {outcome}"),
            ServiceReply::Done {
                ticket,
                outcome,
                output: Some(v),
            } => write!(f, "#{ticket} done: {outcome}, output {v}"),
            ServiceReply::Error { message } => write!(f, "error: {message}"),
            ServiceReply::Unavailable { reason } => write!(f, "refused: {reason}"),
        }
    }
}

/// The engine's side: answers the clients' requests through a [`Handle`] of the engine.
pub struct RequestServer {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

/// What the server knows of a service.
struct Service {
    module: String,
    name: String,
    /// Its refusal conditions in words.
    refusals: Vec<String>,
    /// Whether it runs codels (it needs its module's process).
    codels: bool,
}

type Services = Vec<Service>;

impl RequestServer {
    /// Serves requests to the services of `system` on `session` (keys
    /// `<prefix>/service/<module>/<Service>`), sending them to the engine through
    /// `handle`; a request's replies are followed for at most `follow`. Given the
    /// engine's `presence` ([`crate::RemoteModules::presence`]), a request to a service
    /// with codels whose module's process is absent is refused with the reason
    /// ([`ServiceReply::Unavailable`]) and never reaches the engine.
    pub fn start(
        session: &zenoh::Session,
        prefix: &str,
        system: &System,
        types: Types,
        handle: Handle,
        follow: Duration,
        presence: Option<&Presence>,
    ) -> Result<RequestServer, NetworkError> {
        let key = keys::service(prefix, "**");
        let queryable = session
            .declare_queryable(key.as_str())
            .wait()
            .map_err(|e| NetworkError::Open(format!("cannot serve `{key}`: {e}")))?;
        let services: Services = system
            .genom
            .iter()
            .flat_map(|g| &g.modules)
            .flat_map(|m| {
                m.services.iter().map(|s| Service {
                    module: m.name.clone(),
                    name: s.name.clone(),
                    refusals: s.refusals.iter().map(ToString::to_string).collect(),
                    codels: s.every_codel().next().is_some(),
                })
            })
            .collect();
        let services = Arc::new(services);
        let types = Arc::new(types);
        let presence = presence.cloned();
        let prefix = prefix.to_string();
        let stop = Arc::new(AtomicBool::new(false));
        let stopped = Arc::clone(&stop);
        let thread = std::thread::spawn(move || {
            while !stopped.load(Ordering::Relaxed) {
                let Ok(Some(query)) = queryable.recv_timeout(Duration::from_millis(50)) else {
                    continue;
                };
                let server = Server {
                    prefix: prefix.clone(),
                    handle: handle.clone(),
                    types: Arc::clone(&types),
                    services: Arc::clone(&services),
                    presence: presence.clone(),
                    follow,
                };
                // each request follows its own replies
                std::thread::spawn(move || server.serve(&query));
            }
        });
        Ok(RequestServer {
            stop,
            thread: Some(thread),
        })
    }
}

impl Drop for RequestServer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// What a request's thread needs.
struct Server {
    prefix: String,
    handle: Handle,
    types: Arc<Types>,
    services: Arc<Services>,
    presence: Option<Presence>,
    follow: Duration,
}

impl Server {
    fn serve(&self, query: &zenoh::query::Query) {
        let key = query.key_expr().as_str().to_string();
        let say = |r: &ServiceReply| {
            let bytes = serde_json::to_vec(r).unwrap_or_default();
            if let Err(e) = query.reply(key.as_str(), bytes).wait() {
                tracing::warn!(target: "bip_zenoh", "cannot reply on `{key}`: {e}");
            }
        };
        let (m, s) = module_service(&key, &self.prefix);
        let pending = match self.send(query, &key, m, s) {
            Ok(p) => p,
            Err(r) => return say(&r),
        };
        let refusals = self
            .services
            .iter()
            .find(|x| x.module == m && x.name == s)
            .map(|x| x.refusals.as_slice())
            .unwrap_or_default();
        let end = Instant::now() + self.follow;
        while let Some((ticket, reply)) =
            pending.next(end.saturating_duration_since(Instant::now()))
        {
            let ticket = ticket.0;
            let r = match reply {
                Reply::Accepted => ServiceReply::Accepted { ticket },
                Reply::Started => ServiceReply::Started { ticket },
                Reply::Refused(Refusal::Conditions(reasons)) => ServiceReply::Refused {
                    ticket,
                    reasons: reasons
                        .iter()
                        .filter_map(|k| refusals.get(k).cloned())
                        .collect(),
                },
                Reply::Refused(Refusal::NotEnabled) => ServiceReply::Refused {
                    ticket,
                    reasons: Vec::new(),
                },
                Reply::Refused(refusal @ Refusal::Validation(_)) => ServiceReply::Refused {
                    ticket,
                    reasons: vec![refusal.to_string()],
                },
                Reply::Done { outcome, output } => {
                    let output = output
                        .and_then(|o| self.types.output_codec(m, s).and_then(|c| c.output(&o)));
                    ServiceReply::Done {
                        ticket,
                        outcome: outcome.to_string(),
                        output,
                    }
                }
            };
            let last = r.is_last();
            say(&r);
            if last {
                return;
            }
        }
    }

    /// Reads the query and sends its request to the engine; the one reply to it if it
    /// was not made.
    fn send(
        &self,
        query: &zenoh::query::Query,
        key: &str,
        module: &str,
        service: &str,
    ) -> Result<bip_engine::PendingReply, ServiceReply> {
        let error = |message| ServiceReply::Error { message };
        let Some(known) = self
            .services
            .iter()
            .find(|x| x.module == module && x.name == service)
        else {
            return Err(error(format!(
                "`{key}` names no service of the layer: requests go to `{}`",
                keys::service(&self.prefix, "<module>/<Service>")
            )));
        };
        let payload = query
            .payload()
            .map(|p| p.to_bytes().to_vec())
            .unwrap_or_default();
        let request: ServiceRequest = if payload.iter().all(u8::is_ascii_whitespace) {
            ServiceRequest::default()
        } else {
            serde_json::from_slice(&payload).map_err(|e| {
                error(format!(
                    "the request to {module}.{service} is not `{{\"args\": ...}}` in JSON: {e}"
                ))
            })?
        };
        // a service whose codels cannot run now is not requested: the engine would accept
        // it, and its first codel run would fail
        if let Some(why) = self
            .presence
            .as_ref()
            .filter(|_| known.codels)
            .and_then(|p| p.absent(module))
        {
            return Err(ServiceReply::Unavailable {
                reason: format!("the process of module `{module}` is absent: {why}"),
            });
        }
        let handle = &self.handle;
        match (request.args, self.types.args_codec(module, service)) {
            (None, _) => handle
                .request(module, service, ())
                .map_err(|e| error(e.to_string())),
            (Some(v), Some(codec)) => codec.request(handle, module, service, &v).map_err(|e| {
                error(format!(
                    "the arguments of {module}.{service} ({v}) are not of its type: {e}"
                ))
            }),
            (Some(v), None) => Err(error(format!(
                "{module}.{service} takes no arguments, yet was sent {v}"
            ))),
        }
    }
}

/// The module and service a request's key names.
fn module_service<'a>(key: &'a str, prefix: &str) -> (&'a str, &'a str) {
    let rest = key
        .get(keys::service(prefix, "").len()..)
        .unwrap_or_default();
    rest.split_once('/').unwrap_or((rest, ""))
}

/// Sends a request to `module.service` of the layer under `prefix` and calls `each`
/// with each reply, until its last one or `timeout`; the replies, in order.
pub fn request(
    session: &zenoh::Session,
    prefix: &str,
    module: &str,
    service: &str,
    args: Option<Value>,
    timeout: Duration,
    each: impl FnMut(&ServiceReply),
) -> Result<Vec<ServiceReply>, String> {
    let payload = serde_json::to_vec(&ServiceRequest { args }).unwrap_or_default();
    request_bytes(session, prefix, module, service, payload, timeout, each)
}

/// [`request`] with the query's payload as given (any bytes: the engine refuses what is
/// not a request, with its reason).
pub fn request_bytes(
    session: &zenoh::Session,
    prefix: &str,
    module: &str,
    service: &str,
    payload: Vec<u8>,
    timeout: Duration,
    mut each: impl FnMut(&ServiceReply),
) -> Result<Vec<ServiceReply>, String> {
    let key = keys::service(prefix, &format!("{module}/{service}"));
    // every reply, in order: zenoh would otherwise keep only the last on one key
    let replies = session
        .get(key.as_str())
        .consolidation(zenoh::query::ConsolidationMode::None)
        .payload(payload)
        .timeout(timeout)
        .wait()
        .map_err(|e| format!("cannot query `{key}`: {e}"))?;
    let end = Instant::now() + timeout;
    let mut got = Vec::new();
    while let Ok(Some(reply)) = replies.recv_timeout(end.saturating_duration_since(Instant::now()))
    {
        let Ok(sample) = reply.result() else {
            continue;
        };
        let r: ServiceReply = serde_json::from_slice(&sample.payload().to_bytes())
            .map_err(|e| format!("an unreadable reply on `{key}`: {e}"))?;
        each(&r);
        let last = r.is_last();
        got.push(r);
        if last {
            return Ok(got);
        }
    }
    if got.is_empty() {
        return Err(format!(
            "no engine answered on `{key}` within {} ms",
            timeout.as_millis()
        ));
    }
    Ok(got)
}
