//! OMG IDL as GenoM3 uses it: type specifications (kept as their text), members and
//! declarators, and the declarations `module`, `const`, `typedef`, `struct`, `union`,
//! `enum`, `native` and `exception`. Constants and enumerators are remembered with their
//! values: periods and sizes may name them.

use std::collections::HashMap;

use super::ast::{Member, TypeDecl};
use super::consts::{self, Value};
use super::cursor::Cursor;
use super::lexer::Tok;
use crate::diag::ModelError;
use crate::source::{Span, Text};

/// IDL's basic types of several words, as the parser joins them.
pub(super) const MANY_WORD_BASIC: &[&str] = &[
    "short",
    "long",
    "long long",
    "unsigned short",
    "unsigned long",
    "unsigned long long",
    "long double",
];

/// IDL's basic types of one word.
pub(super) const ONE_WORD_BASIC: &[&str] = &[
    "boolean", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "octet",
    "char", "wchar", "float", "double", "any",
];

/// The IDL declarations read so far: constants by name (plain and scoped), and the scope
/// being read.
#[derive(Default)]
pub struct Idl {
    consts: HashMap<String, Value>,
    scope: Vec<String>,
    pub decls: Vec<TypeDecl>,
    /// The component being read, for `c::ids::s` within component `c` to name `ids::s`.
    pub component: Option<String>,
}

/// The scope of the types an `ids` declares inline (GenoM3's `c::ids::s`).
const IDS_SCOPE: &str = "ids";

/// Words that start an IDL declaration.
pub const DECLARATION_WORDS: &[&str] = &[
    "module",
    "const",
    "typedef",
    "struct",
    "union",
    "enum",
    "native",
    "exception",
];

/// Nesting bound for types within types.
const MAX_DEPTH: usize = 64;

impl Idl {
    /// The value of a constant named in an expression.
    pub fn lookup(&self, name: &str) -> Option<Value> {
        let plain = name.trim_start_matches("::");
        if let Some(v) = self.consts.get(plain) {
            return Some(*v);
        }
        plain
            .rsplit("::")
            .next()
            .and_then(|last| self.consts.get(last))
            .copied()
    }

    /// A constant expression.
    pub fn expression(&self, c: &mut Cursor) -> Result<(Value, Span), ModelError> {
        consts::expression(c, &|n| self.lookup(n), false)
    }

    /// A positive integer constant (a bound, a size, a priority).
    pub fn positive_int(&self, c: &mut Cursor) -> Result<(i128, Span), ModelError> {
        let (v, span) = self.expression(c)?;
        match v {
            Value::Int(i) if i >= 0 => Ok((i, span)),
            _ => Err(ModelError::new(
                "expected a positive integer constant",
                span,
            )),
        }
    }

    fn scoped(&self, name: &str) -> String {
        let mut s = self.scope.join("::");
        if !s.is_empty() {
            s.push_str("::");
        }
        s.push_str(name);
        s
    }

    fn define_const(&mut self, name: &str, v: Value) {
        let full = self.scoped(name);
        self.consts.insert(name.to_string(), v);
        self.consts.insert(full, v);
    }

    fn declare(&mut self, name: &Text, kind: &'static str, members: Vec<Member>) {
        let full = Text::new(self.scoped(&name.value), name.span);
        self.decls.push(TypeDecl {
            name: full,
            kind,
            members,
            switch: None,
            value: None,
        });
    }

    /// An IDL declaration, from its first word; `;` included.
    pub fn declaration(&mut self, c: &mut Cursor) -> Result<(), ModelError> {
        if self.scope.len() > MAX_DEPTH {
            return Err(ModelError::new("modules nested too deeply", c.here()));
        }
        let Some(word) = c.peek().and_then(|t| t.ident().map(str::to_string)) else {
            return Err(c.expected("an IDL declaration"));
        };
        match word.as_str() {
            "module" => {
                c.next();
                let name = c.expect_name("a module name")?;
                c.expect_punct("{")?;
                self.scope.push(name.value.clone());
                while !c.at_punct("}") {
                    if c.at_end() {
                        return Err(c.expected("`}` closing the module"));
                    }
                    self.declaration(c)?;
                }
                self.scope.pop();
                c.expect_punct("}")?;
            }
            "const" => {
                c.next();
                let ty = self.type_spec(c, 0)?;
                let name = c.expect_name("the constant's name")?;
                c.expect_punct("=")?;
                let value = if matches!(c.peek().map(|t| &t.tok), Some(Tok::Str(_))) {
                    c.expect_strings()?;
                    None
                } else if matches!(c.peek().map(|t| &t.tok), Some(Tok::Char(_))) {
                    c.next();
                    None
                } else {
                    Some(self.expression(c)?.0)
                };
                if let Some(v) = value {
                    self.define_const(&name.value, v);
                }
                self.declare(
                    &name,
                    "const",
                    vec![Member {
                        name: name.clone(),
                        ty,
                    }],
                );
                if let Some(d) = self.decls.last_mut() {
                    d.value = value.and_then(|v| match v {
                        Value::Int(i) => Some(i.to_string()),
                        Value::Float(f) if f.is_finite() => Some(format!("{f:?}")),
                        Value::Float(_) => None,
                    });
                }
            }
            "typedef" => {
                c.next();
                let ty = self.type_spec(c, 0)?;
                for (name, dims) in c.list(|c| self.declarator(c))? {
                    let full = format!("{ty}{dims}");
                    self.declare(
                        &name,
                        "typedef",
                        vec![Member {
                            name: name.clone(),
                            ty: full,
                        }],
                    );
                }
            }
            "native" => {
                c.next();
                let name = c.expect_name("the native type's name")?;
                self.declare(&name, "native", Vec::new());
            }
            "exception" => {
                c.next();
                c.list(|c| {
                    let name = c.expect_name("an exception name")?;
                    let members = if c.at_punct("{") {
                        self.members(c, 0)?
                    } else {
                        Vec::new()
                    };
                    self.declare(&name, "exception", members);
                    Ok(())
                })?;
            }
            "struct" | "union" | "enum" => {
                self.type_spec(c, 0)?;
            }
            _ => return Err(c.expected("an IDL declaration")),
        }
        c.expect_punct(";")?;
        Ok(())
    }

    /// `{ T a, b[3]; U c; }` (the braces included).
    pub fn members(&mut self, c: &mut Cursor, depth: usize) -> Result<Vec<Member>, ModelError> {
        c.expect_punct("{")?;
        let mut out = Vec::new();
        while !c.at_punct("}") {
            if c.at_end() {
                return Err(c.expected("`}`"));
            }
            out.extend(self.member(c, depth)?);
        }
        c.expect_punct("}")?;
        Ok(out)
    }

    /// The members of a component's `ids`, whose inline types are declared in its `ids`
    /// scope (`ids { struct s { … } a; }` declares `ids::s`).
    pub fn ids_members(&mut self, c: &mut Cursor) -> Result<Vec<Member>, ModelError> {
        self.scope.push(IDS_SCOPE.to_string());
        let members = self.members(c, 0);
        self.scope.pop();
        members
    }

    /// A scoped type name; `c::ids::s` within component `c` is `ids::s`.
    fn type_name(&self, c: &mut Cursor) -> Result<String, ModelError> {
        let name = c.scoped_name("a type")?.value;
        let own = self.component.as_ref().and_then(|comp| {
            let plain = name.strip_prefix("::").unwrap_or(&name);
            let rest = plain.strip_prefix(comp.as_str())?.strip_prefix("::")?;
            rest.starts_with("ids::").then(|| rest.to_string())
        });
        Ok(own.unwrap_or(name))
    }

    /// `T a, b[3];`
    pub fn member(&mut self, c: &mut Cursor, depth: usize) -> Result<Vec<Member>, ModelError> {
        let ty = self.type_spec(c, depth)?;
        let names = c.list(|c| self.declarator(c))?;
        c.expect_punct(";")?;
        Ok(names
            .into_iter()
            .map(|(name, dims)| Member {
                name,
                ty: format!("{ty}{dims}"),
            })
            .collect())
    }

    /// `a` or `a[3][N]`: the name and its array dimensions as written.
    pub fn declarator(&self, c: &mut Cursor) -> Result<(Text, String), ModelError> {
        let name = c.expect_name("a name")?;
        let mut dims = String::new();
        while c.eat_punct("[").is_some() {
            let (n, _) = self.positive_int(c)?;
            c.expect_punct("]")?;
            dims.push_str(&format!("[{n}]"));
        }
        Ok((name, dims))
    }

    /// A type specification; an inline `struct`, `union` or `enum` is declared on the way.
    pub fn type_spec(&mut self, c: &mut Cursor, depth: usize) -> Result<String, ModelError> {
        if depth > MAX_DEPTH {
            return Err(ModelError::new("types nested too deeply", c.here()));
        }
        let Some(t) = c.peek().cloned() else {
            return Err(c.expected("a type"));
        };
        let Some(word) = t.ident().map(str::to_string) else {
            if t.is_punct("::") {
                return self.type_name(c);
            }
            return Err(c.expected("a type"));
        };
        let simple = |c: &mut Cursor, words: &[&str]| {
            let mut out = Vec::new();
            while let Some(w) = words.iter().find(|w| c.at_ident(w)) {
                c.next();
                out.push(*w);
            }
            out.join(" ")
        };
        Ok(match word.as_str() {
            "unsigned" | "short" | "long" => {
                let s = simple(c, &["unsigned", "short", "long", "int", "double"]);
                if !MANY_WORD_BASIC.contains(&s.as_str()) {
                    return Err(ModelError::new(
                        format!("`{s}` is not an IDL type"),
                        Span::new(t.span.start, c.last_span().end),
                    ));
                }
                s
            }
            w if ONE_WORD_BASIC.contains(&w) => {
                c.next();
                word
            }
            "string" | "wstring" => {
                c.next();
                if c.eat_punct("<").is_some() {
                    let (n, _) = self.positive_int(c)?;
                    c.expect_close_angle()?;
                    format!("{word}<{n}>")
                } else {
                    word
                }
            }
            "sequence" | "optional" => {
                c.next();
                c.expect_punct("<")?;
                let inner = self.type_spec(c, depth + 1)?;
                let bound = if word == "sequence" && c.eat_punct(",").is_some() {
                    Some(self.positive_int(c)?.0)
                } else {
                    None
                };
                c.expect_close_angle()?;
                match bound {
                    Some(n) => format!("{word}<{inner}, {n}>"),
                    None => format!("{word}<{inner}>"),
                }
            }
            "fixed" => {
                return Err(
                    ModelError::new("IDL `fixed` types are not supported", t.span)
                        .with_help("GenoM3 does not implement them either"),
                )
            }
            "struct" | "union" | "enum" => {
                c.next();
                let name = c.expect_name(&format!("the {word}'s name"))?;
                if word == "struct" && c.at_punct("{") {
                    self.scope.push(name.value.clone());
                    let members = self.members(c, depth + 1);
                    self.scope.pop();
                    let members = members?;
                    self.declare(&name, "struct", members);
                } else if word == "enum" && c.at_punct("{") {
                    self.enumerators(c, &name)?;
                } else if word == "union" && c.at_ident("switch") {
                    self.union_body(c, &name, depth)?;
                }
                format!("{word} {}", name.value)
            }
            // IDL keywords; GenoM's own (`task`, `port`, `ids`...) may name types
            "void" | "object" => return Err(c.expected("a type")),
            _ => self.type_name(c)?,
        })
    }

    fn enumerators(&mut self, c: &mut Cursor, name: &Text) -> Result<(), ModelError> {
        c.expect_punct("{")?;
        let names = c.list(|c| c.expect_name("an enumerator"))?;
        c.expect_punct("}")?;
        for (i, n) in names.iter().enumerate() {
            self.define_const(&n.value, Value::Int(i as i128));
        }
        let members = names
            .into_iter()
            .map(|n| Member {
                name: n,
                ty: name.value.clone(),
            })
            .collect();
        self.declare(name, "enum", members);
        Ok(())
    }

    /// `switch (T) { case 1: T a; default: U b; }`
    fn union_body(&mut self, c: &mut Cursor, name: &Text, depth: usize) -> Result<(), ModelError> {
        c.next();
        c.expect_punct("(")?;
        let switch = self.type_spec(c, depth + 1)?;
        c.expect_punct(")")?;
        c.expect_punct("{")?;
        let mut members = Vec::new();
        while !c.at_punct("}") {
            let mut labels = 0;
            loop {
                if c.eat_ident("case").is_some() {
                    self.expression(c)?;
                } else if c.eat_ident("default").is_none() {
                    break;
                }
                c.expect_punct(":")?;
                labels += 1;
            }
            if labels == 0 {
                return Err(c.expected("`case` or `default`"));
            }
            members.extend(self.member(c, depth + 1)?);
        }
        c.expect_punct("}")?;
        self.declare(name, "union", members);
        if let Some(d) = self.decls.last_mut() {
            d.switch = Some(switch);
        }
        Ok(())
    }
}
