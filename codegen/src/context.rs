//! Per codel a typed context over the engine's `Ctx`: its module's ids fields (a setter
//! only for those it `writes`), a reader for every typed port of the layer, a writer for
//! each typed port it `writes`, its service's arguments and output, each of the type the
//! model declares. What the model does not let the codel touch has no method, so using it
//! does not compile. Every accessor is a call of `Ctx` with names fixed at generation:
//! nothing is allocated.

use std::fmt::Write as _;

use bip_model::genom::map::{CodelMap, ModuleMap, ServiceMap};
use bip_model::genom::GenomMap;

use crate::names::snake;
use crate::types::{rust_type, At};

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
        items.push(format!(
            "        /// Ids field `{f}` of `{m}` (`{lo}..={hi}`), as this codel left it so far.\n        pub fn ids_{r}(&self) -> i64 {{\n            self.ctx.get(\"{f}\").unwrap_or_default()\n        }}",
            f = f.name,
            m = m.name,
            lo = f.lo,
            hi = f.hi,
            r = snake(&f.name),
        ));
    }
    for f in &c.ids {
        items.push(format!(
            "        /// Writes ids field `{f}` (`{lo}..={hi}`): a value out of range when the codel\n        /// returns is a fault.\n        pub fn set_ids_{r}(&mut self, value: i64) {{\n            self.ctx.set(\"{f}\", value);\n        }}",
            f = f.name,
            lo = f.lo,
            hi = f.hi,
            r = snake(&f.name),
        ));
    }
    for pm in &layer.modules {
        for p in &pm.ports {
            let Some(ty) = &p.ty else { continue };
            items.push(format!(
                "        /// The data last written on port `{m}.{p}` ({ty}), if any.\n        pub fn read_{rm}_{rp}(&self) -> Option<&{t}> {{\n            self.ctx.port(\"{m}\", \"{p}\")\n        }}",
                m = pm.name,
                p = p.name,
                rm = snake(&pm.name).trim_start_matches("r#"),
                rp = snake(&p.name).trim_start_matches("r#"),
                t = rust_type(ty, At::Module),
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
        items.push(format!(
            "        /// The data of port `{w}` ({ty}), to update in place (created with\n        /// `Default` on first use; `None` only after a fault).\n        pub fn port_{r}_mut(&mut self) -> Option<&mut {t}> {{\n            self.ctx.port_mut(\"{w}\")\n        }}"
        ));
        items.push(format!(
            "        /// Replaces the data of port `{w}` ({ty}).\n        pub fn write_{r}(&mut self, value: {t}) {{\n            self.ctx.write_port(\"{w}\", value);\n        }}"
        ));
    }
    if let Some(ty) = &s.args {
        items.push(format!(
            "        /// The arguments of the request the activity serves ({ty}); `None` if it was\n        /// requested without.\n        pub fn args(&self) -> Option<&{}> {{\n            self.ctx.args()\n        }}",
            rust_type(ty, At::Module)
        ));
    }
    if let Some(ty) = &s.output {
        items.push(format!(
            "        /// Gives the output of the request the activity serves ({ty}).\n        pub fn set_output(&mut self, value: {}) {{\n            self.ctx.set_output(value);\n        }}",
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
