//! The Rust side of one codel call in the generated glue: per codel parameter, its type
//! in the codel's `extern "C"` declaration and the expression that passes it, in GenoM3's
//! passing convention (`codels`), from memory of the C layout the module object owns (a
//! raw pointer `s` to its `State`: the ids, each service's parameters and locals, each
//! port's data); and the conversions between the engine's values of the model's data
//! types and the C mirrors (a request's arguments, an output, port data).

use bip_lang::genom::syntax::DataTypeDef;

use super::codels::{Param, Place};
use super::ctype::{Body, CType, CTypes};
use super::mirror::Mirrors;
use crate::names::ident;
use crate::CodegenError;

/// The glue's name of a service's storage in `State`, and of a port's data and handle.
pub fn service_field(service: &str) -> String {
    format!("svc_{service}")
}

pub fn port_field(port: &str) -> String {
    format!("port_{port}")
}

pub fn port_handle(port: &str) -> String {
    format!("PORT_{port}")
}

/// One codel parameter as the glue passes it.
pub struct Arg {
    /// Its Rust type in the `extern "C"` declaration.
    pub ty: String,
    /// The expression that passes it (`s` is `*mut State`).
    pub expr: String,
}

/// The expression of `place` from `s: *mut State` (`(*s).ids.limits.lo`).
fn place_expr(place: &Place, service: Option<&str>) -> Result<String, CodegenError> {
    let (mut out, path) = match place {
        Place::Ids(path) => ("(*s).ids".to_string(), &path[..]),
        Place::Service(path) => {
            let s = service.ok_or_else(|| {
                CodegenError::CMapping("a task's codel names no service parameter".into())
            })?;
            (format!("(*s).{}", service_field(s)), &path[..])
        }
        Place::Port(p) => return Ok(format!("(*s).{}", port_field(p))),
    };
    for step in path {
        if step.starts_with('[') {
            out.push_str(step);
        } else {
            out.push('.');
            out.push_str(&ident(step));
        }
    }
    Ok(out)
}

/// How parameter `param` (`in` when `input`) at `place` is declared and passed.
pub fn arg(
    m: &mut Mirrors,
    types: &CTypes,
    place: &Place,
    param: &Param,
    input: bool,
    service: Option<&str>,
) -> Result<Arg, CodegenError> {
    let t = match param {
        Param::Port(handle) => {
            let Place::Port(p) = place else {
                return Err(CodegenError::CMapping(format!("`{handle}` is not a port")));
            };
            return Ok(Arg {
                ty: format!("*const {}", port_handle_type(p)),
                expr: format!("core::ptr::addr_of!({})", port_handle(p)),
            });
        }
        Param::Data(t) => t,
    };
    let place = place_expr(place, service)?;
    let rust = m.rust(types, t, 1)?;
    let element = |m: &mut Mirrors| -> Result<Option<String>, CodegenError> {
        Ok(match types.fin(t) {
            CType::String(Some(_)) => Some("core::ffi::c_char".to_string()),
            CType::Array(e, _) => Some(m.rust(types, e, 1)?),
            _ => None,
        })
    };
    Ok(match (input, element(m)?) {
        (_, Some(e)) if input => Arg {
            ty: format!("*const {e}"),
            expr: format!("core::ptr::addr_of!({place}).cast::<{e}>()"),
        },
        (_, Some(e)) => Arg {
            ty: format!("*mut {e}"),
            expr: format!("core::ptr::addr_of_mut!({place}).cast::<{e}>()"),
        },
        (true, None) if by_value(types, t) => Arg {
            ty: rust,
            expr: place,
        },
        (true, None) => Arg {
            ty: format!("*const {rust}"),
            expr: format!("core::ptr::addr_of!({place})"),
        },
        (false, None) => Arg {
            ty: format!("*mut {rust}"),
            expr: format!("core::ptr::addr_of_mut!({place})"),
        },
    })
}

/// Whether an `in` parameter of type `t` is passed by value: a basic type, an enum, a
/// native's pointer, an unbounded string's pointer.
fn by_value(types: &CTypes, t: &CType) -> bool {
    match types.fin(t) {
        CType::Basic(_) | CType::String(None) => true,
        CType::Named(k) => matches!(
            types.decl(k).map(|d| &d.body),
            Some(Body::Enum(_)) | Some(Body::Native)
        ),
        _ => false,
    }
}

/// The glue's `#[repr(C)]` mirror of a port's handle struct.
pub fn port_handle_type(port: &str) -> String {
    format!("PortHandle_{port}")
}

/// Whether data of type `t` holds a pointer (an unbounded string or sequence, a
/// native): such data cannot be handed to the engine, which keeps it past the call.
pub fn holds_pointer(types: &CTypes, t: &CType) -> bool {
    match types.fin(t) {
        CType::Basic(_) | CType::String(Some(_)) => false,
        CType::String(None) | CType::Sequence(_, None) => true,
        CType::Array(e, _) | CType::Sequence(e, Some(_)) | CType::Optional(e) => {
            holds_pointer(types, e)
        }
        CType::Named(k) => match types.decl(k).map(|d| &d.body) {
            Some(Body::Struct(ms)) | Some(Body::Exception(ms)) => {
                ms.iter().any(|(_, t)| holds_pointer(types, t))
            }
            Some(Body::Union { switch, members }) => {
                holds_pointer(types, switch) || members.iter().any(|(_, t)| holds_pointer(types, t))
            }
            Some(Body::Typedef(t)) => holds_pointer(types, t),
            Some(Body::Native) => true,
            _ => false,
        },
    }
}

/// How the engine's value of a model data type becomes the C mirror and back: an `Int`
/// is an `i64`, a `Float` an `f64`, a `Bool` a `bool`; a record (or a port the model
/// leaves untyped) is the mirror itself, which the engine accepts by its name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Conv {
    Int,
    Float,
    Bool,
    Mirror,
}

impl Conv {
    pub fn of(ty: Option<&DataTypeDef>) -> Conv {
        match ty {
            Some(DataTypeDef::Int(..)) => Conv::Int,
            Some(DataTypeDef::Float) => Conv::Float,
            Some(DataTypeDef::Bool) => Conv::Bool,
            _ => Conv::Mirror,
        }
    }

    /// The engine's Rust type for a value whose mirror is `mirror`.
    pub fn engine_type(self, mirror: &str) -> String {
        match self {
            Conv::Int => "i64".into(),
            Conv::Float => "f64".into(),
            Conv::Bool => "bool".into(),
            Conv::Mirror => mirror.into(),
        }
    }

    /// `v` (an engine value) as the mirror `mirror`.
    pub fn to_c(self, v: &str, mirror: &str) -> String {
        match self {
            Conv::Int | Conv::Float => format!("{v} as {mirror}"),
            Conv::Bool | Conv::Mirror => v.into(),
        }
    }

    /// `v` (a mirror's value) as the engine's.
    pub fn to_engine(self, v: &str) -> String {
        match self {
            Conv::Int => format!("{v} as i64"),
            Conv::Float => format!("{v} as f64"),
            Conv::Bool | Conv::Mirror => v.into(),
        }
    }
}
