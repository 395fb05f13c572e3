//! A timed model in which time can stop (`TimeProgress` fails: a loop of codels that
//! take no time, or steps that block the tick) has runs whose jobs neither end nor let
//! their deadlines pass. A deadline that holds, or a worst response, is then true of the
//! model only because time does not pass there: neither is reported as holding.

use bip_model::System;

use crate::report::{CheckKind, PropertyResult, PropertyVerdict};

/// Whether `name` is the generated deadline of one of the model's tasks (`m.t meets its
/// D deadline`, docs/verify.md).
fn is_deadline(system: &System, name: &str) -> bool {
    let Some(map) = &system.genom else {
        return false;
    };
    map.modules.iter().any(|m| {
        m.tasks.iter().any(|t| {
            name.strip_prefix(&format!("{}.{} meets its ", m.name, t.name))
                .is_some_and(|rest| rest.ends_with(" deadline"))
        })
    })
}

/// Makes the holding deadlines and worst responses of a timed model inconclusive where
/// its `TimeProgress` fails.
pub(crate) fn qualify(system: &System, properties: &mut [PropertyResult]) {
    if !system.is_timed() {
        return;
    }
    let stops = properties
        .iter()
        .any(|p| p.kind == CheckKind::TimeProgress && p.verdict.fails());
    if !stops {
        return;
    }
    for p in properties.iter_mut() {
        let timed = p.kind == CheckKind::WorstResponse
            || (p.kind == CheckKind::Invariant && is_deadline(system, &p.name));
        if timed && p.verdict.holds() {
            p.verdict = PropertyVerdict::Inconclusive {
                reason: "time can stop (TimeProgress fails): a job caught where it stops never ends, and its deadline never passes".into(),
            };
            p.note = None;
        }
    }
}
