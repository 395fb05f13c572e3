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

/// The run to product state `x` of a search of the graph's product with an observer that
/// kept each product state's `parent` (the initial one its own): product state `y` is
/// graph state `y / width` with observer value `y % width`, and each step is the first
/// edge out of the parent's state that `leads(value, e)` says takes the observer from the
/// parent's value to the child's.
pub(crate) fn product_run(
    g: &Flagged,
    parent: &[u32],
    width: u32,
    x: u32,
    leads: impl Fn(u32, usize) -> Option<u32>,
) -> Run {
    let mut chain = vec![x];
    let mut cur = x;
    while parent[cur as usize] != cur {
        cur = parent[cur as usize];
        chain.push(cur);
    }
    chain.reverse();
    let mut run = Run {
        states: vec![chain[0] / width],
        ..Run::default()
    };
    for pair in chain.windows(2) {
        let (s, o) = (pair[0] / width, pair[0] % width);
        let (t, o2) = (pair[1] / width, pair[1] % width);
        let e = g
            .edges(s)
            .find(|&e| g.targets[e] == t && leads(o, e) == Some(o2))
            .expect("a parent reaches its child by some edge");
        run.push(g, e);
    }
    run
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
