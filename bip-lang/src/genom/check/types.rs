//! Data types of ports, service arguments and outputs (docs/model.md, "Data types"):
//! checked with their positions and turned into bip-model's `DataType`.

use crate::compile::{check_name, unique, Constants};
use crate::diag::{Errors, ModelError};
use crate::syntax::{DataTypeDef, Text};
use bip_model::genom::map::DataType;

/// The type `def` names, or `None` (with the errors pushed) if it is not one.
pub(super) fn data_type(
    errors: &mut Errors,
    consts: &Constants,
    def: &DataTypeDef,
) -> Option<DataType> {
    match def {
        DataTypeDef::Bool => Some(DataType::Bool),
        DataTypeDef::Float => Some(DataType::Float),
        DataTypeDef::Int(lo, hi) => {
            let (lo_v, hi_v) = match (consts.int(lo), consts.int(hi)) {
                (Ok(a), Ok(b)) => (a, b),
                (a, b) => {
                    for e in [a.err(), b.err()].into_iter().flatten() {
                        errors.push(e);
                    }
                    return None;
                }
            };
            if lo_v > hi_v {
                errors.push(
                    ModelError::new(format!("type `Int({lo_v}, {hi_v})` is empty"), hi.span)
                        .with_label("the upper bound is below the lower one")
                        .with_help("write the bounds in order: `Int(lo, hi)`, both included"),
                );
                return None;
            }
            Some(DataType::Int { lo: lo_v, hi: hi_v })
        }
        DataTypeDef::Record { name, fields } => {
            let mut ok = check_name(errors, name, "record");
            unique(
                errors,
                fields.iter().map(|f| &f.name),
                &format!("field of record `{name}`"),
            );
            let mut out = Vec::new();
            for f in fields {
                ok &= check_name(errors, &f.name, "field");
                if let DataTypeDef::Rust(path) = &f.ty {
                    errors.push(
                        ModelError::new(
                            format!("field `{}` of record `{name}` has a Rust type", f.name),
                            path.span,
                        )
                        .with_label("a record holds model-level types")
                        .with_help(
                            "a record's fields are `Bool`, `Int(lo, hi)`, `Float` or records; \
                             give the whole port or argument a `Rust(\"...\")` type instead",
                        ),
                    );
                    ok = false;
                    continue;
                }
                match data_type(errors, consts, &f.ty) {
                    Some(t) => out.push((f.name.to_string(), t)),
                    None => ok = false,
                }
            }
            ok.then(|| DataType::Record {
                name: name.to_string(),
                fields: out,
            })
        }
        DataTypeDef::Rust(path) => {
            rust_path(errors, path).then(|| DataType::Rust(path.to_string()))
        }
    }
}

/// Whether `path` reads as a Rust type path: `Name`, `a::b::Name`, `Name<T, U>`.
fn rust_path(errors: &mut Errors, path: &Text) -> bool {
    let p = path.as_str();
    let ident_start = |c: char| c.is_ascii_alphabetic() || c == '_';
    let ok = p.chars().next().is_some_and(|c| ident_start(c) || c == ':')
        && p.chars()
            .all(|c| c.is_ascii_alphanumeric() || "_:<>, &'[];".contains(c))
        && !p.ends_with("::")
        && !p.contains(":::")
        && p.chars().filter(|&c| c == '<').count() == p.chars().filter(|&c| c == '>').count();
    if !ok {
        errors.push(
            ModelError::new(format!("`{p}` is not a Rust type path"), path.span)
                .with_label("not a type path")
                .with_help("name the Rust type as code would: `Rust(\"my_crate::nav::Pose\")`"),
        );
    }
    ok
}
