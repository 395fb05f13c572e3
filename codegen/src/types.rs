//! The model's data types as Rust: a record becomes a struct of its name (its fields
//! `bool`, `Bounded`, `f64`, records or Rust types), so that the engine's run-time check
//! (which compares type names) and the generated type agree by construction; an
//! `Int(lo, hi)` is a `bip_engine::Bounded<lo, hi>`, which holds only values in range (the
//! engine keeps it as an `i64`: the API converts where a value enters or leaves it); a
//! `Rust("path")` type is used as written, resolved where the bindings are included.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use bip_model::genom::map::DataType;
use bip_model::genom::GenomMap;

use crate::names::snake;
use crate::CodegenError;

/// Where a type is named: at the top of the bindings, or inside a module's `mod`.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum At {
    Top,
    Module,
}

/// The Rust type of a value of `ty`, named from `at`.
pub(crate) fn rust_type(ty: &DataType, at: At) -> String {
    let up = if at == At::Module { "super::" } else { "" };
    match ty {
        DataType::Bool => "bool".into(),
        DataType::Int { lo, hi } => bounded(*lo, *hi),
        DataType::Float => "f64".into(),
        DataType::Record { name, .. } => format!("{up}{name}"),
        DataType::Rust(path) if is_absolute(path) => path.clone(),
        DataType::Rust(path) => format!("{up}{path}"),
    }
}

/// `bip_engine::Bounded<lo, hi>`, the type of the model's `Int(lo, hi)` and of an ids
/// field of that range.
pub(crate) fn bounded(lo: i64, hi: i64) -> String {
    // a negative literal is a const argument, but `i64::MIN`'s digits overflow before
    // the minus applies
    let arg = |v: i64| {
        if v == i64::MIN {
            "{ i64::MIN }".to_string()
        } else {
            v.to_string()
        }
    };
    format!("bip_engine::Bounded<{}, {}>", arg(lo), arg(hi))
}

/// Whether the engine keeps a value of `ty` as an `i64` that the API gives and takes as a
/// `Bounded`, by value (an `Int`); every other type is kept as its Rust type and read by
/// reference.
pub(crate) fn is_int(ty: &DataType) -> bool {
    matches!(ty, DataType::Int { .. })
}

/// A path that names the same type wherever it is written.
fn is_absolute(path: &str) -> bool {
    path.starts_with("::")
        || ["crate::", "std::", "core::", "alloc::"]
            .iter()
            .any(|p| path.starts_with(p))
}

/// Every data type the layer declares: its ports', services' arguments' and outputs'.
fn declared(layer: &GenomMap) -> impl Iterator<Item = (&DataType, String)> {
    layer.modules.iter().flat_map(|m| {
        let ports = m
            .ports
            .iter()
            .filter_map(move |p| Some((p.ty.as_ref()?, format!("port `{}.{}`", m.name, p.name))));
        let services = m.services.iter().flat_map(move |s| {
            let what = format!("service `{}.{}`", m.name, s.name);
            s.args
                .iter()
                .chain(s.output.iter())
                .map(move |t| (t, what.clone()))
        });
        ports.chain(services)
    })
}

/// The structs of the layer's records, each once; two records of one name with other
/// fields are an error that names both places.
pub(crate) fn records(out: &mut String, layer: &GenomMap) -> Result<(), CodegenError> {
    let mut seen: BTreeMap<String, (&DataType, String)> = BTreeMap::new();
    let mut stack: Vec<(&DataType, String)> = declared(layer).collect();
    while let Some((ty, what)) = stack.pop() {
        let DataType::Record { name, fields } = ty else {
            continue;
        };
        match seen.get(name) {
            Some((first, where_)) if *first != ty => {
                return Err(CodegenError::Clash {
                    first: format!("record `{name}` of {where_}"),
                    second: format!("record `{name}` of {what}"),
                    rust: name.clone(),
                })
            }
            Some(_) => {}
            None => {
                seen.insert(name.clone(), (ty, what.clone()));
                stack.extend(fields.iter().map(|(_, t)| (t, what.clone())));
            }
        }
    }
    for (name, (ty, what)) in &seen {
        let DataType::Record { fields, .. } = ty else {
            continue;
        };
        let _ = writeln!(
            out,
            "/// Record `{name}` of the model (the type of {what}).\n#[derive(Clone, Debug, Default, PartialEq)]\npub struct {name} {{"
        );
        for (field, t) in fields {
            let _ = writeln!(
                out,
                "    /// Field `{field}`: {t}.\n    pub {}: {},",
                snake(field),
                rust_type(t, At::Top)
            );
        }
        out.push_str("}\n\n");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_int_is_a_bounded_of_its_range() {
        let int = |lo, hi| rust_type(&DataType::Int { lo, hi }, At::Module);
        assert_eq!(int(-3, 7), "bip_engine::Bounded<-3, 7>");
        // i64::MIN's digits do not make a literal: a block does
        assert_eq!(
            int(i64::MIN, i64::MAX),
            format!("bip_engine::Bounded<{{ i64::MIN }}, {}>", i64::MAX)
        );
    }
}
