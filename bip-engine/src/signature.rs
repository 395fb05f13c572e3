//! What bindings were made for: a module object's codels in the order it numbers them,
//! each with its outcomes in the order [`crate::Next::Declared`] numbers them, and the
//! data types of a module that typed code assumes. Checked against the model when the
//! engine is built, so that bindings generated from another version of the model are a
//! build error rather than codels called by the wrong numbers or data of the wrong type.

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::genom::map::ModuleMap;

/// One codel of a module object, as the object numbers it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CodelSignature {
    pub service: &'static str,
    /// The codel's state, as the model names it (`start`, `track`).
    pub codel: &'static str,
    /// Its yields as the model writes them (`pause::track`, `ether`), in the model's order.
    pub yields: &'static [&'static str],
    /// Its exceptions, in the model's order.
    pub throws: &'static [&'static str],
}

/// The first difference between `signature` and the codels of `module` (services, then
/// their codels, as declared), in words.
pub(crate) fn difference(signature: &[CodelSignature], module: &ModuleMap) -> Option<String> {
    let mut codels = module
        .services
        .iter()
        .flat_map(|s| s.every_codel().map(move |c| (s, c)));
    for (k, sig) in signature.iter().enumerate() {
        let Some((s, c)) = codels.next() else {
            return Some(format!(
                "they have {} codels, the model {k}",
                signature.len()
            ));
        };
        if (sig.service, sig.codel) != (s.name.as_str(), c.state.as_str()) {
            return Some(format!(
                "their codel {k} is `{}.{}`, the model's is `{}.{}`",
                sig.service, sig.codel, s.name, c.state
            ));
        }
        let yields: Vec<&str> = c.yields.iter().map(|y| y.target.as_str()).collect();
        if sig.yields != yields.as_slice() {
            return Some(format!(
                "codel `{}.{}` yields {:?} in them, {:?} in the model",
                sig.service, sig.codel, sig.yields, yields
            ));
        }
        if sig.throws != c.throws.as_slice() {
            return Some(format!(
                "codel `{}.{}` throws {:?} in them, {:?} in the model",
                sig.service, sig.codel, sig.throws, c.throws
            ));
        }
    }
    let more = codels.count();
    (more > 0).then(|| {
        format!(
            "they have {} codels, the model {}",
            signature.len(),
            signature.len() + more
        )
    })
}

/// The data types of a module as typed code assumes them, each written in full as a model
/// file writes it ([`DataType::written`]; `""` where the model declares none).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ModuleTypes {
    /// Its ids fields: `Bool` or `Int(lo, hi)`.
    pub ids: &'static [Typed],
    pub ports: &'static [Typed],
    pub services: &'static [ServiceTypes],
}

/// A name and its type, written in full.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Typed {
    pub name: &'static str,
    pub ty: &'static str,
}

/// A service and the types of its arguments and output, written in full.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ServiceTypes {
    pub name: &'static str,
    pub args: &'static str,
    pub output: &'static str,
}

/// The first difference between `types` and the data types of `module`, in words.
pub(crate) fn types_difference(types: &ModuleTypes, module: &ModuleMap) -> Option<String> {
    let model = module.written_types();
    let theirs = |xs: &[Typed]| -> Vec<(&'static str, &'static str)> {
        xs.iter().map(|x| (x.name, x.ty)).collect()
    };
    let their_services =
        |f: fn(&ServiceTypes) -> &'static str| -> Vec<(&'static str, &'static str)> {
            types.services.iter().map(|s| (s.name, f(s))).collect()
        };
    compare("ids field", &theirs(types.ids), &model.ids)
        .or_else(|| compare("port", &theirs(types.ports), &model.ports))
        .or_else(|| {
            compare("service", &their_services(|s| s.args), &model.args).map(|d| d + " (arguments)")
        })
        .or_else(|| {
            compare("service", &their_services(|s| s.output), &model.outputs)
                .map(|d| d + " (output)")
        })
}

/// The first difference between two lists of typed names: the names, then a type.
fn compare(what: &str, theirs: &[(&str, &str)], model: &[(&str, String)]) -> Option<String> {
    let names = |xs: Vec<&str>| xs.join(", ");
    let their_names: Vec<&str> = theirs.iter().map(|x| x.0).collect();
    let model_names: Vec<&str> = model.iter().map(|x| x.0).collect();
    if their_names != model_names {
        return Some(format!(
            "their {what}s are [{}], the model's [{}]",
            names(their_names),
            names(model_names)
        ));
    }
    let untyped = |t: &str| {
        if t.is_empty() {
            "untyped".to_string()
        } else {
            t.to_string()
        }
    };
    theirs
        .iter()
        .zip(model)
        .find(|((_, a), (_, b))| *a != b.as_str())
        .map(|((name, a), (_, b))| {
            format!(
                "{what} `{name}` is {} in them, {} in the model",
                untyped(a),
                untyped(b)
            )
        })
}
