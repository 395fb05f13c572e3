//! What a module object was made for: its codels in the order it numbers them, each with
//! its outcomes in the order [`crate::Next::Declared`] numbers them. Checked against the
//! model when the engine is built, so that bindings generated from another version of the
//! model are a build error rather than codels called by the wrong numbers.

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
        .flat_map(|s| s.codels.iter().map(move |c| (s, c)));
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
