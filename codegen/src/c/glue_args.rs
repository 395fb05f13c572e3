//! The Rust side of one codel call in the generated glue: per codel parameter, its type
//! in the codel's `extern "C"` declaration and the expression that passes it, in GenoM3's
//! passing convention (`codels`), from memory of the C layout the module object owns (a
//! raw pointer `s` to its `State`: the ids, each service's parameters and locals, each
//! port's data); and the conversions between the engine's values of the model's data
//! types and the C mirrors (a request's arguments, an output, port data).

use bip_lang::genom::syntax::DataTypeDef;

use super::codels::{Param, Place};
use super::ctype::{owns_buffer, Basic, Body, CType, CTypes};
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
    place_in("s", place, service)
}

/// The expression of `place` from `state`, a `*mut State` (`(*state).ids.limits.lo`).
pub fn place_in(state: &str, place: &Place, service: Option<&str>) -> Result<String, CodegenError> {
    let (mut out, path) = match place {
        Place::Ids(path) => (format!("(*{state}).ids"), &path[..]),
        Place::Service(path) => {
            let s = service.ok_or_else(|| {
                CodegenError::CMapping("a task's codel names no service parameter".into())
            })?;
            (format!("(*{state}).{}", service_field(s)), &path[..])
        }
        Place::Port(p) => return Ok(format!("(*{state}).{}", port_field(p))),
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
        // a `const char *` into the string the memory owns
        (true, None) if matches!(types.fin(t), CType::String(None)) => Arg {
            ty: "*const core::ffi::c_char".into(),
            expr: format!("{place}.0.cast_const()"),
        },
        // C passes a long double by value as Rust can pass nothing
        (true, None) if types.fin(t) == &CType::Basic(Basic::LongDouble) => {
            return Err(CodegenError::CMapping(
                "an `in long double` is passed by value, which Rust cannot do (x87's calling convention): make it `inout`, or a member of a struct".into(),
            ))
        }
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

/// How the engine's value of a model data type becomes the C mirror and back: an `Int`
/// is an `i64`, a `Float` an `f64`, a `Bool` a `bool`; an anonymous unbounded sequence of
/// a basic type a `Vec` of it, a string (bounded or not) a `String` (as the model names
/// them);
/// a record, a declared type (or a port the model leaves untyped) the mirror itself, which
/// the engine accepts by its name, cloned where it owns a buffer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Conv {
    Int,
    Float,
    /// An `f64` as bip-genom-c's `LongDouble`.
    LongDouble,
    Bool,
    /// A `Vec` of the element mirror.
    Vec(String),
    /// A `Vec` of the element mirror as a bounded sequence of this bound (cut there).
    BoundedVec(String, u64),
    String,
    /// A `String` as a `char[N]`.
    BoundedString(u64),
    Mirror {
        copy: bool,
    },
}

impl Conv {
    /// The conversion of data of C type `t` to the model's type `def`.
    pub fn of(
        m: &mut Mirrors,
        types: &CTypes,
        t: &CType,
        def: Option<&DataTypeDef>,
    ) -> Result<Conv, CodegenError> {
        let mirror = m.rust(types, t, 1)?;
        Ok(match def {
            // the engine's own type: nothing to convert
            Some(DataTypeDef::Int(..)) if mirror == "i64" => Conv::Mirror { copy: true },
            Some(DataTypeDef::Float) if mirror == "f64" => Conv::Mirror { copy: true },
            Some(DataTypeDef::Int(..)) => Conv::Int,
            Some(DataTypeDef::Float) if types.fin(t) == &CType::Basic(Basic::LongDouble) => {
                Conv::LongDouble
            }
            Some(DataTypeDef::Float) => Conv::Float,
            Some(DataTypeDef::Bool) => Conv::Bool,
            Some(DataTypeDef::Rust(path)) if path.value == "String" => match types.fin(t) {
                CType::String(None) => Conv::String,
                CType::String(Some(n)) => Conv::BoundedString(*n),
                _ => Conv::Mirror {
                    copy: !owns_buffer(types, t),
                },
            },
            Some(DataTypeDef::Rust(path)) if path.value.starts_with("Vec<") => {
                let (e, bound) = match types.fin(t) {
                    CType::Sequence(e, bound) => (e, *bound),
                    _ => {
                        return Ok(Conv::Mirror {
                            copy: !owns_buffer(types, t),
                        })
                    }
                };
                let element = m.rust(types, e, 1)?;
                if path.value != format!("Vec<{element}>") {
                    return Err(CodegenError::CMapping(format!(
                        "the model names its data `{}`, which the engine checks by name and the glue cannot give from its mirror's `{element}` elements; give the sequence a struct of its own",
                        path.value
                    )));
                }
                match bound {
                    None => Conv::Vec(element),
                    Some(n) => Conv::BoundedVec(element, n),
                }
            }
            _ => Conv::Mirror {
                copy: !owns_buffer(types, t),
            },
        })
    }

    /// The engine's Rust type for a value whose mirror is `mirror`.
    pub fn engine_type(&self, mirror: &str) -> String {
        match self {
            Conv::Int => "i64".into(),
            Conv::Float | Conv::LongDouble => "f64".into(),
            Conv::Bool => "bool".into(),
            Conv::Vec(e) | Conv::BoundedVec(e, _) => format!("Vec<{e}>"),
            Conv::String | Conv::BoundedString(_) => "String".into(),
            Conv::Mirror { .. } => mirror.into(),
        }
    }

    /// The mirror `mirror` of the engine's value that `r` (an expression of a reference)
    /// refers to.
    pub fn to_c(&self, r: &str, mirror: &str) -> String {
        match self {
            Conv::Int | Conv::Float => format!("*{r} as {mirror}"),
            Conv::LongDouble => format!("bip_genom_c::LongDouble::from_f64(*{r})"),
            Conv::Bool | Conv::Mirror { copy: true } => format!("*{r}"),
            Conv::Mirror { copy: false } => format!("{r}.clone()"),
            Conv::Vec(_) => format!("bip_genom_c::Sequence::from_slice({r})"),
            Conv::BoundedVec(_, n) => format!(
                "{{ let mut s = {mirror}::default(); let k = {r}.len().min({n}); s._buffer[..k].copy_from_slice(&{r}[..k]); s._length = k as u32; s }}"
            ),
            Conv::String => format!("bip_genom_c::GenomString::new({r})"),
            Conv::BoundedString(n) => format!("bip_genom_c::owned::bounded_string::<{n}>({r})"),
        }
    }

    /// The engine's value of the mirror at place `v`, a copy that owns its buffers.
    pub fn to_engine(&self, v: &str) -> String {
        match self {
            Conv::Int => format!("{v} as i64"),
            Conv::Float => format!("{v} as f64"),
            Conv::LongDouble => format!("{v}.to_f64()"),
            Conv::Bool | Conv::Mirror { copy: true } => v.into(),
            Conv::Mirror { copy: false } => format!("{v}.clone()"),
            Conv::Vec(_) => format!("{v}.to_vec()"),
            Conv::BoundedVec(_, n) => {
                format!("(&{v}._buffer)[..({v}._length as usize).min({n})].to_vec()")
            }
            Conv::String => format!("{v}.to_string_lossy()"),
            Conv::BoundedString(_) => format!("bip_genom_c::owned::bounded_text(&{v})"),
        }
    }
}
