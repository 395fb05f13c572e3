//! The C text of a component's declared types, in declaration order, as GenoM3's C
//! mapping writes them: a struct or union as a typedef of its C name first (for a member
//! to hold a sequence of it), an enum as a `uint32_t` and its enumerators' constants, an
//! anonymous sequence or optional as a struct of its own name, an exception as its id,
//! its `_detail` type and the function that throws it. Each is guarded, so that the
//! headers of several components declare a type they share once.

use std::collections::HashSet;
use std::fmt::Write as _;

use super::ctype::{Body, CType, CTypes};

/// What has been written, so that each anonymous type is written before its first user.
#[derive(Default)]
pub struct Written {
    names: HashSet<String>,
}

/// `text` within a guard of `name`.
fn guarded(out: &mut String, name: &str, text: &str) {
    let _ = write!(
        out,
        "#ifndef BIP_C_TYPE_{name}\n#define BIP_C_TYPE_{name}\n{text}#endif\n\n"
    );
}

/// The anonymous sequences and optionals `t` uses, each once, inner ones first.
pub fn templates(out: &mut String, types: &CTypes, t: &CType, written: &mut Written) {
    let inner = match t {
        CType::Sequence(e, _) | CType::Optional(e) | CType::Array(e, _) => e,
        _ => return,
    };
    templates(out, types, inner, written);
    if matches!(t, CType::Array(..)) {
        return;
    }
    let name = types.name(t);
    if !written.names.insert(name.clone()) {
        return;
    }
    let body = match t {
        CType::Sequence(e, None) => format!(
            "  uint32_t _maximum, _length;\n  {};\n  void (*_release)(void *_buffer);\n",
            types.declare(e, "*_buffer")
        ),
        // C++ codels need the constant `_maximum` set and an assignment that keeps it
        CType::Sequence(e, Some(n)) => format!(
            "  const uint32_t _maximum;\n  uint32_t _length;\n  {};\n#ifdef __cplusplus\n  {name}() : _maximum({n}), _length(0) {{}}\n  {name} &operator=(const {name} &x)\n  {{\n    _length = x._length;\n    memcpy(_buffer, x._buffer, sizeof(_buffer[0]) * _length);\n    return *this;\n  }}\n#endif\n",
            types.declare(e, &format!("_buffer[{n}]"))
        ),
        CType::Optional(e) => format!("  bool _present;\n  {};\n", types.declare(e, "_value")),
        _ => return,
    };
    guarded(
        out,
        &name,
        &format!("typedef struct {name} {{\n{body}}} {name};\n"),
    );
}

fn members(types: &CTypes, ms: &[(String, CType)], indent: &str) -> String {
    let mut s = String::new();
    for (name, t) in ms {
        let _ = writeln!(s, "{indent}{};", types.declare(t, name));
    }
    s
}

/// The declaration `key`, with the anonymous types it uses before it.
pub fn declaration(out: &mut String, types: &CTypes, key: &str, written: &mut Written) {
    let Some(d) = types.decl(key) else { return };
    let n = &d.cname;
    let uses: Vec<&CType> = match &d.body {
        Body::Struct(ms) | Body::Exception(ms) => ms.iter().map(|(_, t)| t).collect(),
        Body::Union { switch, members } => std::iter::once(switch)
            .chain(members.iter().map(|(_, t)| t))
            .collect(),
        Body::Typedef(t) => vec![t],
        Body::Enum(_) | Body::Native | Body::Const { .. } => Vec::new(),
    };
    match &d.body {
        Body::Struct(_) | Body::Union { .. } | Body::Native => {
            guarded(out, n, &format!("typedef struct {n} {n};\n"));
        }
        _ => {}
    }
    for t in uses {
        templates(out, types, t, written);
    }
    match &d.body {
        Body::Struct(ms) => guarded(
            out,
            &format!("{n}_definition"),
            &format!("struct {n} {{\n{}}};\n", members(types, ms, "  ")),
        ),
        Body::Union {
            switch,
            members: ms,
        } => guarded(
            out,
            &format!("{n}_definition"),
            &format!(
                "struct {n} {{\n  {};\n  union {{\n{}  }} _u;\n}};\n",
                types.declare(switch, "_d"),
                members(types, ms, "    ")
            ),
        ),
        Body::Enum(names) => {
            let mut s = format!("typedef uint32_t {n};\nenum {{\n");
            for (i, e) in names.iter().enumerate() {
                let _ = writeln!(s, "  {e} = {i},");
            }
            s.push_str("};\n");
            guarded(out, n, &s);
        }
        Body::Typedef(t) => guarded(out, n, &format!("typedef {};\n", types.declare(t, n))),
        Body::Native => {}
        Body::Const { ty, value } => {
            // past an `int64_t`, the literal is an unsigned long long
            let suffix = if value
                .parse::<i128>()
                .is_ok_and(|v| v > i128::from(i64::MAX))
            {
                "ULL"
            } else {
                ""
            };
            guarded(
                out,
                n,
                &format!("static const {} = {value}{suffix};\n", types.declare(ty, n)),
            );
        }
        Body::Exception(ms) => {
            let full = format!("::{key}");
            let mut s = format!(
                "/* exception {full} */\nconst char genom_extern_weak {n}_id[] = \"{full}\";\n"
            );
            if ms.is_empty() {
                let _ = write!(
                    s,
                    "typedef void {n}_detail;\nstatic inline genom_event\n{n}(genom_context self)\n{{\n  return self->raise({n}_id, NULL, 0, self);\n}}\n"
                );
            } else {
                let _ = write!(
                    s,
                    "typedef struct {n}_detail {{\n{}}} {n}_detail;\nstatic inline genom_event\n{n}({n}_detail *d, genom_context self)\n{{\n  return self->raise({n}_id, d, sizeof(*d), self);\n}}\n",
                    members(types, ms, "  ")
                );
            }
            guarded(out, n, &s);
        }
    }
}
