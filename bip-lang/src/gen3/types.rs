//! The IDL types of ports and service parameters as the model's data types (docs/genom.md,
//! "GenoM3 files", "IDL types"): `boolean` is `Bool`, an integer type `Int` of its exact
//! range, `float` and `double` `Float`, a structure a `Record` when each of its fields is a
//! model type, an enumeration `Int(0, n-1)`, a typedef what it names; anything else a
//! `Rust` path that names the IDL type (`rover::path`) or, for an anonymous one, spells it
//! in Rust (`Vec<f64>`, `String`).

use std::collections::HashMap;

use super::ast::{Component, Dir, Kind, Service, Spec, TypeDecl};
use super::idl_type::{parse, resolve_scoped, Idl};
use crate::compile::check_name;
use crate::diag::Errors;
use crate::genom::syntax::{DataTypeDef, FieldDef};
use crate::source::{ConstExpr, ConstValue, Span, Text};

/// Nesting bound for typedefs and structures within each other (a cycle ends here).
const MAX_DEPTH: usize = 64;
/// Bound on the parts of one record, its fields within fields counted: structures that
/// hold others several times grow exponentially with their nesting.
const MAX_PARTS: usize = 10_000;

/// The IDL declarations of a file, by scoped name, to resolve the names types use.
pub(super) struct Types<'s> {
    decls: HashMap<&'s str, &'s TypeDecl>,
}

impl<'s> Types<'s> {
    pub fn new(spec: &'s Spec) -> Types<'s> {
        let decls = spec
            .types
            .iter()
            .chain(spec.components.iter().flat_map(|c| c.types.iter()))
            .filter(|d| matches!(d.kind, "struct" | "union" | "enum" | "typedef" | "native"))
            .map(|d| (d.name.value.as_str(), d))
            .collect();
        Types { decls }
    }

    /// The declaration `name` refers to from within `scope` (`a::b`): IDL looks in the
    /// scope, then in each enclosing one; `::a::b` is from the top.
    fn resolve(&self, name: &str, scope: &str) -> Option<&'s TypeDecl> {
        resolve_scoped(name, scope, |full| self.decls.get(full).copied()).map(|(_, d)| d)
    }

    /// The data type of the IDL type `text` written in `scope`, or `None` for an anonymous
    /// array, which has no name and no Rust path (its place names a type instead).
    pub fn data_type(&self, text: &str, scope: &str, at: Span) -> Option<DataTypeDef> {
        let idl = parse(text);
        let mut parts = MAX_PARTS;
        if let Some(t) = self.model(&idl, scope, at, 0, &mut parts) {
            return Some(t);
        }
        let path = self.rust(&idl, scope);
        (!path.starts_with('[')).then(|| DataTypeDef::Rust(Text::new(path, at)))
    }

    /// The model type of `idl` (`Bool`, `Int`, `Float` or a record of them), if it has one.
    fn model(
        &self,
        idl: &Idl,
        scope: &str,
        at: Span,
        depth: usize,
        parts: &mut usize,
    ) -> Option<DataTypeDef> {
        if depth > MAX_DEPTH || *parts == 0 {
            return None;
        }
        *parts -= 1;
        let int = |lo: i64, hi: i64| {
            Some(DataTypeDef::Int(
                ConstExpr::new(ConstValue::Int(lo), at),
                ConstExpr::new(ConstValue::Int(hi), at),
            ))
        };
        match idl {
            Idl::Basic(word) => match *word {
                "boolean" => Some(DataTypeDef::Bool),
                "float" | "double" | "long double" => Some(DataTypeDef::Float),
                "short" | "int16" => int(i16::MIN.into(), i16::MAX.into()),
                "long" | "int32" => int(i32::MIN.into(), i32::MAX.into()),
                "long long" | "int64" => int(i64::MIN, i64::MAX),
                "unsigned short" | "uint16" => int(0, u16::MAX.into()),
                "unsigned long" | "uint32" => int(0, u32::MAX.into()),
                "int8" => int(i8::MIN.into(), i8::MAX.into()),
                // IDL's char holds an ISO 8859-1 character: its code
                "octet" | "uint8" | "char" => int(0, u8::MAX.into()),
                // unsigned 64-bit integers exceed an Int's i64; wchar and any have no
                // model type
                _ => None,
            },
            Idl::Named(name) => {
                let decl = self.resolve(name, scope)?;
                let (inner_scope, own) = split(&decl.name.value);
                match decl.kind {
                    "typedef" => {
                        let target = decl.members.first()?;
                        self.model(&parse(&target.ty), inner_scope, at, depth + 1, parts)
                    }
                    "enum" => {
                        let n = i64::try_from(decl.members.len()).ok()?;
                        (n > 0).then(|| int(0, n - 1))?
                    }
                    "struct" => {
                        let name = Text::new(own.to_string(), at);
                        let mut quiet = Errors::default();
                        if !check_name(&mut quiet, &name, "record") {
                            return None;
                        }
                        let mut fields = Vec::new();
                        for m in &decl.members {
                            let field = Text::new(m.name.value.clone(), at);
                            if !check_name(&mut quiet, &field, "field") {
                                return None;
                            }
                            let ty =
                                self.model(&parse(&m.ty), &decl.name.value, at, depth + 1, parts)?;
                            fields.push(FieldDef { name: field, ty });
                        }
                        Some(DataTypeDef::Record { name, fields })
                    }
                    _ => None,
                }
            }
            Idl::Text(_) | Idl::Sequence(..) | Idl::Optional(_) | Idl::Array(..) => None,
        }
    }

    /// The Rust spelling of `idl`: a declared type's scoped name (`rover::pose`), or the
    /// Rust type an anonymous one would be (`Vec<f64>`, `[u8; 4]`, `String`).
    fn rust(&self, idl: &Idl, scope: &str) -> String {
        match idl {
            Idl::Basic(word) => match *word {
                "boolean" => "bool",
                "short" | "int16" => "i16",
                "long" | "int32" => "i32",
                "long long" | "int64" => "i64",
                "unsigned short" | "uint16" => "u16",
                "unsigned long" | "uint32" => "u32",
                "unsigned long long" | "uint64" => "u64",
                "int8" => "i8",
                "octet" | "uint8" | "char" => "u8",
                "wchar" => "char",
                "float" => "f32",
                "double" | "long double" => "f64",
                other => other,
            }
            .to_string(),
            Idl::Text(_) => "String".to_string(),
            Idl::Sequence(e, _) => format!("Vec<{}>", self.rust(e, scope)),
            Idl::Optional(e) => format!("Option<{}>", self.rust(e, scope)),
            Idl::Array(e, dims) => dims
                .iter()
                .rev()
                .fold(self.rust(e, scope), |inner, n| format!("[{inner}; {n}]")),
            Idl::Named(name) => match self.resolve(name, scope) {
                Some(d) => d.name.value.clone(),
                None => name.trim_start_matches("::").to_string(),
            },
        }
    }

    /// The type of an activity's arguments (its `in` and `inout` parameters) or of its
    /// output (`out` and `inout`): one parameter's type, or a record of several named
    /// `<Service>_input` / `<Service>_output`; when that record cannot be a model type (a
    /// field without one, an anonymous array), the Rust path `<component>::<Service>_input`.
    /// Functions and attributes have none: the model gives them no codel to read them.
    pub fn payload(&self, c: &Component, s: &Service, output: bool) -> Option<DataTypeDef> {
        // a function's codel reads its arguments and gives its output; a validation reads
        // the arguments
        let read =
            s.kind == Kind::Activity || !s.simple.is_empty() || (!output && s.validate.is_some());
        if !read {
            return None;
        }
        let wanted = |d: Dir| if output { d != Dir::In } else { d != Dir::Out };
        let mut parts = MAX_PARTS;
        let params: Vec<(&Text, &str)> = s
            .params
            .iter()
            .filter(|p| wanted(p.dir))
            .filter_map(|p| Some((&p.name, p.ty.as_deref()?)))
            .collect();
        let suffix = if output { "output" } else { "input" };
        let at = s.name.span;
        let named = || {
            DataTypeDef::Rust(Text::new(
                format!("{}::{}_{suffix}", c.name.value, s.name.value),
                at,
            ))
        };
        match params.as_slice() {
            [] => None,
            [(name, ty)] => Some(self.data_type(ty, "", name.span).unwrap_or_else(named)),
            several => {
                let mut fields = Vec::new();
                for (name, ty) in several {
                    if !check_name(&mut Errors::default(), name, "field") {
                        return Some(named());
                    }
                    match self.model(&parse(ty), "", name.span, 0, &mut parts) {
                        Some(ty) => fields.push(FieldDef {
                            name: (*name).clone(),
                            ty,
                        }),
                        None => return Some(named()),
                    }
                }
                Some(DataTypeDef::Record {
                    name: Text::new(format!("{}_{suffix}", s.name.value), at),
                    fields,
                })
            }
        }
    }
}

/// `a::b::c` as its scope `a::b` and its own name `c`.
fn split(scoped: &str) -> (&str, &str) {
    scoped.rsplit_once("::").unwrap_or(("", scoped))
}
