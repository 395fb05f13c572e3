//! Why a failing trace of a GenoM layer ends as it does, for the text and JSON reports and
//! the chart: at a deadlock, the codels that are ready but held, and by what; for a
//! response property, the same where the response fails to come (the state where its
//! cycle starts, the state the tick past the bound leaves, the state where the run
//! stops), with what refuses a new request of the services whose requests it watches.
//! The explanation itself is bip-model's (`GenomMap::stuck`, `ServiceMap::refused_by`).

use bip_model::genom::{GenomMap, ModuleMap, Reason, ServiceMap};
use bip_model::{Happens, PropertyKind, Role, State, System, Trace, Verdict};

/// A line of the explanation, and how deep it is indented under its heading (0: a codel
/// or a service, 1: a condition that holds it).
pub(crate) type Line = (usize, String);

/// The explanation of `trace`'s end; empty for other models and verdicts, or when nothing
/// holds anything.
pub(crate) fn why(system: &System, trace: &Trace) -> Vec<Line> {
    let Some(genom) = &system.genom else {
        return Vec::new();
    };
    let Ok(path) = trace.replay(system) else {
        return Vec::new();
    };
    let state_at = |k: usize| {
        if k == 0 {
            system.initial_state()
        } else {
            path[k - 1].1.clone()
        }
    };
    let (state, watched, mut out) = match &trace.verdict {
        Verdict::Deadlock => (state_at(path.len()), None, Vec::new()),
        Verdict::Violation(name) => {
            let Some(PropertyKind::Response { trigger, .. }) = system
                .properties
                .iter()
                .find(|p| &p.name == name)
                .map(|p| &p.kind)
            else {
                return Vec::new();
            };
            let (k, place) = match trace.loop_start {
                Some(k) => (k, "where the cycle starts"),
                None if ends_late(system, &path) => (path.len() - 1, "when the bound is reached"),
                None => (path.len(), "where the run stops"),
            };
            let at = format!("{place} (after step {k}):");
            (state_at(k), Some(trigger), vec![(0, at)])
        }
        _ => return Vec::new(),
    };
    let heading = out.len();
    let stuck = match genom.stuck(system, &state) {
        Ok(stuck) => stuck,
        Err(e) => return vec![(0, format!("cannot tell ({e})"))],
    };
    for st in &stuck {
        out.push((heading, format!("{st} but held by")));
        out.extend(st.held_by.iter().map(|c| (heading + 1, c.to_string())));
    }
    // the services whose accepted requests are the trigger
    for m in &genom.modules {
        for svc in m.services.iter() {
            // a task's machine is never requested
            let Some(request) = svc.request else { continue };
            let request = system.interactions[request as usize].connector;
            let is_watched = matches!(watched, Some(Happens::Step(patterns))
                if patterns.iter().any(|p| p.connectors.contains(&request)));
            if !is_watched
                || stuck
                    .iter()
                    .any(|s| s.module == m.name && s.service == svc.name)
            {
                continue;
            }
            out.extend(waiting_service(system, genom, &state, m, svc, heading));
        }
    }
    if out.len() == heading {
        return Vec::new();
    }
    out
}

/// What a service whose requests a response property watches waits for in `state`, when
/// no constraint holds its codels: its codels ready only once time passes (its task's
/// period), or what refuses a new request.
fn waiting_service(
    system: &System,
    genom: &GenomMap,
    state: &State,
    m: &ModuleMap,
    svc: &ServiceMap,
    heading: usize,
) -> Vec<Line> {
    let cannot_tell = |e: bip_model::RangeError| {
        vec![(
            heading,
            format!("{}.{}: cannot tell ({e})", m.name, svc.name),
        )]
    };
    let ready = match genom.readiness(system, state) {
        Ok(ready) => ready,
        Err(e) => return cannot_tell(e),
    };
    let mut out: Vec<Line> = ready
        .iter()
        .filter(|r| r.module == m.name && r.service == svc.name && r.after_ticks > 0)
        .map(|r| {
            (
                heading,
                format!("{r} (its task's period); nothing holds it"),
            )
        })
        .collect();
    let refused = match svc.refused_by(system, state) {
        Ok(refused) => refused,
        Err(e) => return cannot_tell(e),
    };
    // that an active service takes no second request says nothing new
    let refused: Vec<_> = refused
        .into_iter()
        .filter(|c| c.reason != Reason::AlreadyRequested)
        .collect();
    if !refused.is_empty() {
        out.push((
            heading,
            format!("a new request of {}.{} is refused by", m.name, svc.name),
        ));
        out.extend(refused.iter().map(|c| (heading + 1, c.to_string())));
    }
    out
}

/// The last step is a tick and the run could go on: a bound passed, not a stop.
fn ends_late(system: &System, path: &[(bip_model::OwnedStep, State)]) -> bool {
    let Some((last, after)) = path.last() else {
        return false;
    };
    system.role(last.label) == Role::Time
        && system
            .successors(after)
            .map_or(true, |next| !next.is_empty())
}

/// The explanation as the text report shows it, under `  why:`.
pub(crate) fn write_why(s: &mut String, system: &System, trace: &Trace) {
    use std::fmt::Write as _;
    let lines = why(system, trace);
    if lines.is_empty() {
        return;
    }
    let _ = writeln!(s, "  why:");
    for (depth, line) in lines {
        let _ = writeln!(s, "    {}{line}", "  ".repeat(depth));
    }
}
