//! A run of the stored graph: states joined by edges, finite or a lasso, and shortest
//! paths in the graph, which counterexamples are made of.

use std::collections::VecDeque;

use super::watched::Flagged;

/// A path from the initial state: `states[k + 1]` is reached from `states[k]` by edge
/// `edges[k]`. A lasso repeats the edges after the first `loop_start` forever (its last
/// state is `states[loop_start]`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Run {
    pub(crate) states: Vec<u32>,
    pub(crate) edges: Vec<usize>,
    pub(crate) loop_start: Option<usize>,
}

impl Run {
    /// Follows edge `e` from the last state.
    pub(crate) fn push(&mut self, g: &Flagged, e: usize) {
        self.edges.push(e);
        self.states.push(g.targets[e]);
    }

    pub(crate) fn extend(&mut self, g: &Flagged, edges: &[usize]) {
        for &e in edges {
            self.push(g, e);
        }
    }

    pub(crate) fn last(&self) -> u32 {
        *self.states.last().expect("a run has a first state")
    }
}

/// The edges of a shortest path from `from` to the first state (in breadth-first order)
/// that `goal` accepts, following only the edges `follow` accepts; `None` if there is none.
pub(crate) fn shortest_path(
    g: &Flagged,
    from: u32,
    follow: impl Fn(usize) -> bool,
    goal: impl Fn(u32) -> bool,
) -> Option<Vec<usize>> {
    if goal(from) {
        return Some(Vec::new());
    }
    // the edge each reached state was first reached by, and from which state
    let mut by = vec![usize::MAX; g.len()];
    let mut prev = vec![u32::MAX; g.len()];
    let mut queue = VecDeque::from([from]);
    let mut seen = vec![false; g.len()];
    seen[from as usize] = true;
    while let Some(s) = queue.pop_front() {
        for e in g.edges(s) {
            if !follow(e) {
                continue;
            }
            let t = g.targets[e];
            if seen[t as usize] {
                continue;
            }
            seen[t as usize] = true;
            by[t as usize] = e;
            prev[t as usize] = s;
            if goal(t) {
                let mut path = vec![e];
                let mut cur = s;
                while cur != from {
                    path.push(by[cur as usize]);
                    cur = prev[cur as usize];
                }
                path.reverse();
                return Some(path);
            }
            queue.push_back(t);
        }
    }
    None
}
