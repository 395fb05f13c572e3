//! A small HTTP/1.1 server: one request per connection, a thread per connection (a
//! browser opens connections it may never use), the session behind one lock. It reads
//! the request line, the headers and a body of `Content-Length` bytes, within bounds on
//! each and a timeout, and hands them to [`api::handle`].

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use super::api::{self, Response};
use super::session::Session;

const MAX_LINE: usize = 8 * 1024;
const MAX_HEADERS: usize = 100;
/// A trace file's text is the largest body the page sends.
const MAX_BODY: usize = 32 * 1024 * 1024;
const TIMEOUT: Duration = Duration::from_secs(10);
const MAX_CONNECTIONS: usize = 64;

/// Serves `listener` until the process ends. With `loopback_only`, a request must name a
/// loopback host (so that a page of another site, whose name was made to resolve to
/// 127.0.0.1, cannot read the explorer).
pub fn serve(listener: TcpListener, session: Session, loopback_only: bool) {
    let session = Arc::new(Mutex::new(session));
    let open = Arc::new(AtomicUsize::new(0));
    for stream in listener.incoming() {
        let Ok(mut stream) = stream else { continue };
        if open.load(Ordering::SeqCst) >= MAX_CONNECTIONS {
            let _ = write(
                &mut stream,
                &Response::error(503, "too many connections"),
                false,
            );
            continue;
        }
        open.fetch_add(1, Ordering::SeqCst);
        let (session, open) = (Arc::clone(&session), Arc::clone(&open));
        std::thread::spawn(move || {
            let _ = connection(stream, &session, loopback_only);
            open.fetch_sub(1, Ordering::SeqCst);
        });
    }
}

struct Request {
    method: String,
    path: String,
    /// The Host header without its port.
    host: String,
    body: Vec<u8>,
}

fn is_loopback(host: &str) -> bool {
    matches!(host, "127.0.0.1" | "localhost" | "[::1]")
}

fn connection(
    stream: TcpStream,
    session: &Mutex<Session>,
    loopback_only: bool,
) -> std::io::Result<()> {
    stream.set_read_timeout(Some(TIMEOUT))?;
    stream.set_write_timeout(Some(TIMEOUT))?;
    let mut reader = BufReader::new(stream.try_clone()?);
    let mut stream = stream;
    let (response, head) = match read_request(&mut reader) {
        Ok(Some(req)) if loopback_only && !is_loopback(&req.host) => (
            Response::error(
                403,
                &format!("host `{}` is not this machine's loopback", req.host),
            ),
            false,
        ),
        Ok(Some(req)) => {
            let head = req.method == "HEAD";
            // a panic in one request must not stop the others: the lock is taken back
            let mut session = session.lock().unwrap_or_else(|p| p.into_inner());
            (
                api::handle(&mut session, &req.method, &req.path, &req.body),
                head,
            )
        }
        Ok(None) => return Ok(()),
        Err((status, message)) => (Response::error(status, &message), false),
    };
    write(&mut stream, &response, head)
}

/// The request, `None` if the client closed the connection without sending one.
fn read_request(reader: &mut impl BufRead) -> Result<Option<Request>, (u16, String)> {
    let Some(line) = read_line(reader)? else {
        return Ok(None);
    };
    let mut parts = line.split(' ');
    let (Some(method), Some(target), Some(version), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return Err((400, format!("not an HTTP request line: {line:?}")));
    };
    if !version.starts_with("HTTP/1.") {
        return Err((505, format!("{version} is not HTTP/1.x")));
    }
    let mut length = 0usize;
    let mut host = String::new();
    for _ in 0..=MAX_HEADERS {
        let header = read_line(reader)?.ok_or((400, "the headers end early".to_string()))?;
        if header.is_empty() {
            let mut body = vec![0; length];
            reader.read_exact(&mut body).map_err(|_| {
                (
                    400,
                    "the body is shorter than its Content-Length".to_string(),
                )
            })?;
            let path = target.split(['?', '#']).next().unwrap_or("").to_string();
            return Ok(Some(Request {
                method: method.to_string(),
                path,
                host,
                body,
            }));
        }
        let Some((name, value)) = header.split_once(':') else {
            return Err((400, format!("not a header: {header:?}")));
        };
        if name.eq_ignore_ascii_case("content-length") {
            length = value
                .trim()
                .parse()
                .map_err(|_| (400, "Content-Length is not a number".to_string()))?;
            if length > MAX_BODY {
                return Err((413, format!("a body has at most {MAX_BODY} bytes")));
            }
        } else if name.eq_ignore_ascii_case("host") {
            let value = value.trim();
            // `[::1]:7390`, `localhost:7390`: the port is what follows the last colon after
            // any bracketed address
            let port_at = value
                .rfind(':')
                .filter(|&i| i > value.rfind(']').unwrap_or(0));
            host = value[..port_at.unwrap_or(value.len())].to_ascii_lowercase();
        } else if name.eq_ignore_ascii_case("transfer-encoding") {
            return Err((411, "send the body with a Content-Length".to_string()));
        }
    }
    Err((431, format!("a request has at most {MAX_HEADERS} headers")))
}

/// A line without its CRLF; `None` at the end of the stream.
fn read_line(reader: &mut impl BufRead) -> Result<Option<String>, (u16, String)> {
    let mut bytes = Vec::new();
    let n = reader
        .take(MAX_LINE as u64 + 1)
        .read_until(b'\n', &mut bytes)
        .map_err(|e| (408, format!("cannot read the request: {e}")))?;
    if n == 0 {
        return Ok(None);
    }
    if !bytes.ends_with(b"\n") {
        return Err((
            431,
            format!("a line of the request has at most {MAX_LINE} bytes"),
        ));
    }
    let text =
        String::from_utf8(bytes).map_err(|_| (400, "the request is not UTF-8".to_string()))?;
    Ok(Some(text.trim_end_matches(['\r', '\n']).to_string()))
}

fn write(stream: &mut TcpStream, response: &Response, head: bool) -> std::io::Result<()> {
    let reason = match response.status {
        200 => "OK",
        400 => "Bad Request",
        404 => "Not Found",
        405 => "Method Not Allowed",
        408 => "Request Timeout",
        409 => "Conflict",
        411 => "Length Required",
        403 => "Forbidden",
        413 => "Content Too Large",
        422 => "Unprocessable Content",
        431 => "Request Header Fields Too Large",
        503 => "Service Unavailable",
        505 => "HTTP Version Not Supported",
        _ => "",
    };
    let header = format!(
        "HTTP/1.1 {} {reason}\r\nContent-Type: {}\r\nContent-Length: {}\r\n\
         Cache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\nConnection: close\r\n\r\n",
        response.status,
        response.content_type,
        response.body.len()
    );
    stream.write_all(header.as_bytes())?;
    if !head {
        stream.write_all(response.body.as_bytes())?;
    }
    stream.flush()
}
