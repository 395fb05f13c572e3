//! What GenoM3 gives a component's codels in C beside its types: the ids struct
//! (`loco_ids`), the events a codel returns as constants (`loco_ether`,
//! `loco_pause_track`), a handle struct per port with its `data` and `read` or `write`
//! functions, and each codel's prototype in GenoM3's passing convention: an `in`
//! parameter by value (a struct, union, sequence or optional by `const` pointer, an array
//! or a string as a `const` array), an `out` or `inout` one by pointer (an array or a
//! bounded string as an array), a port as a `const` pointer to its handle, and
//! `const genom_context self` last.

use std::collections::BTreeSet;
use std::fmt::Write as _;

use bip_lang::gen3::ast::{Codel, CodelParam, Component, Dir, PortDir, Service, Source};

use super::ctype::{cname, Body, CType, CTypes};
use super::decls::{declaration, templates, Written};
use crate::CodegenError;

/// Declares the ids struct of `comp` among `types`, as `{comp}::ids`.
pub fn add_ids(types: &mut CTypes, comp: &Component) -> Result<String, CodegenError> {
    let key = format!("{}::ids", comp.name.value);
    let members = comp
        .ids
        .iter()
        .map(|m| Ok((m.name.value.clone(), types.ctype(&m.ty, &key)?)))
        .collect::<Result<Vec<_>, CodegenError>>()
        .map_err(|e| within(e, &format!("ids of component `{}`", comp.name.value)))?;
    types.add_struct(&key, members);
    Ok(key)
}

/// `e` said of `place` (`component `loco``, `port `pose``).
pub(super) fn within(e: CodegenError, place: &str) -> CodegenError {
    match e {
        CodegenError::CMapping(m) => CodegenError::CMapping(format!("{place}: {m}")),
        other => other,
    }
}

/// The events of `comp` as C constants: `ether` and every yield its codels declare
/// (`pause::track` is `loco_pause_track`). An event and a codel of one C name are an
/// error.
pub fn events(out: &mut String, comp: &Component) -> Result<(), CodegenError> {
    let c = &comp.name.value;
    let mut names = BTreeSet::new();
    names.insert("ether".to_string());
    for codel in all_codels(comp).map(|(_, k)| k) {
        names.extend(codel.yields.iter().map(|y| y.value.replace(' ', "")));
    }
    for e in &names {
        let n = cname(&format!("{c}::{e}"));
        if let Some((_, k)) = all_codels(comp).find(|(_, k)| k.function.value == n) {
            return Err(CodegenError::Clash {
                first: format!("event `{e}` of component `{c}`"),
                second: format!("codel `{}`", k.function.value),
                rust: n,
            });
        }
    }
    out.push_str("/* the events a codel returns */\n");
    for e in names {
        let _ = writeln!(
            out,
            "const char genom_extern_weak {}[] = \"::{c}::{e}\";",
            cname(&format!("{c}::{e}"))
        );
    }
    out.push('\n');
    Ok(())
}

/// Every codel of `comp` with its service (none for a task's): activities' states,
/// functions' codels, validations, then task machines.
pub fn all_codels(comp: &Component) -> impl Iterator<Item = (Option<&Service>, &Codel)> {
    let services = comp.services.iter().flat_map(|s| {
        s.validate
            .iter()
            .chain(&s.codels)
            .chain(&s.simple)
            .map(move |c| (Some(s), c))
    });
    services.chain(
        comp.tasks
            .iter()
            .flat_map(|t| t.codels.iter().map(|c| (None, c))),
    )
}

/// The handle struct of each port of `comp`, after the anonymous types of its data.
pub fn ports(
    out: &mut String,
    types: &CTypes,
    comp: &Component,
    written: &mut Written,
) -> Result<(), CodegenError> {
    let c = &comp.name.value;
    for p in &comp.ports {
        let t = types
            .ctype(&p.ty, c)
            .map_err(|e| within(e, &format!("port `{}`", p.name.value)))?;
        templates(out, types, &t, written);
        let n = cname(&format!("{c}::{}", p.name.value));
        let id = if p.multiple { "const char *id, " } else { "" };
        let data = data_member(types, &t, &format!("{id}genom_context self"));
        let mut s = format!("typedef struct {n} {{\n  {data};\n");
        match p.dir {
            PortDir::In => {
                let _ = writeln!(s, "  genom_event (*read)({id}genom_context self);");
            }
            PortDir::Out => {
                let _ = writeln!(s, "  genom_event (*write)({id}genom_context self);");
                if p.multiple {
                    s.push_str("  genom_event (*open)(const char *id, genom_context self);\n");
                    s.push_str("  genom_event (*close)(const char *id, genom_context self);\n");
                }
            }
        }
        let _ = writeln!(s, "}} {n};");
        let _ = write!(
            out,
            "#ifndef BIP_C_TYPE_{n}\n#define BIP_C_TYPE_{n}\n{s}#endif\n\n"
        );
    }
    Ok(())
}

/// A port handle's `data` member: a function that returns a pointer to the data, or to
/// its first element for an array or a bounded string (`double (*(*data)(..))[3]` for
/// a `double[3][3]`).
fn data_member(types: &CTypes, t: &CType, args: &str) -> String {
    let f = format!("*(*data)({args})");
    match types.fin(t) {
        CType::String(Some(_)) => format!("char {f}"),
        CType::Array(e, _) => types.declare(e, &f),
        _ => types.declare(t, &f),
    }
}

/// What a codel parameter is in C.
pub enum Param {
    Data(CType),
    /// A port: its handle struct's C name.
    Port(String),
}

/// Where a codel parameter's data lives, as a path of members and indices (`[2]`) from
/// its root.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Place {
    /// In the ids (an empty path is the whole ids).
    Ids(Vec<String>),
    /// In a parameter or a local of the codel's service (the path's first name).
    Service(Vec<String>),
    /// A port, by name.
    Port(String),
}

/// The prototype of each codel of `comp`, once per function.
pub fn prototypes(
    out: &mut String,
    types: &CTypes,
    comp: &Component,
    ids: &str,
) -> Result<(), CodegenError> {
    let mut seen = BTreeSet::new();
    out.push_str("/* the codels, as the component declares them */\n");
    for (s, codel) in all_codels(comp) {
        if !seen.insert(codel.function.value.clone()) {
            continue;
        }
        let mut args = Vec::new();
        for p in &codel.params {
            let place = format!(
                "parameter `{}` of codel `{}`",
                p.name.value, codel.function.value
            );
            let var = c_name(p);
            let (_, ty) = param(types, comp, s, ids, p).map_err(|e| within(e, &place))?;
            let arg = match ty {
                Param::Port(handle) => format!("const {handle} *{var}"),
                Param::Data(t) if p.dir == Dir::In => argument_value(types, &t, &var),
                Param::Data(t) => argument_reference(types, &t, &var),
            };
            args.push(arg);
        }
        args.push("const genom_context self".into());
        let _ = writeln!(
            out,
            "genom_event\n{}({});\n",
            codel.function.value,
            args.join(", ")
        );
    }
    Ok(())
}

/// The name of a codel parameter in C: its variable's last member (`wo.bias` is `bias`),
/// `ids` for the whole ids.
fn c_name(p: &CodelParam) -> String {
    p.path
        .iter()
        .rev()
        .find(|s| !s.starts_with('['))
        .cloned()
        .unwrap_or_else(|| p.name.value.clone())
}

/// GenoM3's `in` convention.
fn argument_value(types: &CTypes, t: &CType, var: &str) -> String {
    match types.fin(t) {
        CType::Sequence(..) | CType::Optional(_) => {
            format!("const {}", types.declare(t, &format!("*{var}")))
        }
        CType::String(_) | CType::Array(..) => format!("const {}", types.declare(t, var)),
        CType::Named(k) => match types.decl(k).map(|d| &d.body) {
            Some(Body::Struct(_)) | Some(Body::Union { .. }) | Some(Body::Exception(_)) => {
                format!("const {}", types.declare(t, &format!("*{var}")))
            }
            Some(Body::Native) => format!("const {}", types.declare(t, var)),
            _ => types.declare(t, var),
        },
        CType::Basic(_) => types.declare(t, var),
    }
}

/// GenoM3's `out` and `inout` convention.
fn argument_reference(types: &CTypes, t: &CType, var: &str) -> String {
    match types.fin(t) {
        CType::String(Some(_)) | CType::Array(..) => types.declare(t, var),
        _ => types.declare(t, &format!("*{var}")),
    }
}

/// The type of codel parameter `p`, resolved as GenoM3 resolves its name: its source if
/// written, else the ids member, the service's parameter or local, or the port of that
/// name; then its path of members and indices. With where its data lives.
pub fn param(
    types: &CTypes,
    comp: &Component,
    s: Option<&Service>,
    ids: &str,
    p: &CodelParam,
) -> Result<(Place, Param), CodegenError> {
    let c = &comp.name.value;
    let Some(first) = p.path.first() else {
        return Ok((
            Place::Ids(Vec::new()),
            Param::Data(CType::Named(ids.to_string())),
        ));
    };
    let id = comp.ids.iter().find(|m| &m.name.value == first);
    // a parameter or local: its IDL type, or an attribute's ids member path
    let local = s.and_then(
        |s| match s.params.iter().find(|q| q.local_name() == first) {
            Some(q) => Some(match &q.ty {
                Some(ty) => Ok(ty.clone()),
                None => Err(q
                    .name
                    .value
                    .split('.')
                    .map(str::to_string)
                    .collect::<Vec<_>>()),
            }),
            None => s
                .locals
                .iter()
                .find(|l| &l.name.value == first)
                .map(|l| Ok(l.ty.clone())),
        },
    );
    let port = comp.ports.iter().find(|q| &q.name.value == first);
    let source = p.source.unwrap_or(if id.is_some() {
        Source::Ids
    } else if local.is_some() {
        Source::Local
    } else if port.is_some() {
        Source::Port
    } else {
        Source::Remote
    });
    let (place, mut t) = match source {
        Source::Ids => (
            Place::Ids(p.path.clone()),
            ids_member(types, comp, ids, &p.path[..1])?,
        ),
        Source::Local => match local {
            Some(Ok(ty)) => (Place::Service(p.path.clone()), types.ctype(&ty, c)?),
            Some(Err(path)) => {
                let mut at = path.clone();
                at.extend(p.path[1..].iter().cloned());
                (Place::Ids(at), ids_member(types, comp, ids, &path)?)
            }
            None => {
                return Err(CodegenError::CMapping(format!(
                    "no parameter or local `{first}`"
                )))
            }
        },
        Source::Port => {
            return match port {
                Some(q) => Ok((
                    Place::Port(q.name.value.clone()),
                    Param::Port(cname(&format!("{c}::{}", q.name.value))),
                )),
                None => Err(CodegenError::CMapping(format!("no port `{first}`"))),
            }
        }
        Source::Remote => {
            return Err(CodegenError::CMapping(
                "remote services have no C mapping in bip's headers".into(),
            ))
        }
    };
    for step in &p.path[1..] {
        t = member(types, &t, step)
            .ok_or_else(|| CodegenError::CMapping(format!("`{step}` is not a member here")))?;
    }
    Ok((place, Param::Data(t)))
}

/// The type of the ids member at `path` (`["body", "wmin"]`).
fn ids_member(
    types: &CTypes,
    comp: &Component,
    ids: &str,
    path: &[String],
) -> Result<CType, CodegenError> {
    let no = |what: &str| CodegenError::CMapping(format!("no ids member `{what}`"));
    let first = path.first().ok_or_else(|| no(""))?;
    let m = comp
        .ids
        .iter()
        .find(|m| &m.name.value == first)
        .ok_or_else(|| no(first))?;
    let mut t = types.ctype(&m.ty, ids)?;
    for step in &path[1..] {
        t = member(types, &t, step).ok_or_else(|| no(&path.join(".")))?;
    }
    Ok(t)
}

/// The type of member `step` (`x`, or an index `[2]`) of `t`.
fn member(types: &CTypes, t: &CType, step: &str) -> Option<CType> {
    match types.fin(t) {
        CType::Array(e, _) if step.starts_with('[') => Some((**e).clone()),
        CType::Named(k) => match &types.decl(k)?.body {
            Body::Struct(ms) | Body::Union { members: ms, .. } => {
                ms.iter().find(|(n, _)| n == step).map(|(_, t)| t.clone())
            }
            _ => None,
        },
        _ => None,
    }
}

/// The ids struct's declaration.
pub fn ids_struct(out: &mut String, types: &CTypes, key: &str, written: &mut Written) {
    declaration(out, types, key, written);
}
