//! Per codel a typed context over the engine's `Ctx`: its module's ids fields (a setter
//! only for those it `writes`), a reader for every typed port of the layer, a writer for
//! each typed port it `writes`, its service's arguments and output, each of the type the
//! model declares. What the model does not let the codel touch has no method, so using it
//! does not compile. An `Int` (and an ids field of a range) is given and taken as a
//! `Bounded`, by value, so that no value out of range is written through the context (no
//! `&mut` to an `Int` port's `i64`); a `Bool` ids field as a `bool`; the rest by
//! reference. Every accessor is a call of `Ctx` with names fixed at generation: nothing is
//! allocated.

use std::fmt::Write as _;

use bip_model::genom::map::{CodelMap, IdsField, ModuleMap, ServiceMap};
use bip_model::genom::GenomMap;

use crate::names::snake;
use crate::types::{bounded, is_int, rust_type, At};

/// The context struct `name` of codel `c` of `m.s`, and its accessors.
pub(crate) fn context(
    out: &mut String,
    layer: &GenomMap,
    m: &ModuleMap,
    s: &ServiceMap,
    c: &CodelMap,
    name: &str,
) {
    let _ = writeln!(
        out,
        "    /// What codel `{}` of `{}.{}` may touch, typed: its module's ids, the layer's ports\n    /// (written only those it `writes`), its service's arguments and output.",
        c.state, m.name, s.name
    );
    let _ = writeln!(
        out,
        "    pub struct {name}<'c, 'e> {{\n        ctx: &'c mut bip_engine::Ctx<'e>,\n    }}\n"
    );
    let _ = writeln!(out, "    impl<'e> {name}<'_, 'e> {{");
    let mut items: Vec<String> = Vec::new();
    for f in &m.ids {
        items.push(ids_reader(m, f));
    }
    for w in &c.ids {
        if let Some(f) = m.ids.iter().find(|f| f.name == w.name) {
            items.push(ids_writer(f));
        }
    }
    for pm in &layer.modules {
        for p in &pm.ports {
            let Some(ty) = &p.ty else { continue };
            let t = rust_type(ty, At::Module);
            // an `Int` port holds an `i64`: read by value, and only in range (a value out
            // of range, written through `untyped()`, reads as none)
            let (ret, stored, read) = if is_int(ty) {
                (t, "::<i64>", ".and_then(|v| bip_engine::Bounded::new(*v))")
            } else {
                (format!("&{t}"), "", "")
            };
            items.push(format!(
                "        /// The data last written on port `{m}.{p}` ({ty}), if any.\n        pub fn read_{rm}_{rp}(&self) -> Option<{ret}> {{\n            self.ctx.port{stored}(\"{m}\", \"{p}\"){read}\n        }}",
                m = pm.name,
                p = p.name,
                rm = snake(&pm.name).trim_start_matches("r#"),
                rp = snake(&p.name).trim_start_matches("r#"),
            ));
        }
    }
    for w in &c.writes {
        let Some(ty) = m
            .ports
            .iter()
            .find(|p| &p.name == w)
            .and_then(|p| p.ty.as_ref())
        else {
            continue;
        };
        let t = rust_type(ty, At::Module);
        let r = snake(w);
        let r = r.trim_start_matches("r#");
        if is_int(ty) {
            // no `&mut i64`: the port's data stays in range
            items.push(format!(
                "        /// Replaces the data of port `{w}` ({ty}).\n        pub fn write_{r}(&mut self, value: {t}) {{\n            self.ctx.write_port(\"{w}\", value.get());\n        }}"
            ));
            continue;
        }
        items.push(format!(
            "        /// The data of port `{w}` ({ty}), to update in place (created with\n        /// `Default` on first use; `None` only after a fault).\n        pub fn port_{r}_mut(&mut self) -> Option<&mut {t}> {{\n            self.ctx.port_mut(\"{w}\")\n        }}"
        ));
        items.push(format!(
            "        /// Replaces the data of port `{w}` ({ty}).\n        pub fn write_{r}(&mut self, value: {t}) {{\n            self.ctx.write_port(\"{w}\", value);\n        }}"
        ));
    }
    if let Some(ty) = &s.args {
        let t = rust_type(ty, At::Module);
        let (ret, body) = if is_int(ty) {
            (
                t,
                "self.ctx.args::<i64>().and_then(|v| bip_engine::Bounded::new(*v))",
            )
        } else {
            (format!("&{t}"), "self.ctx.args()")
        };
        items.push(format!(
            "        /// The arguments of the request the activity serves ({ty}); `None` if it was\n        /// requested without.\n        pub fn args(&self) -> Option<{ret}> {{\n            {body}\n        }}"
        ));
    }
    if let Some(ty) = &s.output {
        let given = if is_int(ty) { "value.get()" } else { "value" };
        items.push(format!(
            "        /// Gives the output of the request the activity serves ({ty}).\n        pub fn set_output(&mut self, value: {}) {{\n            self.ctx.set_output({given});\n        }}",
            rust_type(ty, At::Module)
        ));
    }
    items.push(
        "        /// The engine's time, in microseconds since it started.\n        pub fn now_us(&self) -> u64 {\n            self.ctx.now_us()\n        }".into(),
    );
    items.push(
        "        /// Ticks fired so far.\n        pub fn tick(&self) -> u64 {\n            self.ctx.tick()\n        }".into(),
    );
    items.push(
        "        /// The engine's untyped context, for what the model leaves untyped (a port\n        /// without a type).\n        pub fn untyped(&mut self) -> &mut bip_engine::Ctx<'e> {\n            self.ctx\n        }".into(),
    );
    out.push_str(&items.join("\n\n"));
    out.push_str("\n    }\n\n");
}

/// The reader of ids field `f` of `m`: a `bool` for a `Bool` field, else a `Bounded` of
/// its range.
fn ids_reader(m: &ModuleMap, f: &IdsField) -> String {
    let name = &f.name;
    let r = snake(name);
    let r = r.trim_start_matches("r#");
    let (range, ty, body) = if f.is_bool {
        (
            "Bool".to_string(),
            "bool".to_string(),
            format!("self.ctx.get_bool(\"{name}\").unwrap_or_default()"),
        )
    } else {
        (
            format!("`{}..={}`", f.lo, f.hi),
            bounded(f.lo, f.hi),
            // only an out-of-range value set through `untyped()` (a fault when the codel
            // returns) is moved into the range
            format!(
                "bip_engine::Bounded::saturating(self.ctx.get(\"{name}\").unwrap_or_default())"
            ),
        )
    };
    format!(
        "        /// Ids field `{name}` of `{m}` ({range}), as this codel left it so far.\n        pub fn ids_{r}(&self) -> {ty} {{\n            {body}\n        }}",
        m = m.name,
    )
}

/// The writer of ids field `f`, for a codel that `writes` it.
fn ids_writer(f: &IdsField) -> String {
    let name = &f.name;
    let r = snake(name);
    let r = r.trim_start_matches("r#");
    if f.is_bool {
        format!(
            "        /// Writes ids field `{name}` (Bool).\n        pub fn set_ids_{r}(&mut self, value: bool) {{\n            self.ctx.set_bool(\"{name}\", value);\n        }}"
        )
    } else {
        format!(
            "        /// Writes ids field `{name}` (`{lo}..={hi}`).\n        pub fn set_ids_{r}(&mut self, value: {t}) {{\n            self.ctx.set(\"{name}\", value.get());\n        }}",
            lo = f.lo,
            hi = f.hi,
            t = bounded(f.lo, f.hi),
        )
    }
}
