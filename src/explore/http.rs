//! The explorer's HTTP/1.1 front, on hyper: one request per connection (keep-alive off,
//! so a browser's idle connections do not pile up), the session behind one lock. hyper
//! parses the requests and answers malformed ones; this file bounds what a client may
//! send (headers, body, time, connections), checks the Host header, and hands each
//! request to [`api::handle`].

use std::net::TcpListener;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use http_body_util::{BodyExt, Full, Limited};
use hyper::body::{Body, Bytes, Incoming};
use hyper::header::{HeaderValue, CACHE_CONTROL, CONTENT_TYPE, HOST, X_CONTENT_TYPE_OPTIONS};
use hyper::server::conn::http1;
use hyper::service::service_fn;
use hyper::{Request, StatusCode};
use hyper_util::rt::{TokioIo, TokioTimer};
use tokio::sync::Semaphore;

use super::api::{self, Response};
use super::session::Session;

const MAX_HEADERS: usize = 100;
/// A trace file's text is the largest body the page sends.
const MAX_BODY: usize = 32 * 1024 * 1024;
/// How long a client may take to send its headers, and to be served once it has.
const TIMEOUT: Duration = Duration::from_secs(10);
const MAX_CONNECTIONS: usize = 64;

/// Serves `listener` until the process ends. With `loopback_only`, a request must name a
/// loopback host (so that a page of another site, whose name was made to resolve to
/// 127.0.0.1, cannot read the explorer).
pub fn serve(listener: TcpListener, session: Session, loopback_only: bool) -> std::io::Result<()> {
    listener.set_nonblocking(true)?;
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_io()
        .enable_time()
        .build()?;
    let session = Arc::new(Mutex::new(session));
    let open = Arc::new(Semaphore::new(MAX_CONNECTIONS));
    runtime.block_on(async move {
        let listener = tokio::net::TcpListener::from_std(listener)?;
        loop {
            let Ok((stream, _)) = listener.accept().await else {
                continue;
            };
            let permit = Arc::clone(&open).try_acquire_owned().ok();
            let session = Arc::clone(&session);
            tokio::spawn(async move {
                let service = service_fn(|request| {
                    let session = Arc::clone(&session);
                    let busy = permit.is_none();
                    async move {
                        let response = if busy {
                            Response::error(503, "too many connections")
                        } else {
                            answer(request, &session, loopback_only).await
                        };
                        Ok::<_, std::convert::Infallible>(to_hyper(response))
                    }
                });
                let connection = http1::Builder::new()
                    .keep_alive(false)
                    .max_headers(MAX_HEADERS)
                    .timer(TokioTimer::new())
                    .header_read_timeout(TIMEOUT)
                    .serve_connection(TokioIo::new(stream), service);
                // a client that sends its headers and then its body at a trickle is cut off
                let _ = tokio::time::timeout(2 * TIMEOUT, connection).await;
            });
        }
    })
}

fn is_loopback(host: &str) -> bool {
    matches!(host, "127.0.0.1" | "localhost" | "[::1]")
}

/// The Host header without its port, in lower case; empty if there is none.
fn host(request: &Request<Incoming>) -> String {
    let value = request
        .headers()
        .get(HOST)
        .and_then(|h| h.to_str().ok())
        .unwrap_or("")
        .trim();
    // `[::1]:7390`, `localhost:7390`: the port is what follows the last colon after any
    // bracketed address
    let port_at = value
        .rfind(':')
        .filter(|&i| i > value.rfind(']').unwrap_or(0));
    value[..port_at.unwrap_or(value.len())].to_ascii_lowercase()
}

async fn answer(
    request: Request<Incoming>,
    session: &Mutex<Session>,
    loopback_only: bool,
) -> Response {
    if request.body().size_hint().lower() > MAX_BODY as u64 {
        return Response::error(413, &format!("a body has at most {MAX_BODY} bytes"));
    }
    let host = host(&request);
    if loopback_only && !is_loopback(&host) {
        return Response::error(
            403,
            &format!("host `{host}` is not this machine's loopback"),
        );
    }
    let method = request.method().as_str().to_string();
    let path = request.uri().path().to_string();
    let body = request.into_body();
    let body = match Limited::new(body, MAX_BODY).collect().await {
        Ok(collected) => collected.to_bytes(),
        Err(e) if e.is::<http_body_util::LengthLimitError>() => {
            return Response::error(413, &format!("a body has at most {MAX_BODY} bytes"))
        }
        Err(e) => return Response::error(400, &format!("cannot read the body: {e}")),
    };
    // a panic in one request must not stop the others: the lock is taken back
    let mut session = session.lock().unwrap_or_else(|p| p.into_inner());
    api::handle(&mut session, &method, &path, &body)
}

fn to_hyper(response: Response) -> hyper::Response<Full<Bytes>> {
    let mut answer = hyper::Response::new(Full::new(Bytes::from(response.body)));
    *answer.status_mut() =
        StatusCode::from_u16(response.status).unwrap_or(StatusCode::INTERNAL_SERVER_ERROR);
    let headers = answer.headers_mut();
    headers.insert(
        CONTENT_TYPE,
        HeaderValue::from_static(response.content_type),
    );
    headers.insert(CACHE_CONTROL, HeaderValue::from_static("no-store"));
    headers.insert(X_CONTENT_TYPE_OPTIONS, HeaderValue::from_static("nosniff"));
    answer
}
