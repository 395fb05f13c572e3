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
        }
    }
}

/// The engine's side: answers the clients' requests through a [`Handle`] of the engine.
pub struct RequestServer {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

/// What the server knows of a service: (module, service, its refusal conditions in
/// words).
type Services = Vec<(String, String, Vec<String>)>;

impl RequestServer {
    /// Serves requests to the services of `system` on `session` (keys
    /// `<prefix>/service/<module>/<Service>`), sending them to the engine through
    /// `handle`; a request's replies are followed for at most `follow`.
    pub fn start(
        session: &zenoh::Session,
        prefix: &str,
        system: &System,
        types: Types,
        handle: Handle,
        follow: Duration,
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
                m.services.iter().map(|s| {
                    let refusals = s.refusals.iter().map(ToString::to_string).collect();
                    (m.name.clone(), s.name.clone(), refusals)
                })
            })
            .collect();
        let services = Arc::new(services);
        let types = Arc::new(types);
        let prefix = prefix.to_string();
        let stop = Arc::new(AtomicBool::new(false));
        let stopped = Arc::clone(&stop);
        let thread = std::thread::spawn(move || {
            while !stopped.load(Ordering::Relaxed) {
                let Ok(Some(query)) = queryable.recv_timeout(Duration::from_millis(50)) else {
                    continue;
                };
                let (handle, types, services) =
                    (handle.clone(), Arc::clone(&types), Arc::clone(&services));
                let prefix = prefix.clone();
                // each request follows its own replies
                std::thread::spawn(move || {
                    serve(&query, &prefix, &handle, &types, &services, follow)
                });
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

fn serve(
    query: &zenoh::query::Query,
    prefix: &str,
    handle: &Handle,
    types: &Types,
    services: &Services,
    follow: Duration,
) {
    let key = query.key_expr().as_str().to_string();
    let say = |r: &ServiceReply| {
        let bytes = serde_json::to_vec(r).unwrap_or_default();
        if let Err(e) = query.reply(key.as_str(), bytes).wait() {
            tracing::warn!(target: "bip_zenoh", "cannot reply on `{key}`: {e}");
        }
    };
    let pending = match send(query, &key, prefix, handle, types, services) {
        Ok(p) => p,
        Err(message) => return say(&ServiceReply::Error { message }),
    };
    let (m, s) = module_service(&key, prefix);
    let refusals = services
        .iter()
        .find(|x| x.0 == m && x.1 == s)
        .map(|x| x.2.as_slice())
        .unwrap_or_default();
    let end = Instant::now() + follow;
    while let Some((ticket, reply)) = pending.next(end.saturating_duration_since(Instant::now())) {
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
            Reply::Done { outcome, output } => {
                let output =
                    output.and_then(|o| types.output_codec(m, s).and_then(|c| c.output(&o)));
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

/// The module and service a request's key names.
fn module_service<'a>(key: &'a str, prefix: &str) -> (&'a str, &'a str) {
    let rest = key
        .get(keys::service(prefix, "").len()..)
        .unwrap_or_default();
    rest.split_once('/').unwrap_or((rest, ""))
}

/// Reads the query and sends its request to the engine.
fn send(
    query: &zenoh::query::Query,
    key: &str,
    prefix: &str,
    handle: &Handle,
    types: &Types,
    services: &Services,
) -> Result<bip_engine::PendingReply, String> {
    let (module, service) = module_service(key, prefix);
    if !services.iter().any(|x| x.0 == module && x.1 == service) {
        return Err(format!(
            "`{key}` names no service of the layer: requests go to `{}`",
            keys::service(prefix, "<module>/<Service>")
        ));
    }
    let payload = query
        .payload()
        .map(|p| p.to_bytes().to_vec())
        .unwrap_or_default();
    let request: ServiceRequest = if payload.iter().all(u8::is_ascii_whitespace) {
        ServiceRequest::default()
    } else {
        serde_json::from_slice(&payload).map_err(|e| {
            format!("the request to {module}.{service} is not `{{\"args\": ...}}` in JSON: {e}")
        })?
    };
    match (request.args, types.args_codec(module, service)) {
        (None, _) => handle
            .request(module, service, ())
            .map_err(|e| e.to_string()),
        (Some(v), Some(codec)) => codec.request(handle, module, service, &v).map_err(|e| {
            format!("the arguments of {module}.{service} ({v}) are not of its type: {e}")
        }),
        (Some(v), None) => Err(format!(
            "{module}.{service} takes no arguments, yet was sent {v}"
        )),
    }
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
