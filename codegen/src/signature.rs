//! What the bindings were made for, for the engine to check against the model it is
//! built for: per module its codels in the order `bind` numbers them with their outcomes
//! in the order their enums number them (`CODELS`), and its data types (`TYPES`).

use std::fmt::Write as _;

use bip_model::genom::map::{CodelMap, ModuleMap, ServiceMap};

/// `CODELS`: `codels` as `bind` numbers them.
pub(crate) fn codels<'a>(
    out: &mut String,
    m: &ModuleMap,
    codels: impl Iterator<Item = (&'a ServiceMap, &'a CodelMap)>,
) {
    let _ = writeln!(
        out,
        "    /// The codels of module `{}` as [`bind`] numbers them, with their outcomes: the\n    /// engine refuses to build if its model declares others.\n    pub const CODELS: &[bip_engine::CodelSignature] = &[",
        m.name
    );
    for (s, c) in codels {
        let yields = list(c.yields.iter().map(|y| y.target.as_str()));
        let throws = list(c.throws.iter().map(String::as_str));
        let _ = writeln!(
            out,
            "        bip_engine::CodelSignature {{\n            service: {:?},\n            codel: {:?},\n            yields: &[{yields}],\n            throws: &[{throws}],\n        }},",
            s.name, c.state
        );
    }
    out.push_str("    ];\n\n");
}

/// `TYPES`: the module's ids, ports and services with their types written in full.
pub(crate) fn types(out: &mut String, m: &ModuleMap) {
    let model = m.written_types();
    let _ = writeln!(
        out,
        "    /// The data types of module `{}` the typed code here assumes: the engine refuses\n    /// to build if its model declares others.\n    pub const TYPES: bip_engine::ModuleTypes = bip_engine::ModuleTypes {{",
        m.name
    );
    let typed = |out: &mut String, field: &str, xs: &[(&str, String)]| {
        let _ = write!(out, "        {field}: &[");
        for (name, ty) in xs {
            let _ = write!(
                out,
                "\n            bip_engine::Typed {{\n                name: {name:?},\n                ty: {ty:?},\n            }},"
            );
        }
        out.push_str(if xs.is_empty() {
            "],\n"
        } else {
            "\n        ],\n"
        });
    };
    typed(out, "ids", &model.ids);
    typed(out, "ports", &model.ports);
    out.push_str("        services: &[");
    for ((name, args), (_, output)) in model.args.iter().zip(&model.outputs) {
        let _ = write!(
            out,
            "\n            bip_engine::ServiceTypes {{\n                name: {name:?},\n                args: {args:?},\n                output: {output:?},\n            }},"
        );
    }
    out.push_str(if m.services.is_empty() {
        "],\n"
    } else {
        "\n        ],\n"
    });
    out.push_str("    };\n\n");
}

/// `"a", "b"`.
fn list<'a>(xs: impl Iterator<Item = &'a str>) -> String {
    xs.map(|x| format!("{x:?}")).collect::<Vec<_>>().join(", ")
}
