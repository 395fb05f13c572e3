//! Bounded response (`Response`, `Replies(within)`): a breadth-first search of the
//! product of the stored graph with an observer that counts the time units since the
//! oldest trigger not yet answered, each tick its `advance` (docs/verify.md, "Response and
//! liveness"). The first product state found that takes a tick past the bound, or stops
//! with a trigger unanswered, ends a shortest counterexample.

use super::run::{product_run, Run};
use super::watched::{at_start, on_edge, trigger_bit, units, Flagged, TICK};
use crate::explore::graph::IN_ERROR;
use crate::watch::Watch;

/// What the search found.
pub(crate) enum Found {
    Holds {
        vacuous: bool,
    },
    Fails(Run),
    /// The product would not fit (more states than can be numbered, or the memory limit).
    TooLarge,
    Stopped,
}

/// The observer: 0 when no trigger waits, `c + 1` when the oldest waiting trigger came
/// `c` time units ago (`c <= within`).
struct Observer<'g> {
    g: &'g Flagged,
    p: usize,
    within: u64,
}

/// What a step does to the observer.
enum Next {
    To(u32),
    /// The step is a tick past the bound.
    Late,
}

impl Observer<'_> {
    fn initial(&self) -> u32 {
        u32::from(at_start(self.g, self.p).waits_after(false))
    }

    /// From observer value `o`, along edge `e`.
    fn next(&self, o: u32, e: usize) -> Next {
        let mut o = o;
        if o > 0 && self.g.edge_data[e] & TICK != 0 {
            let after = u64::from(o - 1) + u64::from(units(self.g, e));
            if after > self.within {
                return Next::Late;
            }
            // at most `within`, which the product's width holds
            o = after as u32 + 1;
        }
        let h = on_edge(self.g, self.p, e);
        if !h.waits_after(o > 0) {
            Next::To(0)
        } else if h.starts_wait(o > 0) {
            Next::To(1)
        } else {
            Next::To(o)
        }
    }
}

/// Searches property `p`, which must answer within `within` time units.
pub(crate) fn search(g: &Flagged, p: usize, within: u64, watch: &Watch) -> Found {
    let obs = Observer { g, p, within };
    let trigger = trigger_bit(p);
    let vacuous = !g.state_flags.iter().any(|f| f & trigger != 0)
        && !g.edge_data.iter().any(|f| f & trigger != 0);
    if vacuous {
        return Found::Holds { vacuous };
    }
    let width = within.saturating_add(2);
    let size = (g.len() as u64).checked_mul(width);
    let Some(size) = size.filter(|&s| s < u64::from(u32::MAX)) else {
        return Found::TooLarge;
    };
    if watch.stopped().is_some() {
        return Found::Stopped;
    }
    if !watch.expect(size * 4) {
        // the memory limit is raised: the run stops here
        return Found::TooLarge;
    }
    let width = width as u32;
    // each reached product state's parent (itself for the initial one)
    let mut parent = vec![u32::MAX; size as usize];
    let start = obs.initial();
    parent[start as usize] = start;
    let mut level = vec![start];
    let mut next_level = Vec::new();
    let mut work = 0u64;
    while !level.is_empty() {
        for &x in &level {
            work += 1;
            if work.is_multiple_of(4096) && watch.stopped().is_some() {
                return Found::Stopped;
            }
            let (s, o) = (x / width, x % width);
            let edges = g.edges(s);
            if o > 0 && edges.is_empty() && g.state_flags[s as usize] & IN_ERROR == 0 {
                return Found::Fails(run_to(g, &parent, width, x, &obs));
            }
            for e in edges {
                let t = g.targets[e];
                match obs.next(o, e) {
                    Next::Late => {
                        let mut run = run_to(g, &parent, width, x, &obs);
                        run.push(g, e);
                        return Found::Fails(run);
                    }
                    Next::To(o2) => {
                        let y = t * width + o2;
                        if parent[y as usize] == u32::MAX {
                            parent[y as usize] = x;
                            next_level.push(y);
                        }
                    }
                }
            }
        }
        std::mem::swap(&mut level, &mut next_level);
        next_level.clear();
    }
    Found::Holds { vacuous: false }
}

/// The run to product state `x`, following parents.
fn run_to(g: &Flagged, parent: &[u32], width: u32, x: u32, obs: &Observer) -> Run {
    product_run(g, parent, width, x, |o, e| match obs.next(o, e) {
        Next::To(v) => Some(v),
        Next::Late => None,
    })
}
