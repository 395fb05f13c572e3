//! Strongly connected components of a stored state graph, or of a part of it: Tarjan's
//! algorithm, iterative (a graph of millions of states would overflow the call stack).
//! Components are numbered as they complete, so every component comes after those it
//! reaches: a pass in numbering order sees a component's successors first. Used by the
//! response properties (the states where a trigger waits) and by the exact demands (the
//! steps other than the tick).
//!
//! Written here rather than taken from petgraph, which the rest of the workspace uses for
//! its graphs: petgraph's `tarjan_scc` recurses once per state (a chain of 100,000 states
//! overflows an 8 MiB stack), and its `kosaraju_scc` needs the reverse edges, which the
//! stored graph does not keep, and a vector per component (a chain of 10^7 states took
//! 5.7 s and 825 MB with petgraph's own graph, against 16 bytes a state here). Neither
//! can stop at a limit halfway.

use super::graph::Graph;
use crate::watch::Watch;

/// The component of a state outside the part asked for.
pub(crate) const OUTSIDE: u32 = u32::MAX;

/// Edges looked at between two looks at the limits.
const EDGES_PER_LOOK: u64 = 4096;

pub(crate) struct Components {
    /// Each state's component; [`OUTSIDE`] for a state outside the part.
    pub(crate) of: Vec<u32>,
    /// The states of component `c`: `members[starts[c]..starts[c + 1]]`.
    starts: Vec<u32>,
    members: Vec<u32>,
}

impl Components {
    pub(crate) fn len(&self) -> usize {
        self.starts.len() - 1
    }

    pub(crate) fn members(&self, c: u32) -> &[u32] {
        &self.members[self.starts[c as usize] as usize..self.starts[c as usize + 1] as usize]
    }
}

/// The components of the states `state` admits, by the edges `edge` admits (an admitted
/// edge's target must be admitted too); `None` once `watch` says stop.
pub(crate) fn components<E, N>(
    g: &Graph<E, N>,
    state: impl Fn(u32) -> bool,
    edge: impl Fn(usize) -> bool,
    watch: &Watch,
) -> Option<Components> {
    let n = g.len();
    // index, low, of, members
    if !watch.expect(n as u64 * 16) {
        return None;
    }
    const UNSEEN: u32 = u32::MAX;
    let mut index = vec![UNSEEN; n];
    let mut low = vec![0u32; n];
    let mut out = Components {
        of: vec![OUTSIDE; n],
        starts: vec![0],
        members: Vec::new(),
    };
    let mut stack: Vec<u32> = Vec::new();
    // (state, next edge to look at)
    let mut calls: Vec<(u32, usize)> = Vec::new();
    let mut counter = 0u32;
    let mut work = 0u64;
    for root in 0..n as u32 {
        if !state(root) || index[root as usize] != UNSEEN {
            continue;
        }
        index[root as usize] = counter;
        low[root as usize] = counter;
        counter += 1;
        stack.push(root);
        calls.push((root, g.edges(root).start));
        while let Some(&mut (v, ref mut pos)) = calls.last_mut() {
            work += 1;
            if work.is_multiple_of(EDGES_PER_LOOK) && watch.stopped().is_some() {
                return None;
            }
            if *pos < g.edges(v).end {
                let e = *pos;
                *pos += 1;
                if !edge(e) {
                    continue;
                }
                let t = g.targets[e];
                if index[t as usize] == UNSEEN {
                    index[t as usize] = counter;
                    low[t as usize] = counter;
                    counter += 1;
                    stack.push(t);
                    calls.push((t, g.edges(t).start));
                } else if out.of[t as usize] == OUTSIDE {
                    // seen and in no component yet: on the stack
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
            let c = out.len() as u32;
            loop {
                let x = stack.pop().expect("v is on the stack");
                out.of[x as usize] = c;
                out.members.push(x);
                if x == v {
                    break;
                }
            }
            out.starts.push(out.members.len() as u32);
        }
    }
    Some(out)
}
