//! The worst response of a response property (`Replies`, `Response`, `LeadsTo`) in a
//! model with time: the longest time a trigger can wait for its response, with the run
//! that waits it (docs/verify.md, "Worst responses of services and properties").
//!
//! A run waits where the bounded observer's count is running: in the product of the
//! stored graph with "a trigger waits", from the step that starts a wait to the step that
//! answers it, and each tick taken while a trigger waits adds its time units (the
//! answering tick too, as the observer counts it). The waiting part of the graph is the
//! states reached with a trigger waiting and the steps out of them that do not answer.
//! The worst wait is the longest path through it, by its ticks' units. It is unbounded
//! where the waiting part holds a cycle that goes on forever (one with a tick, or of
//! timelocked states, where time cannot pass) or a state with no step: there the
//! property fails without a bound. Otherwise every cycle of the waiting part takes no
//! time, so each strongly connected component is one point in time, and the longest
//! path is a pass over the components, successors first.

use super::run::{product_run, shortest_path, Run};
use super::watched::{at_start, on_edge, units, Flagged, TICK};
use crate::explore::graph::IN_ERROR;
use crate::explore::scc::{self, Components};
use crate::watch::Watch;

/// The worst wait of a property.
#[derive(Debug, PartialEq)]
pub(crate) enum Worst {
    /// No trigger ever waits: it never happens, or each is answered in its own step.
    NoWait,
    /// The longest wait, in time units, and a run that waits it: a shortest run to the
    /// step that starts the wait, then the longest wait to the step that answers it.
    Units(u64, Run),
    /// A trigger can wait for ever, or for longer than any bound.
    Unbounded,
    Stopped,
}

/// Product states are `2 s + w`: state `s` with a trigger waiting (`w = 1`) or not.
const NONE: u32 = u32::MAX;

/// The worst wait of property `p` on the complete graph `g`; `locked`, in a model with
/// time, its timelocked states.
pub(crate) fn longest_wait(g: &Flagged, p: usize, locked: &[bool], watch: &Watch) -> Worst {
    let n = g.len();
    // the product's parents and breadth-first order (16 bytes a state), the components
    // (16), a value per one (8)
    if watch.stopped().is_some() || !watch.expect(n as u64 * 40) {
        return Worst::Stopped;
    }
    let Some((parent, order)) = reach(g, p, watch) else {
        return Worst::Stopped;
    };
    let waits = |s: u32| parent[2 * s as usize + 1] != NONE;
    if !(0..n as u32).any(waits) {
        return Worst::NoWait;
    }
    // the steps along which a trigger goes on waiting
    let goes_on = |e: usize| !on_edge(g, p, e).response;
    let Some(scc) = scc::components(g, waits, goes_on, watch) else {
        return Worst::Stopped;
    };
    let Some(longest) = longest_per_component(g, &scc, locked, &goes_on) else {
        return Worst::Unbounded;
    };
    let value = |s: u32| longest[scc.of[s as usize] as usize];
    let worst = (0..n as u32)
        .filter(|&s| waits(s))
        .map(value)
        .max()
        .unwrap_or(0);
    // the first product state in breadth-first order that waits with the worst ahead of
    // it: reached from one that does not wait (any waiting parent would have as much
    // ahead, and come first), or the initial one
    let start = *order
        .iter()
        .find(|&&x| x % 2 == 1 && value(x / 2) == worst)
        .expect("a waiting state has the worst wait ahead of it");
    drop(order);
    let mut run = run_to(g, p, &parent, start);
    follow_longest(g, &scc, &longest, &goes_on, &mut run);
    Worst::Units(worst, run)
}

/// The product's states reached from the initial one, breadth first: each one's parent
/// (itself for the initial one), [`NONE`] if it is not reached, and the reached ones in
/// breadth-first order; `None` once `watch` says stop.
fn reach(g: &Flagged, p: usize, watch: &Watch) -> Option<(Vec<u32>, Vec<u32>)> {
    let mut parent = vec![NONE; 2 * g.len()];
    let start = u32::from(at_start(g, p).waits_after(false));
    parent[start as usize] = start;
    // the queue, kept whole: it is the breadth-first order
    let mut order = vec![start];
    let mut next = 0;
    let mut work = 0u64;
    while let Some(&x) = order.get(next) {
        next += 1;
        let (s, waited) = (x / 2, x % 2 == 1);
        for e in g.edges(s) {
            work += 1;
            if work.is_multiple_of(4096) && watch.stopped().is_some() {
                return None;
            }
            let y = 2 * g.targets[e] + u32::from(on_edge(g, p, e).waits_after(waited));
            if parent[y as usize] == NONE {
                parent[y as usize] = x;
                order.push(y);
            }
        }
    }
    Some((parent, order))
}

/// What an edge out of a waiting state adds to the wait: its time units if it is a tick.
fn weight(g: &Flagged, e: usize) -> u64 {
    if g.edge_data[e] & TICK != 0 {
        u64::from(units(g, e))
    } else {
        0
    }
}

/// The longest wait from each component of the waiting part, successors first; `None`
/// if some wait is unbounded: a component with a cycle that goes on forever (a tick
/// inside it, or a timelocked state with a step inside it) or a state with no step.
fn longest_per_component(
    g: &Flagged,
    scc: &Components,
    locked: &[bool],
    goes_on: &impl Fn(usize) -> bool,
) -> Option<Vec<u64>> {
    let mut longest = Vec::with_capacity(scc.len());
    for c in 0..scc.len() as u32 {
        let mut most = 0u64;
        for &x in scc.members(c) {
            if g.edges(x).is_empty() && g.state_flags[x as usize] & IN_ERROR == 0 {
                return None;
            }
            for e in g.edges(x) {
                let ahead = if !goes_on(e) {
                    // answered: the answering step's own time counts
                    weight(g, e)
                } else {
                    let d = scc.of[g.targets[e] as usize];
                    if d == c {
                        if weight(g, e) > 0 || locked[x as usize] {
                            return None;
                        }
                        continue;
                    }
                    weight(g, e).saturating_add(longest[d as usize])
                };
                most = most.max(ahead);
            }
        }
        longest.push(most);
    }
    Some(longest)
}

/// The run to product state `x`, following parents.
fn run_to(g: &Flagged, p: usize, parent: &[u32], x: u32) -> Run {
    product_run(g, parent, 2, x, |waited, e| {
        Some(u32::from(on_edge(g, p, e).waits_after(waited == 1)))
    })
}

/// Extends `run`, whose last state waits, along a longest wait to its answer: in each
/// component, to the member whose step out of it has the component's longest wait
/// ahead, then that step.
fn follow_longest(
    g: &Flagged,
    scc: &Components,
    longest: &[u64],
    goes_on: &impl Fn(usize) -> bool,
    run: &mut Run,
) {
    loop {
        let c = scc.of[run.last() as usize];
        let inside = |e: usize| goes_on(e) && scc.of[g.targets[e] as usize] == c;
        let best = |e: usize| {
            if !goes_on(e) {
                weight(g, e) == longest[c as usize]
            } else {
                let d = scc.of[g.targets[e] as usize];
                d != c && weight(g, e) + longest[d as usize] == longest[c as usize]
            }
        };
        let has_best = |s: u32| g.edges(s).any(best);
        // none in a component whose states are in range error: the wait ends there
        let Some(path) = shortest_path(g, run.last(), inside, has_best) else {
            return;
        };
        run.extend(g, &path);
        let e = g
            .edges(run.last())
            .find(|&e| best(e))
            .expect("found by has_best");
        run.push(g, e);
        if !goes_on(e) {
            return;
        }
    }
}
