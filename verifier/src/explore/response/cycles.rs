//! Unbounded response (`LeadsTo`, `Replies`, `Terminates`): a search for a run on which
//! the response never comes, on the stored graph (docs/verify.md, "Response and
//! liveness").
//!
//! After a trigger, the run waits: it stays in states where the response does not hold
//! and takes steps that are not the response. The property fails if, from a trigger, the
//! waiting part of the graph leads to a cycle that lets time pass (a tick on the cycle;
//! any cycle in a model without `Time` connectors) or to a state with no step at all.
//! One pass of Tarjan's algorithm over the waiting part finds its strongly connected
//! components, successors first, and marks each *doomed* if it holds such a cycle or
//! dead end, or leads to a doomed one; a trigger into a doomed state is a counterexample.

use super::run::{shortest_path, Run};
use super::watched::{response_bit, trigger_bit, Flagged, TICK};
use crate::explore::graph::IN_ERROR;
use crate::watch::Watch;

/// What the search found.
pub(crate) enum Found {
    Holds {
        vacuous: bool,
    },
    /// A lasso (a cycle that lets time pass) or a run to a state with no step.
    Fails(Run),
    Stopped,
}

const NONE: u32 = u32::MAX;

struct Waiting<'g> {
    g: &'g Flagged,
    response: u32,
    /// The model has a `Time` connector: only runs with infinitely many ticks count.
    timed: bool,
}

impl Waiting<'_> {
    fn state(&self, s: u32) -> bool {
        self.g.state_flags[s as usize] & (self.response | IN_ERROR) == 0
    }

    fn edge(&self, e: usize) -> bool {
        self.g.edge_data[e] & self.response == 0 && self.state(self.g.targets[e])
    }

    /// An edge that lets the run count as going on forever on a cycle.
    fn fair(&self, e: usize) -> bool {
        !self.timed || self.g.edge_data[e] & TICK != 0
    }

    fn dead(&self, s: u32) -> bool {
        self.g.edges(s).is_empty() && self.g.state_flags[s as usize] & IN_ERROR == 0
    }
}

/// Searches property `p` of the graph, of a model with `Time` connectors if `timed`.
pub(crate) fn search(g: &Flagged, p: usize, timed: bool, watch: &Watch) -> Found {
    let w = Waiting {
        g,
        response: response_bit(p),
        timed,
    };
    let trigger = trigger_bit(p);
    let Some(scc) = components(&w, watch) else {
        return Found::Stopped;
    };
    let doomed = |s: u32| scc.comp[s as usize] != NONE && scc.doomed[scc.comp[s as usize] as usize];
    // the first trigger, in the exploration's order, from which the response can be avoided
    let mut vacuous = true;
    let mut start = None;
    'states: for s in 0..g.len() as u32 {
        let flags = g.state_flags[s as usize];
        if flags & trigger != 0 {
            vacuous = false;
            if doomed(s) {
                start = Some((s, None));
                break;
            }
        }
        for e in g.edges(s) {
            if g.edge_data[e] & trigger != 0 {
                vacuous = false;
                if g.edge_data[e] & w.response == 0 && doomed(g.targets[e]) {
                    start = Some((s, Some(e)));
                    break 'states;
                }
            }
        }
    }
    let Some((s, by)) = start else {
        return Found::Holds { vacuous };
    };
    let mut run = Run {
        states: vec![0],
        ..Run::default()
    };
    let stem = shortest_path(g, 0, |_| true, |t| t == s).expect("every stored state is reached");
    run.extend(g, &stem);
    if let Some(e) = by {
        run.push(g, e);
    }
    // on to the nearest dead end or state of a doomed component with a fair cycle
    let ends = |t: u32| w.dead(t) || scc.fair[scc.comp[t as usize] as usize];
    let to_end = shortest_path(g, run.last(), |e| w.edge(e) && doomed(g.targets[e]), ends)
        .expect("a doomed state leads to a dead end or a fair cycle");
    run.extend(g, &to_end);
    let entry = run.last();
    if w.dead(entry) {
        return Found::Fails(run);
    }
    let c = scc.comp[entry as usize];
    let inside = |e: usize| w.edge(e) && scc.comp[g.targets[e] as usize] == c;
    // to a state with a fair edge inside the component, along it, and back to the entry
    let has_fair = |t: u32| g.edges(t).any(|e| inside(e) && w.fair(e));
    let to_fair = shortest_path(g, entry, inside, has_fair).expect("the component has a fair edge");
    let loop_start = run.edges.len();
    run.extend(g, &to_fair);
    let fair = g
        .edges(run.last())
        .find(|&e| inside(e) && w.fair(e))
        .expect("found by has_fair");
    run.push(g, fair);
    let back = shortest_path(g, run.last(), inside, |t| t == entry)
        .expect("a component is strongly connected");
    run.extend(g, &back);
    run.loop_start = Some(loop_start);
    Found::Fails(run)
}

struct Components {
    /// Each waiting state's component (`NONE` outside the waiting part).
    comp: Vec<u32>,
    fair: Vec<bool>,
    doomed: Vec<bool>,
}

/// Tarjan's algorithm, iterative, over the waiting part; components are numbered as they
/// complete, so a component's successors are numbered before it.
fn components(w: &Waiting<'_>, watch: &Watch) -> Option<Components> {
    let g = w.g;
    let n = g.len();
    let mut index = vec![NONE; n];
    let mut low = vec![0u32; n];
    let mut out = Components {
        comp: vec![NONE; n],
        fair: Vec::new(),
        doomed: Vec::new(),
    };
    let mut stack: Vec<u32> = Vec::new();
    let mut calls: Vec<(u32, usize)> = Vec::new();
    let mut members: Vec<u32> = Vec::new();
    let mut counter = 0u32;
    let mut work = 0u64;
    for root in 0..n as u32 {
        if !w.state(root) || index[root as usize] != NONE {
            continue;
        }
        index[root as usize] = counter;
        low[root as usize] = counter;
        counter += 1;
        stack.push(root);
        calls.push((root, g.edges(root).start));
        while let Some(&mut (v, ref mut pos)) = calls.last_mut() {
            work += 1;
            if work.is_multiple_of(4096) && watch.stopped().is_some() {
                return None;
            }
            let end = g.edges(v).end;
            if *pos < end {
                let e = *pos;
                *pos += 1;
                if !w.edge(e) {
                    continue;
                }
                let t = g.targets[e];
                if index[t as usize] == NONE {
                    index[t as usize] = counter;
                    low[t as usize] = counter;
                    counter += 1;
                    stack.push(t);
                    calls.push((t, g.edges(t).start));
                } else if out.comp[t as usize] == NONE {
                    low[v as usize] = low[v as usize].min(index[t as usize]);
                }
                continue;
            }
            calls.pop();
            if let Some(&(u, _)) = calls.last() {
                low[u as usize] = low[u as usize].min(low[v as usize]);
            }
            if low[v as usize] != index[v as usize] {
                continue;
            }
            let c = out.fair.len() as u32;
            members.clear();
            loop {
                let x = stack.pop().expect("v is on the stack");
                out.comp[x as usize] = c;
                members.push(x);
                if x == v {
                    break;
                }
            }
            let mut fair = false;
            let mut doomed = false;
            for &x in &members {
                doomed |= w.dead(x);
                for e in g.edges(x) {
                    if !w.edge(e) {
                        continue;
                    }
                    let d = out.comp[g.targets[e] as usize];
                    if d == c {
                        fair |= w.fair(e);
                    } else {
                        doomed |= out.doomed[d as usize];
                    }
                }
            }
            out.fair.push(fair);
            out.doomed.push(doomed || fair);
        }
    }
    Some(out)
}
