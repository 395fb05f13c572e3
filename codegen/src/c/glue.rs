//! The Rust glue that binds a GenoM3 component's C codels to bip-engine, generated from
//! its `.gen` file beside the mirrors of its types (docs/codegen.md, "Running C codels on
//! the engine"). In the component's module (`counter::`): the `extern "C"` declaration of
//! every codel function with its prototype's Rust mirror and of its events' and
//! exceptions' symbols, `CODELS` (its module object's codels with their outcomes, which
//! the engine checks against the model), `State` (its ids, each service's parameters and
//! locals, each port's data, in the C layout), the port handles the codels are given,
//! `Component` (the module object: `run(k, ctx)` calls codel `k` and reads the event it
//! returns through `bip_genom_c::Events`), `bind` and `bind_shared`.

use std::collections::BTreeSet;
use std::fmt::Write as _;

use bip_lang::gen3::ast::{Codel, Component, Dir, Kind, Service, Spec};
use bip_lang::genom::syntax::ModuleDef;

use super::codels::{all_codels, param, within, Param, Place};
use super::ctype::{cname, holds_native, owns_buffer, Body, CTypes};
use super::glue_apart::{apart_glue, Apart};
use super::glue_args::{arg, port_field, service_field, Conv};
use super::glue_ports::{port_glue, Port};
use super::glue_service::service_data;
use super::mirror::{derives, maxima, Mirrors};
use crate::CodegenError;

/// The mirrors of `spec`'s types and, in each component's module, the glue of its codels,
/// as the text of Rust items for a module of their own (`mod counter_c { include!(..) }`).
/// The code depends on bip-engine and bip-genom-c.
pub fn rust_glue(spec: &Spec) -> Result<String, CodegenError> {
    rust_glue_of(&[spec])
}

/// As [`rust_glue`] for the files of one layer, in one text: their types' mirrors once,
/// shared by every component (the data one component's codels write on a port is the
/// type another's read).
pub fn rust_glue_of(specs: &[&Spec]) -> Result<String, CodegenError> {
    let mut m = Mirrors::of(specs)?;
    for spec in specs {
        let modules = bip_lang::gen3::modules(spec, 1).map_err(|errors| {
            let words: Vec<String> = errors.iter().map(|e| e.message.clone()).collect();
            CodegenError::CMapping(words.join("; "))
        })?;
        for (comp, module) in spec.components.iter().zip(&modules) {
            let types = super::c_types(spec, comp)?;
            let text = component_glue(&mut m, &types, comp, module)
                .map_err(|e| within(e, &format!("component `{}`", comp.name.value)))?;
            m.items
                .entry(vec![comp.name.value.clone()])
                .or_default()
                .push(text);
        }
    }
    Ok(m.text())
}

/// A codel of the module object, as the engine numbers them: tasks' machines first, then
/// the services' codels, each state of each codel once, then each service's codels at a
/// request (its `validate`, a function's codel).
struct Numbered<'a> {
    service: Option<&'a Service>,
    /// The service's name, or the task's.
    owner: &'a str,
    state: &'a str,
    codel: &'a Codel,
    /// Its yields as the model writes them (`ether` for a codel at a request).
    yields: Vec<String>,
    throws: Vec<String>,
    /// It runs at a request, and GenoM3's `genom_ok` is its success.
    at_request: bool,
}

fn last(name: &str) -> String {
    name.rsplit("::").next().unwrap_or(name).to_string()
}

fn numbered(comp: &Component) -> Vec<Numbered<'_>> {
    let yields = |codel: &Codel| {
        codel
            .yields
            .iter()
            .map(|y| y.value.replace(' ', ""))
            .collect()
    };
    let tasks = comp.tasks.iter().flat_map(|t| {
        t.codels.iter().flat_map(move |codel| {
            codel.states.iter().map(move |st| Numbered {
                service: None,
                owner: &t.name.value,
                state: &st.value,
                codel,
                yields: yields(codel),
                throws: t.throws.iter().map(|e| last(&e.value)).collect(),
                at_request: false,
            })
        })
    });
    let services = comp.services.iter().flat_map(|s| {
        let throws = || s.throws.iter().map(|e| last(&e.value)).collect();
        let states = s.codels.iter().flat_map(move |codel| {
            codel.states.iter().map(move |st| Numbered {
                service: Some(s),
                owner: &s.name.value,
                state: &st.value,
                codel,
                yields: yields(codel),
                throws: throws(),
                at_request: false,
            })
        });
        // as the model has them (docs/genom.md, "Codels at the request")
        let function: &[Codel] = if s.kind != Kind::Activity {
            &s.simple
        } else {
            &[]
        };
        let at_request = s
            .validate
            .iter()
            .map(|codel| ("validate", codel))
            .chain(function.iter().map(|codel| ("start", codel)))
            .map(move |(state, codel)| Numbered {
                service: Some(s),
                owner: &s.name.value,
                state,
                codel,
                yields: vec!["ether".to_string()],
                throws: throws(),
                at_request: true,
            });
        states.chain(at_request)
    });
    tasks.chain(services).collect()
}

fn quoted(list: &[String]) -> String {
    let q: Vec<String> = list.iter().map(|s| format!("{s:?}")).collect();
    format!("&[{}]", q.join(", "))
}

fn component_glue(
    m: &mut Mirrors,
    types: &CTypes,
    comp: &Component,
    module: &ModuleDef,
) -> Result<String, CodegenError> {
    let c = &comp.name.value;
    let ids = format!("{c}::ids");
    let codels = numbered(comp);
    let mut out = String::from("// The glue of the component's C codels (bip-codegen).\n");

    // the module object's codels, as the engine checks them against the model
    out.push_str("/// The module object's codels as the engine numbers them (tasks' machines, then the\n/// services' codels), with their outcomes as the model declares them.\npub const CODELS: &[bip_genom_c::bip_engine::CodelSignature] = &[\n");
    for n in &codels {
        let _ = writeln!(
            out,
            "    bip_genom_c::bip_engine::CodelSignature {{ service: {:?}, codel: {:?}, yields: {}, throws: {} }},",
            n.owner,
            n.state,
            quoted(&n.yields),
            quoted(&n.throws)
        );
    }
    out.push_str("];\n\n");

    // the symbols: events, exceptions, codel functions
    let mut events: BTreeSet<String> = BTreeSet::from(["ether".to_string()]);
    for (_, codel) in all_codels(comp) {
        events.extend(codel.yields.iter().map(|y| y.value.replace(' ', "")));
    }
    let exceptions: Vec<(String, String)> = types
        .order
        .iter()
        .filter(|k| matches!(types.decl(k).map(|d| &d.body), Some(Body::Exception(_))))
        .map(|k| (format!("{}_id", cname(k)), format!("::{k}")))
        .collect();
    out.push_str("extern \"C\" {\n");
    for e in &events {
        let _ = writeln!(
            out,
            "    static {}: [core::ffi::c_char; {}];",
            cname(&format!("{c}::{e}")),
            format!("::{c}::{e}").len() + 1
        );
    }
    for (sym, full) in &exceptions {
        let _ = writeln!(
            out,
            "    static {sym}: [core::ffi::c_char; {}];",
            full.len() + 1
        );
    }
    let _ = writeln!(
        out,
        "    static genom_fatal: [core::ffi::c_char; {}];",
        "::genom::fatal".len() + 1
    );
    let _ = writeln!(
        out,
        "    static genom_syserr_id: [core::ffi::c_char; {}];\n    static bip_genom_enotconn: i32;\n    static bip_genom_enoent: i32;\n    static bip_genom_einval: i32;",
        "::genom::syserr".len() + 1
    );

    // each codel's arguments, and the ports they name
    let mut calls = Vec::new();
    let mut declared = BTreeSet::new();
    let mut ports = BTreeSet::new();
    let mut apart = Vec::new();
    for (k, n) in codels.iter().enumerate() {
        let f = &n.codel.function.value;
        let mut run_apart = n
            .codel
            .asynchronous
            .then(|| Apart::new(k, n.service.map(|s| s.name.value.as_str())));
        let mut tys = Vec::new();
        let mut exprs = Vec::new();
        for p in &n.codel.params {
            let place = format!("parameter `{}` of codel `{f}`", p.name.value);
            let (at, ty) = param(types, comp, n.service, &ids, p).map_err(|e| within(e, &place))?;
            if let (Place::Port(name), Param::Port(_)) = (&at, &ty) {
                ports.insert(name.clone());
            }
            if let (Some(a), true) = (run_apart.as_mut(), p.dir.writes()) {
                a.writes(&at);
            }
            let a = arg(
                m,
                types,
                &at,
                &ty,
                p.dir == Dir::In,
                n.service.map(|s| s.name.value.as_str()),
            )
            .map_err(|e| within(e, &place))?;
            tys.push(a.ty);
            exprs.push(a.expr);
        }
        if declared.insert(f.clone()) {
            let params: Vec<String> = tys
                .iter()
                .enumerate()
                .map(|(k, t)| format!("a{k}: {t}"))
                .chain(["this: *const bip_genom_c::ContextIface".to_string()])
                .collect();
            let _ = writeln!(
                out,
                "    fn {f}({}) -> bip_genom_c::GenomEvent;",
                params.join(", ")
            );
        }
        exprs.push("this".into());
        calls.push(format!("{f}({})", exprs.join(", ")));
        apart.extend(run_apart);
    }
    out.push_str("}\n\n");

    // the events by address
    let yields: Vec<String> = events
        .iter()
        .map(|e| {
            format!(
                "(core::ptr::addr_of!({}) as usize, {e:?})",
                cname(&format!("{c}::{e}"))
            )
        })
        .collect();
    let excs: Vec<String> = exceptions
        .iter()
        .map(|(sym, full)| format!("(core::ptr::addr_of!({sym}) as usize, {:?})", last(full)))
        .collect();
    let _ = writeln!(
        out,
        "/// The component's events and exceptions by address, with each codel's declared ones.\npub fn events() -> bip_genom_c::Events {{\n    bip_genom_c::Events::new(\n        CODELS,\n        vec![{}],\n        vec![{}],\n    )\n}}\n",
        yields.join(", "),
        excs.join(", ")
    );

    // the memory of the C layout: ids, services' parameters and locals, ports' data
    let ids_type = super::ctype::CType::Named(ids.clone());
    let mut state = format!("    pub ids: {},\n", m.rust(types, &ids_type, 1)?);
    // the fields' first values: all zero (valid for every mirror), but a multiple port's
    // instances, which are none
    let mut firsts = vec!["ids: unsafe { core::mem::zeroed() }".to_string()];
    let mut copy = !owns_buffer(types, &ids_type);
    let mut set = maxima(types, &ids_type, "v.ids", 0);
    let mut extra = String::new();
    let mut starts = Vec::new();
    let mut outputs = Vec::new();
    for (s, def) in comp.services.iter().zip(&module.services) {
        let Some(data) = service_data(m, types, comp, s, def, &mut extra)? else {
            continue;
        };
        copy &= data.copy;
        let data_output = data.output;
        let data = data.ty;
        let _ = writeln!(state, "    pub {}: {data},", service_field(&s.name.value));
        firsts.push(format!(
            "{}: {data}::default()",
            service_field(&s.name.value)
        ));
        starts.push((s.name.value.clone(), format!("args_{}", s.name.value)));
        if data_output {
            outputs.push((s.name.value.clone(), format!("output_{}", s.name.value)));
        }
    }
    for name in &ports {
        let Some(p) = comp.ports.iter().find(|p| &p.name.value == name) else {
            continue;
        };
        let t = types.ctype(&p.ty, c)?;
        let place = format!("port `{name}`");
        if holds_native(types, &t) {
            return Err(CodegenError::CMapping(format!(
                "{place}: its data holds a native (a pointer to the codels' own object), which the engine can neither copy nor free"
            )));
        }
        let rust = m.rust(types, &t, 1)?;
        if p.multiple {
            // its instances, each of the type's default when opened
            copy = false;
            let _ = writeln!(
                state,
                "    pub {}: bip_genom_c::Instances<{rust}>,",
                port_field(name)
            );
            firsts.push(format!(
                "{}: bip_genom_c::Instances::default()",
                port_field(name)
            ));
        } else {
            copy &= !owns_buffer(types, &t);
            let _ = writeln!(state, "    pub {}: {rust},", port_field(name));
            firsts.push(format!(
                "{}: unsafe {{ core::mem::zeroed() }}",
                port_field(name)
            ));
            set.push_str(&maxima(types, &t, &format!("v.{}", port_field(name)), 0));
        }
        let ty = module
            .ports
            .iter()
            .chain(&module.in_ports)
            .find(|q| &q.name.value == name)
            .and_then(|q| q.ty.as_ref());
        let conv = Conv::of(m, types, &t, ty).map_err(|e| within(e, &place))?;
        let port = Port {
            component: c,
            name,
            dir: p.dir,
            multiple: p.multiple,
        };
        port_glue(&mut extra, m, types, &port, &t, conv)?;
    }
    state.push_str("}\n");
    let mut state = format!("/// What the component's codels share with the engine, in the C layout: its ids, each\n/// service's parameters and locals, each port's data.\n{}pub struct State {{\n{state}", derives(copy));
    let first = format!("State {{ {} }}", firsts.join(", "));
    let body = if set.is_empty() {
        first
    } else {
        format!("let mut v = {first};\n{set}        v")
    };
    let _ = write!(
        state,
        "// (derivable for some components, not for others: written alike for all)\n#[allow(clippy::derivable_impls)]\nimpl Default for State {{\n    // every field of a C mirror is valid all zero\n    fn default() -> Self {{\n        {body}\n    }}\n}}\n"
    );
    state.push_str("// SAFETY: the pointers a state may hold (unbounded sequences' and strings' buffers,\n// natives) are the codels' own, which only this module object's codels touch, one call\n// at a time\nunsafe impl Send for State {}\n");
    out.push_str(&state);
    out.push_str(&extra);

    // the call of codel k
    out.push_str("\n/// The call in progress, for the port handles' functions (through the context).\nstruct Call {\n    state: *mut State,\n    ctx: *mut bip_genom_c::bip_engine::Ctx<'static>,\n}\n\n");
    out.push_str("/// Runs codel `k` on `s`; `None` if its arguments are missing.\n///\n/// # Safety\n/// `s` and `ctx` are valid for the call, `this` is the module object's context.\n#[allow(unused_variables)]\nunsafe fn call(\n    k: usize,\n    s: *mut State,\n    ctx: *mut bip_genom_c::bip_engine::Ctx<'static>,\n    this: *const bip_genom_c::ContextIface,\n) -> Option<bip_genom_c::GenomEvent> {\n    unsafe {\n        Some(match k {\n");
    for (k, (n, call)) in codels.iter().zip(&calls).enumerate() {
        let owner = n.owner;
        // GenoM3's `genom_ok` (NULL) is a codel at a request's success: its `ether`
        let call = &match n.at_request {
            true => format!(
                "{{ let ev = {call}; if ev.is_null() {{ core::ptr::addr_of!({}).cast() }} else {{ ev }} }}",
                cname(&format!("{c}::ether"))
            ),
            false => call.clone(),
        };
        // the arguments, read by the codel that starts an activity or checks a request
        let reads_args = n.state == "start" || n.state == "validate" && n.at_request;
        let start = match starts.iter().find(|(s, _)| s == owner) {
            Some((_, f)) if reads_args => {
                format!(
                    "if !{f}(&mut (*s).{}, &*ctx) {{ return None; }} ",
                    service_field(owner)
                )
            }
            _ => String::new(),
        };
        // a validation gives no output
        let gives = outputs
            .iter()
            .find(|(s, _)| s == owner && !(n.at_request && n.state == "validate"));
        let body = match gives {
            Some((_, f)) => format!(
                "let ev = {call}; {f}(&(*s).{}, &mut *ctx); ev",
                service_field(owner)
            ),
            None => call.clone(),
        };
        let _ = writeln!(out, "            {k} => {{ {start}{body} }}");
    }
    out.push_str("            _ => return None,\n        })\n    }\n}\n\n");

    let bind = if apart.is_empty() {
        format!("/// Binds every codel of module `{c}` to its C function, the module object owning its\n/// memory (nothing to lock).\npub fn bind(builder: bip_genom_c::bip_engine::EngineBuilder) -> bip_genom_c::bip_engine::EngineBuilder {{\n    let mut module = Component::default();\n    builder.module({c:?}, CODELS, move |k, ctx| module.run(k, ctx))\n}}")
    } else {
        format!("/// Binds every codel of module `{c}` to its C function: its async codels apart from the\n/// module object, which is shared with them (see [`bind_shared`]).\npub fn bind(builder: bip_genom_c::bip_engine::EngineBuilder) -> bip_genom_c::bip_engine::EngineBuilder {{\n    bind_shared(builder).0\n}}")
    };
    let aparts: String = apart
        .iter()
        .map(|a| {
            format!(
                "\n    // async codel {k}: on its own thread, beside the object\n    let mut apart = Apart::new({k}, &shared);\n    let builder = builder.apart({c:?}, {k}, move |ctx| apart.run(ctx));",
                k = a.k
            )
        })
        .collect();
    if !apart.is_empty() {
        let storages: Vec<String> = starts.iter().map(|(s, _)| s.clone()).collect();
        apart_glue(&mut out, &apart, &storages)?;
    }
    let _ = write!(
        out,
        r#"/// The module object of component `{c}`: its memory of the C layout, the context its
/// codels are given, and its events.
pub struct Component {{
    pub state: State,
    context: bip_genom_c::Context,
    events: bip_genom_c::Events,
}}

impl Default for Component {{
    fn default() -> Self {{
        Component {{
            state: State::default(),
            context: bip_genom_c::Context::default(),
            events: events(),
        }}
    }}
}}

impl Component {{
    /// What the codels raised, to be read from outside the engine.
    pub fn raised(&self) -> std::sync::Arc<bip_genom_c::Raised> {{
        self.context.raised()
    }}

    /// Runs codel `k` (as [`CODELS`] numbers them) and reads the event it returns: a
    /// declared outcome, or one the engine takes the activity's error path with.
    pub fn run(&mut self, k: usize, ctx: &mut bip_genom_c::bip_engine::Ctx<'_>) -> bip_genom_c::bip_engine::Next {{
        run_on(k, &mut self.state, &self.context, &self.events, ctx)
    }}
}}

/// Runs codel `k` on `state` with `context`, and reads the event it returns by `events`.
fn run_on(
    k: usize,
    state: &mut State,
    context: &bip_genom_c::Context,
    events: &bip_genom_c::Events,
    ctx: &mut bip_genom_c::bip_engine::Ctx<'_>,
) -> bip_genom_c::bip_engine::Next {{
    let Some(sig) = CODELS.get(k) else {{
        return bip_genom_c::bip_engine::Next::Declared(u16::MAX);
    }};
    let s: *mut State = state;
    let ctx: *mut bip_genom_c::bip_engine::Ctx<'static> = (ctx as *mut bip_genom_c::bip_engine::Ctx<'_>).cast();
    let this = context.as_ptr();
    let mut now = Call {{ state: s, ctx }};
    let at: *mut Call = &mut now;
    // SAFETY: the prototypes are the header's (the codels compile against it); the
    // state, the context and the engine's `ctx` outlive the call, and the codel is
    // given pointers into the state for the call only
    let ev = context.with_call(at.cast(), || unsafe {{ call(k, s, ctx, this) }});
    match ev {{
        Some(ev) => events.next(k, sig, ev),
        None => bip_genom_c::bip_engine::Next::Declared(u16::MAX),
    }}
}}

{bind}

/// As [`bind`], the module object shared with the caller, who may read its memory between
/// the engine's steps (a lock per codel call).
pub fn bind_shared(
    builder: bip_genom_c::bip_engine::EngineBuilder,
) -> (bip_genom_c::bip_engine::EngineBuilder, std::sync::Arc<std::sync::Mutex<Component>>) {{
    let shared = std::sync::Arc::new(std::sync::Mutex::new(Component::default()));
    let module = std::sync::Arc::clone(&shared);
    let builder = builder.module({c:?}, CODELS, move |k, ctx| match module.lock() {{
        Ok(mut m) => m.run(k, ctx),
        Err(_) => bip_genom_c::bip_engine::Next::Declared(u16::MAX),
    }});{aparts}
    (builder, shared)
}}
"#
    );
    Ok(out)
}
