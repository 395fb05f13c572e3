//! Time progress (`TimeProgress`, docs/model.md, "Time progress"), on the stored graph:
//! a state is *timelocked* when no run from it ever fires a step of a `Time` connector.
//! The liveness properties assume that time diverges; in a timelocked state it cannot,
//! so `cycles` and `bounded` count a cycle of timelocked states as a run that goes on
//! forever, and this check reports the first such state.
//!
//! One pass of Tarjan's algorithm over the whole graph gives its components, successors
//! first; a component lets time pass if one of its states has a tick, or an edge to a
//! component that lets time pass. A state in range error counts as letting time pass:
//! its run ends in the error, which `RangeErrors` reports.

use bip_model::System;

use super::run::{shortest_path, Run};
use super::watched::{Flagged, TICK};
use crate::explore::graph::IN_ERROR;
use crate::explore::scc;
use crate::watch::Watch;

/// The timelocked states of a graph, with its components.
pub(crate) struct Timelocks {
    /// Per state: no run from it fires a tick.
    pub(crate) locked: Vec<bool>,
    /// Each state's component, and per component whether it holds a cycle (an edge
    /// between two of its states, or from one to itself).
    comp: Vec<u32>,
    cyclic: Vec<bool>,
}

/// The timelocked states of `g`; `None` once `watch` says stop.
pub(crate) fn locked(g: &Flagged, watch: &Watch) -> Option<Timelocks> {
    let scc = scc::components(g, |_| true, |_| true, watch)?;
    let mut passes = vec![false; scc.len()];
    let mut cyclic = vec![false; scc.len()];
    for c in 0..scc.len() as u32 {
        for &x in scc.members(c) {
            passes[c as usize] |= g.state_flags[x as usize] & IN_ERROR != 0;
            for e in g.edges(x) {
                let d = scc.of[g.targets[e] as usize];
                cyclic[c as usize] |= d == c;
                passes[c as usize] |= g.edge_data[e] & TICK != 0 || passes[d as usize];
            }
        }
    }
    let locked = scc.of.iter().map(|&c| !passes[c as usize]).collect();
    Some(Timelocks {
        locked,
        comp: scc.of,
        cyclic,
    })
}

/// The first timelocked state in the exploration's order (so at the smallest depth), a
/// shortest path to it, and on from it to where the run is stuck for ever: a shortest
/// path to a state with no step, or to a cycle, then that cycle (the run's `loop_start`).
/// `None` if no state is timelocked.
pub(crate) fn first_timelock(g: &Flagged, t: &Timelocks) -> Option<Run> {
    let first = t.locked.iter().position(|&l| l)? as u32;
    let mut run = Run {
        states: vec![0],
        ..Run::default()
    };
    let stem =
        shortest_path(g, 0, |_| true, |s| s == first).expect("every stored state is reached");
    run.extend(g, &stem);
    // every successor of a timelocked state is timelocked
    let stuck = |s: u32| g.edges(s).is_empty() || t.cyclic[t.comp[s as usize] as usize];
    let to_end = shortest_path(g, first, |_| true, stuck).expect("a finite graph loops or ends");
    run.extend(g, &to_end);
    let entry = run.last();
    let c = t.comp[entry as usize];
    let inside = |e: usize| t.comp[g.targets[e] as usize] == c;
    let Some(first_edge) = g.edges(entry).find(|&e| inside(e)) else {
        return Some(run);
    };
    let back = shortest_path(g, g.targets[first_edge], inside, |s| s == entry)
        .expect("a component is strongly connected");
    run.loop_start = Some(run.edges.len());
    run.push(g, first_edge);
    run.extend(g, &back);
    Some(run)
}

/// Why time cannot pass in `state`, in the model's names: what holds each `Time`
/// interaction back.
pub(crate) fn why(system: &System, state: &bip_model::State) -> String {
    match system.why_time_held(state) {
        Ok(held) if held.is_empty() => "no step of a `Time` connector is enabled".into(),
        Ok(held) => held
            .iter()
            .map(|h| system.describe_time_held(state, h))
            .collect::<Vec<_>>()
            .join("; "),
        Err(e) => format!("the state has a range error ({e})"),
    }
}
