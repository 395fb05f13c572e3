//! What a verification checks, whatever the method: the same list, in the same order, so
//! that the reports of two methods line up property by property.

use std::borrow::Cow;

use bip_model::eval::Expr;
use bip_model::{Property, PropertyKind as ModelKind, System};

/// The name of the result that reports range errors.
pub const RANGE_ERRORS: &str = "RangeErrors";

/// The model properties a verification checks: the model's, or `DeadlockFree` if it
/// declares none, meaning what a written one means: in a GenoM layer it excuses the idle
/// layer ([`GenomMap::idle`](bip_model::GenomMap)). Range errors are checked besides, as
/// [`RANGE_ERRORS`], reported last.
pub(crate) fn checked_properties(system: &System) -> Vec<Cow<'_, Property>> {
    if system.properties.is_empty() {
        vec![Cow::Owned(Property {
            name: "DeadlockFree".into(),
            kind: ModelKind::DeadlockFree {
                terminal: default_terminal(system).cloned(),
            },
            text: String::new(),
        })]
    } else {
        system.properties.iter().map(Cow::Borrowed).collect()
    }
}

/// The states the default `DeadlockFree` excuses: the idle GenoM layer's, if any.
pub(crate) fn default_terminal(system: &System) -> Option<&Expr> {
    system.genom.as_ref()?.idle.as_ref()
}
