//! The IDL types of a GenoM3 component as C types, following GenoM3's C mapping
//! (docs/codegen.md, "C codels"): the declarations of the file and of the component by
//! scoped name, each with its C name, and each type's C layout (size, alignment, the
//! offsets of its members) as the C compiler of the target lays it out, for the memory the
//! engine owns for a codel (its ids, its ports' data, its arguments).

use std::collections::HashMap;

use bip_lang::gen3::ast::{Component, Spec, TypeDecl};
use bip_lang::gen3::idl_type::{parse, resolve_scoped, Idl};

use crate::CodegenError;

/// A C basic type of GenoM3's mapping.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Basic {
    Bool,
    /// IDL `char`: an `int8_t`.
    Char,
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    Float,
    Double,
    LongDouble,
}

impl Basic {
    /// The basic type of an IDL word; `None` for those GenoM3 does not map (`any`,
    /// `wchar`).
    fn of(word: &str) -> Option<Basic> {
        Some(match word {
            "boolean" => Basic::Bool,
            "char" => Basic::Char,
            "int8" => Basic::I8,
            "octet" | "uint8" => Basic::U8,
            "short" | "int16" => Basic::I16,
            "unsigned short" | "uint16" => Basic::U16,
            "long" | "int32" => Basic::I32,
            "unsigned long" | "uint32" => Basic::U32,
            "long long" | "int64" => Basic::I64,
            "unsigned long long" | "uint64" => Basic::U64,
            "float" => Basic::Float,
            "double" => Basic::Double,
            "long double" => Basic::LongDouble,
            _ => return None,
        })
    }

    /// Its C spelling.
    pub fn c(self) -> &'static str {
        match self {
            Basic::Bool => "bool",
            Basic::Char | Basic::I8 => "int8_t",
            Basic::U8 => "uint8_t",
            Basic::I16 => "int16_t",
            Basic::U16 => "uint16_t",
            Basic::I32 => "int32_t",
            Basic::U32 => "uint32_t",
            Basic::I64 => "int64_t",
            Basic::U64 => "uint64_t",
            Basic::Float => "float",
            Basic::Double => "double",
            Basic::LongDouble => "long double",
        }
    }

    /// Its IDL kind, which names the anonymous sequences of it (`sequence_unsigned_long`).
    fn kind(self) -> &'static str {
        match self {
            Basic::Bool => "boolean",
            Basic::Char => "char",
            Basic::I8 => "int8",
            Basic::U8 => "octet",
            Basic::I16 => "short",
            Basic::U16 => "unsigned short",
            Basic::I32 => "long",
            Basic::U32 => "unsigned long",
            Basic::I64 => "long long",
            Basic::U64 => "unsigned long long",
            Basic::Float => "float",
            Basic::Double => "double",
            Basic::LongDouble => "long double",
        }
    }

    fn layout(self) -> Layout {
        use std::mem::{align_of, size_of};
        let of = |size: usize, align: usize| Layout {
            size: size as u64,
            align: align as u64,
        };
        match self {
            Basic::Bool | Basic::Char | Basic::I8 | Basic::U8 => of(1, 1),
            Basic::I16 | Basic::U16 => of(2, align_of::<i16>()),
            Basic::I32 | Basic::U32 => of(4, align_of::<i32>()),
            Basic::I64 | Basic::U64 => of(8, align_of::<i64>()),
            Basic::Float => of(4, align_of::<f32>()),
            Basic::Double => of(8, align_of::<f64>()),
            // Rust has no `long double`: the psABI's figure, where it is not a double
            Basic::LongDouble if cfg!(any(target_arch = "x86_64", target_arch = "aarch64")) => {
                of(16, 16)
            }
            Basic::LongDouble => of(size_of::<f64>(), align_of::<f64>()),
        }
    }
}

/// A C type of the mapping.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CType {
    Basic(Basic),
    /// `char *` without a bound, `char[n]` with one.
    String(Option<u64>),
    Array(Box<CType>, u64),
    /// A struct with `_maximum`, `_length`, `_buffer` (a pointer and `_release` without a
    /// bound, an array with one).
    Sequence(Box<CType>, Option<u64>),
    /// A struct with `_present` and `_value`.
    Optional(Box<CType>),
    /// A declared type, by its scoped name among the declarations.
    Named(String),
}

/// What a declaration declares, its types resolved.
#[derive(Clone, Debug)]
pub enum Body {
    Struct(Vec<(String, CType)>),
    Union {
        switch: CType,
        members: Vec<(String, CType)>,
    },
    /// A `uint32_t`, with its enumerators' C names.
    Enum(Vec<String>),
    Typedef(CType),
    /// Opaque: a pointer where it is used.
    Native,
    /// The members of its `_detail` struct; `void` without any.
    Exception(Vec<(String, CType)>),
    /// A numeric constant: its type and its value as C writes it.
    Const {
        ty: CType,
        value: String,
    },
}

/// A declared type: its C name and what it is.
#[derive(Clone, Debug)]
pub struct Decl {
    pub cname: String,
    pub body: Body,
}

/// The size and the alignment of a C type, in bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    pub size: u64,
    pub align: u64,
}

/// Nesting bound for types within each other.
const MAX_DEPTH: usize = 64;

/// A walk through types for their layouts: the declared types being laid out (one met
/// again holds itself) and those laid out already (a type held many times is laid out
/// once).
#[derive(Default)]
struct Walk {
    path: Vec<String>,
    done: HashMap<String, Layout>,
}

/// The declarations a component sees: the file's and its own, in declaration order.
pub struct CTypes {
    pub order: Vec<String>,
    pub decls: HashMap<String, Decl>,
}

/// `a::b::c` as C names it: `a_b_c`.
pub fn cname(scoped: &str) -> String {
    scoped
        .trim_start_matches("::")
        .replace("::", "_")
        .replace(' ', "_")
}

impl CTypes {
    /// The declarations of `spec`'s top level and of `component`: a component's own
    /// declarations are in its scope (`loco::ids::state`), as GenoM3 names them.
    pub fn new(spec: &Spec, component: &Component) -> Result<CTypes, CodegenError> {
        let own = |d: &TypeDecl| format!("{}::{}", component.name.value, d.name.value);
        let all: Vec<(String, &TypeDecl)> = spec
            .types
            .iter()
            .map(|d| (d.name.value.clone(), d))
            .chain(
                component
                    .types
                    .iter()
                    .chain(&component.exceptions)
                    .map(|d| (own(d), d)),
            )
            // a constant GenoM3 maps is numeric: a string's has no value here
            .filter(|(_, d)| d.kind != "const" || d.value.is_some())
            .collect();
        let mut types = CTypes {
            order: Vec::new(),
            decls: HashMap::new(),
        };
        // first the names, for a member to name a type declared after it
        for (key, _) in &all {
            types.decls.insert(
                key.clone(),
                Decl {
                    cname: cname(key),
                    body: Body::Native,
                },
            );
        }
        for (key, d) in &all {
            let members = |types: &CTypes| -> Result<Vec<(String, CType)>, CodegenError> {
                d.members
                    .iter()
                    .map(|m| Ok((m.name.value.clone(), types.ctype(&m.ty, key)?)))
                    .collect()
            };
            let body = (|| -> Result<Body, CodegenError> {
                Ok(match d.kind {
                    "struct" => Body::Struct(members(&types)?),
                    "exception" => Body::Exception(members(&types)?),
                    "union" => Body::Union {
                        switch: types.ctype(d.switch.as_deref().unwrap_or("long"), key)?,
                        members: members(&types)?,
                    },
                    "enum" => {
                        let scope = key.rsplit_once("::").map_or("", |(s, _)| s);
                        Body::Enum(
                            d.members
                                .iter()
                                .map(|m| cname(&format!("{scope}::{}", m.name.value)))
                                .collect(),
                        )
                    }
                    "const" => {
                        let ty = d.members.first().map_or("", |m| m.ty.as_str());
                        let scope = key.rsplit_once("::").map_or("", |(s, _)| s);
                        Body::Const {
                            ty: types.ctype(ty, scope)?,
                            value: d.value.clone().unwrap_or_default(),
                        }
                    }
                    "typedef" => {
                        let target = d.members.first().map_or("", |m| m.ty.as_str());
                        let scope = key.rsplit_once("::").map_or("", |(s, _)| s);
                        Body::Typedef(types.ctype(target, scope)?)
                    }
                    _ => Body::Native,
                })
            })()
            .map_err(|e| match e {
                CodegenError::CMapping(m) => CodegenError::CMapping(format!("`{key}`: {m}")),
                other => other,
            })?;
            if let Some(decl) = types.decls.get_mut(key) {
                decl.body = body;
            }
            types.order.push(key.clone());
        }
        Ok(types)
    }

    /// Declares a struct that the component implies (its ids), under `key`.
    pub fn add_struct(&mut self, key: &str, members: Vec<(String, CType)>) {
        self.decls.insert(
            key.to_string(),
            Decl {
                cname: cname(key),
                body: Body::Struct(members),
            },
        );
        self.order.push(key.to_string());
    }

    /// The declaration `name` refers to from within `scope`: IDL looks in the scope, then
    /// in each enclosing one; `::a::b` is from the top.
    fn resolve(&self, name: &str, scope: &str) -> Option<String> {
        resolve_scoped(name, scope, |full| {
            self.decls.contains_key(full).then_some(())
        })
        .map(|(full, ())| full)
    }

    /// The C type of the IDL type `text` written in `scope`.
    pub fn ctype(&self, text: &str, scope: &str) -> Result<CType, CodegenError> {
        self.of(&parse(text), scope)
            .ok_or_else(|| CodegenError::CMapping(format!("IDL type `{text}`: {}", why(text))))
    }

    fn of(&self, idl: &Idl, scope: &str) -> Option<CType> {
        Some(match idl {
            Idl::Basic(w) => CType::Basic(Basic::of(w)?),
            Idl::Text(bound) => CType::String(*bound),
            Idl::Sequence(e, bound) => CType::Sequence(Box::new(self.of(e, scope)?), *bound),
            Idl::Optional(e) => CType::Optional(Box::new(self.of(e, scope)?)),
            Idl::Array(e, dims) => {
                let mut t = self.of(e, scope)?;
                for d in dims.iter().rev() {
                    t = CType::Array(Box::new(t), d.parse().ok()?);
                }
                t
            }
            Idl::Named(name) => CType::Named(self.resolve(name, scope)?),
        })
    }

    pub fn decl(&self, key: &str) -> Option<&Decl> {
        self.decls.get(key)
    }

    /// `t` with its typedefs followed to what they name.
    pub fn fin<'a>(&'a self, t: &'a CType) -> &'a CType {
        let mut t = t;
        for _ in 0..MAX_DEPTH {
            match t {
                CType::Named(k) => match self.decls.get(k).map(|d| &d.body) {
                    Some(Body::Typedef(target)) => t = target,
                    _ => return t,
                },
                _ => return t,
            }
        }
        t
    }

    /// The size and alignment of `t` as C lays it out.
    pub fn layout(&self, t: &CType) -> Result<Layout, CodegenError> {
        self.layout_at(t, &mut Walk::default())
    }

    fn layout_at(&self, t: &CType, walk: &mut Walk) -> Result<Layout, CodegenError> {
        if walk.path.len() > MAX_DEPTH {
            return Err(CodegenError::CMapping(format!(
                "type `{}` is nested too deeply",
                self.name(t)
            )));
        }
        let CType::Named(k) = t else {
            return self.layout_of(t, walk);
        };
        if let Some(l) = walk.done.get(k) {
            return Ok(*l);
        }
        if walk.path.contains(k) {
            return Err(CodegenError::CMapping(format!(
                "type `{}` holds itself (other than through an unbounded sequence)",
                self.name(t)
            )));
        }
        walk.path.push(k.clone());
        let l = self.layout_of(t, walk);
        walk.path.pop();
        let l = l?;
        walk.done.insert(k.clone(), l);
        Ok(l)
    }

    fn layout_of(&self, t: &CType, d: &mut Walk) -> Result<Layout, CodegenError> {
        Ok(match t {
            CType::Basic(b) => b.layout(),
            CType::String(None) => pointer(),
            CType::String(Some(n)) => Layout { size: *n, align: 1 },
            CType::Array(e, n) => {
                let e = self.layout_at(e, d)?;
                Layout {
                    size: e.size * n,
                    align: e.align,
                }
            }
            CType::Sequence(..) | CType::Optional(_) => {
                struct_layout(&self.member_layouts(t, d)?).0
            }
            CType::Named(k) => match self.decls.get(k).map(|x| &x.body) {
                Some(Body::Enum(_)) => Basic::U32.layout(),
                Some(Body::Typedef(target)) => self.layout_at(target, d)?,
                Some(Body::Native) | Some(Body::Const { .. }) | None => pointer(),
                Some(Body::Union { .. }) | Some(Body::Struct(_)) | Some(Body::Exception(_)) => {
                    struct_layout(&self.member_layouts(t, d)?).0
                }
            },
        })
    }

    /// The members of a type C lays out as a struct, with their layouts, in order.
    fn member_layouts(
        &self,
        t: &CType,
        d: &mut Walk,
    ) -> Result<Vec<(String, Layout)>, CodegenError> {
        let u32l = Basic::U32.layout();
        let mut out = Vec::new();
        match self.fin(t) {
            CType::Sequence(e, None) => {
                out.push(("_maximum".into(), u32l));
                out.push(("_length".into(), u32l));
                out.push(("_buffer".into(), pointer()));
                out.push(("_release".into(), pointer()));
                let _ = e;
            }
            CType::Sequence(e, Some(n)) => {
                out.push(("_maximum".into(), u32l));
                out.push(("_length".into(), u32l));
                let e = self.layout_at(e, d)?;
                out.push((
                    "_buffer".into(),
                    Layout {
                        size: e.size * n,
                        align: e.align,
                    },
                ));
            }
            CType::Optional(v) => {
                out.push(("_present".into(), Basic::Bool.layout()));
                out.push(("_value".into(), self.layout_at(v, d)?));
            }
            CType::Named(k) => match self.decls.get(k).map(|x| &x.body) {
                Some(Body::Struct(ms)) | Some(Body::Exception(ms)) => {
                    for (name, mt) in ms {
                        out.push((name.clone(), self.layout_at(mt, d)?));
                    }
                }
                Some(Body::Union { switch, members }) => {
                    out.push(("_d".into(), self.layout_at(switch, d)?));
                    let mut u = Layout { size: 0, align: 1 };
                    for (_, mt) in members {
                        let l = self.layout_at(mt, d)?;
                        u.size = u.size.max(l.size);
                        u.align = u.align.max(l.align);
                    }
                    u.size = round_up(u.size, u.align);
                    out.push(("_u".into(), u));
                }
                _ => {}
            },
            _ => {}
        }
        Ok(out)
    }

    /// The members of `t` (a struct, union, exception detail, sequence or optional, or a
    /// typedef of one) with their offsets, in order; empty for other types.
    pub fn offsets(&self, t: &CType) -> Result<Vec<(String, u64)>, CodegenError> {
        let ms = self.member_layouts(t, &mut Walk::default())?;
        let (_, offsets) = struct_layout(&ms);
        Ok(ms.into_iter().map(|(n, _)| n).zip(offsets).collect())
    }

    /// The name C gives `t` where it is declared: a typedef's, a struct's, `sequence_double`
    /// for an anonymous sequence; an array's element's (see [`CTypes::declare`]).
    pub fn name(&self, t: &CType) -> String {
        self.split(t).0
    }

    /// `t`'s C declarator before and after the declared name: `("double", "[3]")`.
    fn split(&self, t: &CType) -> (String, String) {
        match t {
            CType::Basic(b) => (b.c().into(), String::new()),
            CType::String(None) => ("char *".into(), String::new()),
            CType::String(Some(n)) => ("char".into(), format!("[{n}]")),
            CType::Array(e, n) => {
                let (pre, post) = self.split(e);
                (pre, format!("[{n}]{post}"))
            }
            CType::Sequence(..) | CType::Optional(_) => (self.template_name(t), String::new()),
            CType::Named(k) => match self.decls.get(k) {
                Some(Decl {
                    cname,
                    body: Body::Native,
                }) => (format!("{cname} *"), String::new()),
                Some(Decl {
                    cname,
                    body: Body::Exception(_),
                }) => (format!("{cname}_detail"), String::new()),
                Some(d) => (d.cname.clone(), String::new()),
                None => (cname(k), String::new()),
            },
        }
    }

    /// `var` declared of type `t`: `double v[3]`, `char *s`, `rover_pose (*p)[2]`.
    pub fn declare(&self, t: &CType, var: &str) -> String {
        let (pre, post) = self.split(t);
        let var = if !post.is_empty() && var.starts_with('*') {
            format!("({var})")
        } else {
            var.to_string()
        };
        if pre.ends_with('*') || var.is_empty() && post.is_empty() {
            format!("{pre}{var}{post}")
        } else {
            format!("{pre} {var}{post}")
        }
    }

    /// The name GenoM3 gives an anonymous sequence or optional: its kind, its bound, then
    /// the names of what it holds (`sequence16_rover_pose`, `optional_sequence_double`).
    pub(crate) fn template_name(&self, t: &CType) -> String {
        let mut out = String::new();
        let mut t = t;
        let mut first = true;
        loop {
            let (word, bound, inner) = match t {
                CType::Sequence(e, b) => ("sequence".to_string(), *b, Some(&**e)),
                CType::Optional(e) => ("optional".to_string(), None, Some(&**e)),
                CType::String(b) => ("string".to_string(), *b, None),
                CType::Array(_, n) => ("array".to_string(), Some(*n), None),
                CType::Basic(b) => (b.kind().to_string(), None, None),
                CType::Named(k) => (k.clone(), None, None),
            };
            if !first {
                out.push('_');
            }
            out.push_str(&cname(&word));
            if let Some(b) = bound {
                out.push_str(&b.to_string());
            }
            first = false;
            match inner {
                Some(e) => t = e,
                None => return out,
            }
        }
    }
}

/// Why an IDL type has no C type here.
fn why(text: &str) -> &'static str {
    match parse(text) {
        Idl::Basic("any") => "GenoM3's C mapping does not implement `any`",
        Idl::Basic("wchar") => "GenoM3's C mapping has no `wchar`",
        _ if text.trim_start().starts_with("wstring") => "GenoM3's C mapping has no `wstring`",
        _ => "not a type declared in the file or the component",
    }
}

fn pointer() -> Layout {
    Layout {
        size: std::mem::size_of::<*const u8>() as u64,
        align: std::mem::align_of::<*const u8>() as u64,
    }
}

fn round_up(v: u64, align: u64) -> u64 {
    v.div_ceil(align.max(1)) * align.max(1)
}

/// A struct of `members` as C lays it out: each at the next offset its alignment allows,
/// the whole rounded up to the largest alignment.
fn struct_layout(members: &[(String, Layout)]) -> (Layout, Vec<u64>) {
    let mut size = 0;
    let mut align = 1;
    let mut offsets = Vec::with_capacity(members.len());
    for (_, l) in members {
        size = round_up(size, l.align);
        offsets.push(size);
        size += l.size;
        align = align.max(l.align);
    }
    (
        Layout {
            size: round_up(size, align),
            align,
        },
        offsets,
    )
}

/// Whether data of type `t` holds a pointer of a kind `leaf` picks, within it.
fn holds(types: &CTypes, t: &CType, leaf: &impl Fn(&CType) -> bool) -> bool {
    let t = types.fin(t);
    if leaf(t) {
        return true;
    }
    match t {
        CType::Basic(_) | CType::String(_) => false,
        CType::Array(e, _) | CType::Sequence(e, _) | CType::Optional(e) => holds(types, e, leaf),
        CType::Named(k) => match types.decl(k).map(|d| &d.body) {
            Some(Body::Struct(ms)) | Some(Body::Exception(ms)) => {
                ms.iter().any(|(_, t)| holds(types, t, leaf))
            }
            Some(Body::Union { switch, members }) => {
                holds(types, switch, leaf) || members.iter().any(|(_, t)| holds(types, t, leaf))
            }
            _ => false,
        },
    }
}

/// Whether data of type `t` owns a buffer: an unbounded string or sequence within it,
/// which its mirror's clone copies and its drop frees (bip-genom-c's `GenomString` and
/// `Sequence`).
pub fn owns_buffer(types: &CTypes, t: &CType) -> bool {
    holds(types, t, &|t| {
        matches!(t, CType::String(None) | CType::Sequence(_, None))
    })
}

/// Whether data of type `t` holds a native, a pointer to the codels' own object, which
/// the engine can neither copy nor free: such data cannot be handed to the engine, which
/// keeps it past the call.
pub fn holds_native(types: &CTypes, t: &CType) -> bool {
    holds(types, t, &|t| match t {
        CType::Named(k) => matches!(types.decl(k).map(|d| &d.body), Some(Body::Native)),
        _ => false,
    })
}
