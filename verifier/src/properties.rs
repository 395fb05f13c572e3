//! What a verification checks, whatever the method: the same list, in the same order, so
//! that the reports of two methods line up property by property.

use std::borrow::Cow;

use bip_model::{Property, PropertyKind as ModelKind, System};

/// The name of the result that reports range errors.
pub const RANGE_ERRORS: &str = "RangeErrors";

/// The model properties a verification checks: the model's, or `DeadlockFree` if it
/// declares none. Range errors are checked besides, as [`RANGE_ERRORS`], reported last.
pub(crate) fn checked_properties(system: &System) -> Vec<Cow<'_, Property>> {
    if system.properties.is_empty() {
        vec![Cow::Owned(Property {
            name: "DeadlockFree".into(),
            kind: ModelKind::DeadlockFree { terminal: None },
            text: String::new(),
        })]
    } else {
        system.properties.iter().map(Cow::Borrowed).collect()
    }
}
