//! Per service a typed request and a typed end: `request_go_to(engine, goal: f64)` takes
//! the arguments of the type the model declares, and its ticket reads the reply that ends
//! the request as `GoToEnd::Done(output)`, `GoToEnd::Exception(GoToException::EBlocked,
//! output)` (the output its codels gave before the throw; no output when the service
//! declares none) or the engine's other outcomes.

use std::fmt::Write as _;

use bip_model::genom::map::{ModuleMap, ServiceMap};

use crate::names::{camel, snake};
use crate::types::{is_int, rust_type, At};

/// The arguments as the engine takes them: an `Int`'s `Bounded` as its `i64`.
fn sent(s: &ServiceMap) -> &'static str {
    match &s.args {
        Some(ty) if is_int(ty) => "args.get()",
        Some(_) => "args",
        None => "()",
    }
}

/// The Rust names a service's request takes.
pub(crate) struct RequestNames {
    pub function: String,
    /// The request through a `Handle`, from another thread.
    pub from_handle: String,
    pub ticket: String,
    /// The replies of a request made through a `Handle`.
    pub pending: String,
    pub end: String,
    pub exception: String,
}

impl RequestNames {
    pub fn of(s: &ServiceMap) -> RequestNames {
        let c = camel(&s.name);
        let function = format!("request_{}", snake(&s.name).trim_start_matches("r#"));
        RequestNames {
            from_handle: format!("{function}_from"),
            function,
            ticket: format!("{c}Ticket"),
            pending: format!("{c}Pending"),
            end: format!("{c}End"),
            exception: format!("{c}Exception"),
        }
    }
}

/// The exceptions a service's codels may throw, each once, in declaration order.
fn exceptions(s: &ServiceMap) -> Vec<&str> {
    let mut all: Vec<&str> = Vec::new();
    // a function's codel ends its request too; a validation's exception refuses it
    for c in s.codels.iter().chain(&s.function) {
        for e in &c.throws {
            if !all.contains(&e.as_str()) {
                all.push(e);
            }
        }
    }
    all
}

pub(crate) fn request(out: &mut String, m: &ModuleMap, s: &ServiceMap, n: &RequestNames) {
    let sent = sent(s);
    let (param, ty_doc) = match &s.args {
        Some(ty) => (
            format!(",\n        args: {}", rust_type(ty, At::Module)),
            format!(" with its arguments ({ty})"),
        ),
        None => (String::new(), String::new()),
    };
    let _ = writeln!(
        out,
        "    /// Requests `{m}.{s}`{ty_doc}: the engine serves it at its next quiescent point.\n    pub fn {f}(\n        engine: &mut bip_engine::Engine{param},\n    ) -> Result<{t}, bip_engine::RequestError> {{\n        engine.request(\"{m}\", \"{s}\", {sent}).map({t})\n    }}\n",
        m = m.name,
        s = s.name,
        f = n.function,
        t = n.ticket,
    );
    let throws = exceptions(s);
    if !throws.is_empty() {
        let _ = writeln!(
            out,
            "    /// The exceptions of `{}.{}`.\n    #[derive(Clone, Copy, Debug, PartialEq, Eq)]\n    pub enum {} {{",
            m.name, s.name, n.exception
        );
        for e in &throws {
            let _ = writeln!(out, "        /// Exception `{e}`.\n        {},", camel(e));
        }
        out.push_str("    }\n\n");
    }
    let output = s.output.as_ref().map(|t| (t, rust_type(t, At::Module)));
    let _ = writeln!(
        out,
        "    /// How a request of `{}.{}` ended.\n    #[derive(Clone, Debug, PartialEq)]\n    pub enum {} {{",
        m.name, s.name, n.end
    );
    match &output {
        Some((ty, t)) => {
            let _ = writeln!(
                out,
                "        /// It ended well (`ether`), with the output ({ty}) its codels last gave.\n        Done(Option<{t}>),"
            );
        }
        None => out.push_str("        /// It ended well (`ether`).\n        Done,\n"),
    }
    if !throws.is_empty() {
        match &output {
            Some((ty, t)) => {
                let _ = writeln!(
                    out,
                    "        /// A codel threw one of the service's exceptions, with the output ({ty})\n        /// its codels gave before.\n        Exception({}, Option<{t}>),",
                    n.exception
                );
            }
            None => {
                let _ = writeln!(
                    out,
                    "        /// A codel threw one of the service's exceptions.\n        Exception({}),",
                    n.exception
                );
            }
        }
    }
    out.push_str("        /// It was interrupted, aborted by a rule of the model, or a codel was faulty.\n        Other(bip_engine::Outcome),\n    }\n\n");
    let typed_output = output.as_ref().map(|(ty, t)| {
        if is_int(ty) {
            "output.as_ref().and_then(|o| o.get::<i64>()).and_then(|v| bip_engine::Bounded::new(*v))".to_string()
        } else {
            format!("output.as_ref().and_then(|o| o.get::<{t}>()).cloned()")
        }
    });
    let done = match &typed_output {
        Some(o) => format!("{}::Done({o})", n.end),
        None => format!("{}::Done", n.end),
    };
    let thrown_output = typed_output.map_or(String::new(), |o| format!(", {o}"));
    let output_binding = if output.is_some() { "output" } else { ".." };
    let _ = writeln!(
        out,
        "    /// A request of `{m}.{s}`: its ticket, which reads the reply that ends it.\n    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]\n    pub struct {t}(pub bip_engine::Ticket);\n\n    impl {t} {{\n        /// How the request ended, if `reply`, the reply to `ticket`, is its end.\n        pub fn end(self, ticket: bip_engine::Ticket, reply: &bip_engine::Reply) -> Option<{e}> {{\n            let bip_engine::Reply::Done {{ outcome, {output_binding} }} = reply else {{\n                return None;\n            }};\n            if ticket != self.0 {{\n                return None;\n            }}\n            Some(match outcome {{\n                bip_engine::Outcome::Ether => {done},",
        m = m.name,
        s = s.name,
        t = n.ticket,
        e = n.end,
    );
    if !throws.is_empty() {
        out.push_str("                bip_engine::Outcome::Exception(e) => match &**e {\n");
        for e in &throws {
            let _ = writeln!(
                out,
                "                    \"{e}\" => {}::Exception({}::{}{thrown_output}),",
                n.end,
                n.exception,
                camel(e)
            );
        }
        let _ = writeln!(
            out,
            "                    _ => {}::Other(outcome.clone()),\n                }},",
            n.end
        );
    }
    let _ = writeln!(
        out,
        "                _ => {}::Other(outcome.clone()),\n            }})\n        }}\n    }}\n",
        n.end
    );
}

/// The same request from another thread, through a `bip_engine::Handle`, and its replies
/// read as the typed end.
pub(crate) fn request_from_handle(
    out: &mut String,
    m: &ModuleMap,
    s: &ServiceMap,
    n: &RequestNames,
) {
    let sent = sent(s);
    let param = match &s.args {
        Some(ty) => format!(",\n        args: {}", rust_type(ty, At::Module)),
        None => String::new(),
    };
    let _ = writeln!(
        out,
        "    /// Requests `{m}.{s}` from another thread, through `handle`; its replies come on\n    /// the returned channel (bip-engine with `std`).\n    pub fn {f}(\n        handle: &bip_engine::Handle{param},\n    ) -> Result<{p}, bip_engine::RequestError> {{\n        handle.request(\"{m}\", \"{s}\", {sent}).map({p})\n    }}\n\n    /// The replies of a request of `{m}.{s}` made through a `Handle`.\n    pub struct {p}(pub bip_engine::PendingReply);\n\n    impl {p} {{\n        /// How the request ended: waits at most `timeout` for each of its replies until\n        /// the one that ends it; `None` if one does not come in time or the engine is gone.\n        pub fn end(&self, timeout: std::time::Duration) -> Option<{e}> {{\n            loop {{\n                let (ticket, reply) = self.0.next(timeout)?;\n                if let Some(end) = {t}(ticket).end(ticket, &reply) {{\n                    return Some(end);\n                }}\n            }}\n        }}\n    }}\n",
        m = m.name,
        s = s.name,
        f = n.from_handle,
        p = n.pending,
        t = n.ticket,
        e = n.end,
    );
}
