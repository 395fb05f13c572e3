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
//!
//! Time progress also fails on a *busy loop*, a reachable cycle on which no state lets
//! time pass though the run could leave it (a loop of plain yields, codels that wake each
//! other for ever): the liveness properties assume that time diverges, and on such a run
//! it does not. Another pass finds the components of the states without a tick.

use bip_model::System;

use super::run::{shortest_path, Run};
use super::watched::{Flagged, ENVIRONMENT, TICK};
use crate::explore::graph::IN_ERROR;
use crate::explore::scc::{self, OUTSIDE};
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
    close_cycle(g, &mut run, &t.comp, |_| true);
    Some(run)
}

/// Ends `run`, whose last state is in component `comp[last]`, with a cycle of that
/// component through it along edges `follow` admits (the run's `loop_start`), if the
/// component holds one.
fn close_cycle(g: &Flagged, run: &mut Run, comp: &[u32], follow: impl Fn(usize) -> bool) {
    let entry = run.last();
    let c = comp[entry as usize];
    let inside = |e: usize| follow(e) && comp[g.targets[e] as usize] == c;
    let Some(first_edge) = g.edges(entry).find(|&e| inside(e)) else {
        return;
    };
    let back = shortest_path(g, g.targets[first_edge], inside, |s| s == entry)
        .expect("a component is strongly connected");
    run.loop_start = Some(run.edges.len());
    run.push(g, first_edge);
    run.extend(g, &back);
}

/// A busy loop: a reachable cycle of states none of which lets time pass in one step (no
/// tick leaves them), made of steps the model takes by itself, on which a run stays for
/// ever while time stands still, though it could leave (else its states are timelocked,
/// which [`first_timelock`] reports). A cycle with a step of the environment is the
/// environment's choice to act without end in an instant, not the model's: it is not
/// one. A shortest run to such a cycle, then the cycle (the run's `loop_start`);
/// `Some(None)` if there is none, `None` once `watch` says stop.
pub(crate) fn first_busy_loop(g: &Flagged, watch: &Watch) -> Option<Option<Run>> {
    let held = |s: u32| {
        g.state_flags[s as usize] & IN_ERROR == 0 && g.edges(s).all(|e| g.edge_data[e] & TICK == 0)
    };
    let follow = |e: usize| g.edge_data[e] & ENVIRONMENT == 0 && held(g.targets[e]);
    let scc = scc::components(g, held, follow, watch)?;
    let mut cyclic = vec![false; scc.len()];
    for c in 0..scc.len() as u32 {
        cyclic[c as usize] = scc.members(c).iter().any(|&x| {
            g.edges(x)
                .any(|e| follow(e) && scc.of[g.targets[e] as usize] == c)
        });
    }
    let on_loop = |s: u32| scc.of[s as usize] != OUTSIDE && cyclic[scc.of[s as usize] as usize];
    let Some(stem) = shortest_path(g, 0, |_| true, on_loop) else {
        return Some(None);
    };
    let mut run = Run {
        states: vec![0],
        ..Run::default()
    };
    run.extend(g, &stem);
    close_cycle(g, &mut run, &scc.of, follow);
    Some(Some(run))
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
