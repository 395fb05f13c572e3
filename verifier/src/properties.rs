//! What a verification checks, whatever the method: the same list, in the same order, so
//! that the reports of two methods line up property by property.

use std::borrow::Cow;

use bip_model::eval::Expr;
use bip_model::{Property, PropertyKind as ModelKind, Steps, System, Trace, Verdict};

use crate::report::CheckKind;

/// The name of the result that reports range errors.
pub const RANGE_ERRORS: &str = "RangeErrors";

/// The name of the result that says time can always pass (docs/model.md, "Time
/// progress"): from every reachable state, some run fires a step of a `Time` connector.
pub use bip_model::TIME_PROGRESS;

/// `units` of `system`'s time steps, as its bounds are written of: a duration in a timed
/// model, whose steps are units of its time; ticks otherwise.
pub(crate) fn time_words(system: &System, units: u64) -> String {
    match system.genom.as_ref().and_then(|g| g.time_unit_us) {
        Some(us) => bip_sched::show_micros(units.saturating_mul(us)),
        None => format!("{units} tick{}", if units == 1 { "" } else { "s" }),
    }
}

/// True if a verification of `system` checks [`TIME_PROGRESS`]: it has `Time` connectors.
/// It is reported after the model's properties, before range errors.
pub(crate) fn checks_time_progress(system: &System) -> bool {
    system.has_time()
}

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

/// What a result of property `kind` checks.
pub(crate) fn check_kind(kind: &ModelKind) -> CheckKind {
    match kind {
        ModelKind::DeadlockFree { .. } => CheckKind::DeadlockFree,
        ModelKind::Invariant(_) => CheckKind::Invariant,
        ModelKind::Reachable(_) => CheckKind::Reachable,
        ModelKind::Response {
            within: Some(_), ..
        } => CheckKind::Response,
        ModelKind::Response { within: None, .. } => CheckKind::LeadsTo,
    }
}

/// The states the default `DeadlockFree` excuses: the idle GenoM layer's, if any.
pub(crate) fn default_terminal(system: &System) -> Option<&Expr> {
    system.genom.as_ref()?.idle.as_ref()
}

/// For a range-error trace whose last state has a step that fails when fired: that step's
/// name (the connector's interaction, or `component.internal`), which the trace cannot
/// list (a failing step has no successor). `None` for other traces, and for a range error
/// in a guard or a property, which the last state itself shows.
pub(crate) fn error_step(system: &System, trace: &Trace) -> Option<String> {
    if !matches!(trace.verdict, Verdict::RangeError(_)) {
        return None;
    }
    let path = trace.replay(system).ok()?;
    let last = path
        .last()
        .map_or_else(|| system.initial_state(), |(_, s)| s.clone());
    let mut steps = Steps::new();
    system.enabled_steps(&last, &mut steps).ok()?;
    let mut next = last.clone();
    let failing = steps
        .iter()
        .find(|s| system.fire(&last, *s, &mut next).is_err())
        .map(|s| system.label_name(s.label));
    failing
}
