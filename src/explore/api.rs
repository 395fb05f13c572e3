//! What the explorer answers to each request, without sockets: the page and its two
//! assets, and a JSON API over the [`Session`]. Every answer to a change is the new view
//! (as `GET /api/state` gives it); every error is a 4xx with `{"error": message}`.
//!
//! | request | body | does |
//! |---|---|---|
//! | `GET /api/state` | | nothing |
//! | `POST /api/fire` | `{"index": N}` or `{"step": NAME}` | fires an enabled step |
//! | `POST /api/back`, `POST /api/forward` | | one step along the history |
//! | `POST /api/go` | `{"position": N}` | to the state after N steps of the history |
//! | `POST /api/replay` | `{"history": [N, ...], "position": N}` | a deep link's history |
//! | `POST /api/trace` | `{"trace": "Trace(...)"}` | a trace file's text as the history |

use serde_json::{json, Value};

use super::session::Session;

const INDEX: &str = include_str!("assets/index.html");
const STYLE: &str = include_str!("assets/explore.css");
const SCRIPT: &str = include_str!("assets/explore.js");

pub struct Response {
    pub status: u16,
    pub content_type: &'static str,
    pub body: String,
}

impl Response {
    fn asset(content_type: &'static str, body: &str) -> Response {
        Response {
            status: 200,
            content_type,
            body: body.to_string(),
        }
    }

    fn json(status: u16, value: &Value) -> Response {
        Response {
            status,
            content_type: "application/json",
            body: value.to_string(),
        }
    }

    pub fn error(status: u16, message: &str) -> Response {
        Response::json(status, &json!({ "error": message }))
    }
}

/// The answer to `method path` with `body` (the path without its query).
pub fn handle(session: &mut Session, method: &str, path: &str, body: &[u8]) -> Response {
    let get = method == "GET" || method == "HEAD";
    match (path, get, method == "POST") {
        ("/" | "/index.html", true, _) => Response::asset("text/html; charset=utf-8", INDEX),
        ("/explore.css", true, _) => Response::asset("text/css; charset=utf-8", STYLE),
        ("/explore.js", true, _) => Response::asset("text/javascript; charset=utf-8", SCRIPT),
        ("/api/state", true, _) => Response::json(200, &session.view()),
        (
            "/api/fire" | "/api/back" | "/api/forward" | "/api/go" | "/api/replay" | "/api/trace",
            _,
            true,
        ) => match change(session, path, body) {
            Ok(()) => Response::json(200, &session.view()),
            Err((status, message)) => Response::error(status, &message),
        },
        (
            "/" | "/index.html" | "/explore.css" | "/explore.js" | "/api/state" | "/api/fire"
            | "/api/back" | "/api/forward" | "/api/go" | "/api/replay" | "/api/trace",
            _,
            _,
        ) => Response::error(405, &format!("{method} is not allowed on {path}")),
        _ => Response::error(404, &format!("no such page: {path}")),
    }
}

fn change(session: &mut Session, path: &str, body: &[u8]) -> Result<(), (u16, String)> {
    let conflict = |e: String| (409, e);
    match path {
        "/api/back" => session.back().map_err(conflict),
        "/api/forward" => session.forward().map_err(conflict),
        "/api/fire" => {
            let doc = parse(body)?;
            let index = match doc.get("step") {
                Some(Value::String(name)) => session.index_of(name)?,
                Some(_) => return Err(bad("`step` must be a step's name")),
                None => index(&doc, "index")?,
            };
            session.fire(index).map_err(conflict)
        }
        "/api/go" => {
            let position = index(&parse(body)?, "position")?;
            session.go(position).map_err(conflict)
        }
        "/api/replay" => {
            let doc = parse(body)?;
            let history = doc
                .get("history")
                .and_then(Value::as_array)
                .ok_or_else(|| bad("`history` must be a list of step indices"))?
                .iter()
                .map(|v| as_index(v).ok_or_else(|| bad("`history` must be a list of step indices")))
                .collect::<Result<Vec<usize>, _>>()?;
            let position = match doc.get("position") {
                None | Some(Value::Null) => None,
                Some(_) => Some(index(&doc, "position")?),
            };
            session.replay(&history, position).map_err(conflict)
        }
        "/api/trace" => {
            let doc = parse(body)?;
            let text = doc
                .get("trace")
                .and_then(Value::as_str)
                .ok_or_else(|| bad("`trace` must be the text of a trace file"))?;
            let trace = bip_lang::trace_file::from_ron(text)
                .map_err(|e| bad(&format!("not a trace: {e}")))?;
            session.load(&trace).map_err(|e| (422, e))
        }
        _ => Err((404, format!("no such page: {path}"))),
    }
}

fn bad(message: &str) -> (u16, String) {
    (400, message.to_string())
}

fn parse(body: &[u8]) -> Result<Value, (u16, String)> {
    let doc: Value =
        serde_json::from_slice(body).map_err(|e| bad(&format!("the body is not JSON: {e}")))?;
    if !doc.is_object() {
        return Err(bad("the body must be a JSON object"));
    }
    Ok(doc)
}

fn index(doc: &Value, field: &str) -> Result<usize, (u16, String)> {
    doc.get(field)
        .and_then(as_index)
        .ok_or_else(|| bad(&format!("`{field}` must be a number from 0")))
}

fn as_index(v: &Value) -> Option<usize> {
    v.as_u64().and_then(|n| usize::try_from(n).ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn session() -> Session {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/robots/philosophers.ron");
        Session::new(bip_lang::load_file(std::path::Path::new(path)).expect("loads"))
    }

    fn body(r: &Response) -> Value {
        serde_json::from_str(&r.body).expect("JSON")
    }

    #[test]
    fn fire_back_forward_and_go_move_along_the_history() {
        let mut s = session();
        let r = handle(&mut s, "GET", "/api/state", b"");
        assert_eq!(r.status, 200);
        let first = body(&r);
        assert_eq!(first["position"], 0);
        assert!(!first["enabled"].as_array().unwrap().is_empty());
        let r = handle(&mut s, "POST", "/api/fire", br#"{"index": 0}"#);
        assert_eq!((r.status, body(&r)["position"].clone()), (200, json!(1)));
        assert_eq!(body(&r)["history"], json!([0]));
        let r = handle(&mut s, "POST", "/api/back", b"");
        assert_eq!(body(&r)["position"], 0);
        assert_eq!(body(&r)["state"], first["state"]);
        let r = handle(&mut s, "POST", "/api/forward", b"");
        assert_eq!(body(&r)["position"], 1);
        let r = handle(&mut s, "POST", "/api/go", br#"{"position": 0}"#);
        assert_eq!(body(&r)["position"], 0);
        assert_eq!(body(&r)["history"], json!([0]));
    }

    #[test]
    fn response_properties_show_the_trigger_that_waits_along_the_history() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/robots/served.ron");
        let mut s = Session::new(bip_lang::load_file(std::path::Path::new(path)).expect("loads"));
        let status = |r: &Response, name: &str| -> String {
            let doc = body(r);
            let p = doc["properties"]
                .as_array()
                .unwrap()
                .iter()
                .find(|p| p["name"] == name)
                .unwrap_or_else(|| panic!("{doc}"))
                .clone();
            p["status"].as_str().unwrap().to_string()
        };
        let r = handle(&mut s, "GET", "/api/state", b"");
        assert_eq!(status(&r, "served"), "nothing waits");
        let r = handle(&mut s, "POST", "/api/fire", br#"{"step": "request"}"#);
        assert_eq!(status(&r, "served"), "a trigger waits (0 ticks so far)");
        let r = handle(&mut s, "POST", "/api/fire", br#"{"step": "tick"}"#);
        assert_eq!(
            status(&r, "answered_in_one"),
            "a trigger waits (1 tick so far)"
        );
        let r = handle(&mut s, "POST", "/api/fire", br#"{"step": "tick"}"#);
        assert_eq!(
            status(&r, "answered_in_one"),
            "fails at step 3: the bound passed"
        );
        assert_eq!(
            status(&r, "answered_in_two"),
            "a trigger waits (2 ticks so far)"
        );
        let r = handle(&mut s, "POST", "/api/fire", br#"{"step": "reply"}"#);
        assert_eq!(status(&r, "answered_in_two"), "nothing waits");
        assert_eq!(status(&r, "served"), "nothing waits");
        let r = handle(&mut s, "POST", "/api/go", br#"{"position": 1}"#);
        assert_eq!(
            status(&r, "answered_in_one"),
            "a trigger waits (0 ticks so far)"
        );
    }

    #[test]
    fn bad_requests_get_a_4xx_with_a_message() {
        let mut s = session();
        for (method, path, req, status) in [
            ("POST", "/api/fire", &b"{index: 0"[..], 400),
            ("POST", "/api/fire", b"[0]", 400),
            ("POST", "/api/fire", br#"{"index": -1}"#, 400),
            ("POST", "/api/fire", br#"{"index": 9999}"#, 409),
            ("POST", "/api/fire", br#"{"step": "no_such_thing"}"#, 404),
            ("POST", "/api/fire", br#"{"step": 3}"#, 400),
            ("POST", "/api/go", br#"{"position": 3}"#, 409),
            ("POST", "/api/back", b"", 409),
            ("POST", "/api/forward", b"", 409),
            ("POST", "/api/replay", br#"{"history": [0, 9999]}"#, 409),
            ("POST", "/api/replay", br#"{"history": "0"}"#, 400),
            ("POST", "/api/trace", br#"{"trace": "Trace(oops"}"#, 400),
            ("GET", "/api/fire", b"", 405),
            ("DELETE", "/api/state", b"", 405),
            ("GET", "/../Cargo.toml", b"", 404),
            ("GET", "/assets/explore.js", b"", 404),
        ] {
            let r = handle(&mut s, method, path, req);
            assert_eq!(r.status, status, "{method} {path} {}", r.body);
            assert!(body(&r)["error"].as_str().is_some_and(|m| !m.is_empty()));
        }
        // none of them changed anything
        let r = handle(&mut s, "GET", "/api/state", b"");
        assert_eq!(body(&r)["position"], 0);
        assert_eq!(body(&r)["history"], json!([]));
    }
}
