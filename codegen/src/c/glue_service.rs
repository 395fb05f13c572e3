//! A service's part of the generated glue: the storage of its parameters and locals in
//! the C layout, filled from a request's arguments at its `start` codel, and its output
//! given back to the engine after each codel, with the conversions between the engine's
//! values of the model's types and the mirrors (`glue_args::Conv`).

use std::fmt::Write as _;

use bip_lang::gen3::ast::{Component, Dir, Service};
use bip_lang::genom::syntax::{DataTypeDef, ServiceDef};

use super::codels::within;
use super::ctype::{holds_native, owns_buffer, CType, CTypes};
use super::glue_args::Conv;
use super::mirror::{defaulted, derives, maxima, Mirrors};
use crate::names::ident;
use crate::CodegenError;

/// What a service's storage is in the glue's `State`.
pub struct ServiceData {
    /// Its type, `{S}_data`.
    pub ty: String,
    /// Whether it is `Copy` (it owns no buffer).
    pub copy: bool,
    /// Whether it gives an output (the service has `out` or `inout` parameters).
    pub output: bool,
}

/// One parameter or local of the storage.
struct Field {
    dir: Dir,
    name: String,
    c: CType,
    /// Its name in Rust, and its mirror.
    rust: String,
    mirror: String,
}

/// How the engine's value of a request's arguments (or of an output) is the storage's:
/// one parameter of the model's type, or the glue's struct of them.
enum Payload {
    One(Conv),
    Struct(String),
}

/// The storage of service `s`'s parameters and locals (`{S}_data`), and, where the model's
/// type of its arguments or output is a record of several or no model type, the
/// `{S}_input` or `{S}_output` struct the engine takes; the functions that fill the storage
/// from a request (`args_{S}`, at its `start` codel) and give the output (`output_{S}`,
/// after each codel). `None` for a service with neither.
pub fn service_data(
    m: &mut Mirrors,
    types: &CTypes,
    comp: &Component,
    s: &Service,
    def: &ServiceDef,
    out: &mut String,
) -> Result<Option<ServiceData>, CodegenError> {
    let c = &comp.name.value;
    let name = &s.name.value;
    let mut fields = Vec::new();
    let typed = s
        .params
        .iter()
        .filter_map(|p| Some((p.dir, &p.name.value, p.ty.as_ref()?)));
    let locals = s.locals.iter().map(|l| (Dir::InOut, &l.name.value, &l.ty));
    let n_locals = s.locals.len();
    for (dir, n, ty) in typed.chain(locals) {
        let t = types.ctype(ty, c)?;
        fields.push(Field {
            dir,
            name: n.clone(),
            rust: ident(n),
            mirror: m.rust(types, &t, 1)?,
            c: t,
        });
    }
    let has_codels = !s.codels.is_empty() || !s.simple.is_empty() || s.validate.is_some();
    if fields.is_empty() || !has_codels {
        return Ok(None);
    }
    let data = format!("{name}_data");
    let copy = !fields.iter().any(|f| owns_buffer(types, &f.c));
    let _ = writeln!(
        out,
        "\n/// Service `{name}`'s parameters and locals, in the C layout.\n{}pub struct {data} {{",
        derives(copy)
    );
    for f in &fields {
        let _ = writeln!(out, "    pub {}: {},", f.rust, f.mirror);
    }
    out.push_str("}\n");
    let set: String = fields
        .iter()
        .map(|f| maxima(types, &f.c, &format!("v.{}", f.rust), 0))
        .collect();
    out.push_str(&defaulted(&data, &set));
    let params = &fields[..fields.len() - n_locals];
    let ins: Vec<&Field> = params.iter().filter(|f| f.dir != Dir::Out).collect();
    let outs: Vec<&Field> = params.iter().filter(|f| f.dir != Dir::In).collect();
    let mut structs = String::new();

    // the arguments, at the start codel
    let _ = writeln!(
        out,
        "/// Fills `d` for a new request of `{name}` from its arguments; false if they are missing.\n#[allow(unused_variables)]\nfn args_{name}(d: &mut {data}, ctx: &bip_genom_c::bip_engine::Ctx<'_>) -> bool {{\n    *d = {data}::default();"
    );
    match payload(
        m,
        types,
        name,
        "input",
        &ins,
        def.args.as_ref(),
        &mut structs,
    )? {
        None => {}
        Some(Payload::One(conv)) => {
            let f = ins[0];
            let _ = writeln!(
                out,
                "    match ctx.args::<{}>() {{\n        Some(v) => d.{} = {},\n        None => return false,\n    }}",
                conv.engine_type(&f.mirror),
                f.rust,
                conv.to_c("v", &f.mirror)
            );
        }
        Some(Payload::Struct(t)) => {
            let _ = writeln!(
                out,
                "    let Some(v) = ctx.args::<{t}>() else {{\n        return false;\n    }};"
            );
            for f in &ins {
                let _ = writeln!(out, "    d.{0} = {1};", f.rust, copied(types, f, "v"));
            }
        }
    }
    // a bounded sequence's bound is the type's, whatever the request's copy says
    for f in &ins {
        out.push_str(&maxima(types, &f.c, &format!("d.{}", f.rust), 0));
    }
    out.push_str("    true\n}\n");

    // the output, after each codel
    if !outs.is_empty() {
        let _ = writeln!(
            out,
            "/// Gives `{name}`'s output (its `out` and `inout` parameters) to the engine.\n#[allow(unused_variables)]\nfn output_{name}(d: &{data}, ctx: &mut bip_genom_c::bip_engine::Ctx<'_>) {{"
        );
        match payload(
            m,
            types,
            name,
            "output",
            &outs,
            def.output.as_ref(),
            &mut structs,
        )? {
            None => {}
            Some(Payload::One(conv)) => {
                let _ = writeln!(
                    out,
                    "    ctx.set_output({});",
                    conv.to_engine(&format!("d.{}", outs[0].rust))
                );
            }
            Some(Payload::Struct(t)) => {
                let fs: Vec<String> = outs
                    .iter()
                    .map(|f| format!("{}: {}", f.rust, copied(types, f, "d")))
                    .collect();
                let _ = writeln!(out, "    ctx.set_output({t} {{ {} }});", fs.join(", "));
            }
        }
        out.push_str("}\n");
    }
    out.push_str(&structs);
    Ok(Some(ServiceData {
        ty: data,
        copy,
        output: !outs.is_empty(),
    }))
}

/// Field `f` of the struct at `of`, copied (cloned where it owns a buffer).
fn copied(types: &CTypes, f: &Field, of: &str) -> String {
    if owns_buffer(types, &f.c) {
        format!("{of}.{}.clone()", f.rust)
    } else {
        format!("{of}.{}", f.rust)
    }
}

/// How the parameters `chosen` of service `name` travel as its `what` (`input` or
/// `output`), whose model type is `def`: one parameter as the model types it (a model
/// type, an unbounded sequence or string as a `Vec` or `String`, a declared type as its
/// mirror), or the glue's `{name}_{what}` struct of them, written to `out`.
fn payload(
    m: &mut Mirrors,
    types: &CTypes,
    name: &str,
    what: &str,
    chosen: &[&Field],
    def: Option<&DataTypeDef>,
    out: &mut String,
) -> Result<Option<Payload>, CodegenError> {
    let Some(def) = def else {
        return Ok(None);
    };
    for f in chosen {
        if holds_native(types, &f.c) {
            return Err(CodegenError::CMapping(format!(
                "service `{name}`: parameter `{}` holds a native (a pointer to the codels' own object), which a request or a reply cannot carry",
                f.name
            )));
        }
    }
    let one = match (chosen, def) {
        ([], _) => return Ok(None),
        ([_], DataTypeDef::Rust(path)) => match &chosen[0].c {
            CType::Named(k) if *k == path.value => true,
            _ => path.value == "String" || path.value.starts_with("Vec<"),
        },
        ([_], _) => true,
        _ => false,
    };
    if one {
        let place = format!("service `{name}`: parameter `{}`", chosen[0].name);
        let conv = Conv::of(m, types, &chosen[0].c, Some(def)).map_err(|e| within(e, &place))?;
        return Ok(Some(Payload::One(conv)));
    }
    let t = format!("{name}_{what}");
    let copy = !chosen.iter().any(|f| owns_buffer(types, &f.c));
    let _ = writeln!(
        out,
        "/// Service `{name}`'s {what} as the engine takes it.\n{}pub struct {t} {{",
        derives(copy)
    );
    for f in chosen {
        let _ = writeln!(out, "    pub {}: {},", f.rust, f.mirror);
    }
    out.push_str("}\n");
    let set: String = chosen
        .iter()
        .map(|f| maxima(types, &f.c, &format!("v.{}", f.rust), 0))
        .collect();
    out.push_str(&defaulted(&t, &set));
    Ok(Some(Payload::Struct(t)))
}
