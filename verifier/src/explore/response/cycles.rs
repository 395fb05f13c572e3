//! Unbounded response (`LeadsTo`, `Replies`, `Terminates`): a search for a run on which
//! the response never comes, on the stored graph (docs/verify.md, "Response and
//! liveness").
//!
//! After a trigger, the run waits: it stays in states where the response does not hold
//! and takes steps that are not the response. The property fails if, from a trigger, the
//! waiting part of the graph leads to a cycle that goes on forever ([`Forever`]: a tick
//! on the cycle, or its states timelocked; any cycle in a model without `Time`
//! connectors) or to a state with no step at all.
//! One pass of Tarjan's algorithm over the waiting part finds its strongly connected
//! components, successors first, and marks each *doomed* if it holds such a cycle or
//! dead end, or leads to a doomed one; a trigger into a doomed state is a counterexample.

use super::run::{shortest_path, Run};
use super::watched::{at_start, on_edge, response_bit, trigger_bit, Flagged, TICK};
use crate::explore::graph::IN_ERROR;
use crate::explore::scc::{self, OUTSIDE};
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

/// Which cycles count as runs that go on forever.
#[derive(Clone, Copy)]
pub(crate) enum Forever<'a> {
    /// Every cycle: a model without `Time` connectors assumes nothing.
    Any,
    /// Runs on which time diverges: a cycle with a tick; and a cycle of timelocked
    /// states (per state, `timelock`'s answer), where time cannot pass, so that the run
    /// stays on it for ever.
    Divergent(&'a [bool]),
    /// Only cycles of timelocked states (bounded response, whose observer sees the
    /// cycles with a tick).
    Timelocked(&'a [bool]),
}

struct Waiting<'g> {
    g: &'g Flagged,
    p: usize,
    response: u32,
    forever: Forever<'g>,
}

impl Waiting<'_> {
    fn state(&self, s: u32) -> bool {
        self.g.state_flags[s as usize] & (self.response | IN_ERROR) == 0
    }

    /// The run goes on waiting along edge `e`: it is no response (on the step or in the
    /// state it leads to) and leads to no state in range error.
    fn edge(&self, e: usize) -> bool {
        !on_edge(self.g, self.p, e).response
            && self.g.state_flags[self.g.targets[e] as usize] & IN_ERROR == 0
    }

    /// An edge out of state `s` that lets the run count as going on forever on a cycle.
    fn fair(&self, s: u32, e: usize) -> bool {
        match self.forever {
            Forever::Any => true,
            Forever::Divergent(locked) => self.g.edge_data[e] & TICK != 0 || locked[s as usize],
            Forever::Timelocked(locked) => locked[s as usize],
        }
    }

    fn dead(&self, s: u32) -> bool {
        self.g.edges(s).is_empty() && self.g.state_flags[s as usize] & IN_ERROR == 0
    }
}

/// Searches property `p` of the graph for a run that waits forever, by `forever`'s
/// cycles, or stops.
pub(crate) fn search<'g>(g: &'g Flagged, p: usize, forever: Forever<'g>, watch: &Watch) -> Found {
    let w = Waiting {
        g,
        p,
        response: response_bit(p),
        forever,
    };
    let trigger = trigger_bit(p);
    let Some(scc) = components(&w, watch) else {
        return Found::Stopped;
    };
    let doomed =
        |s: u32| scc.comp[s as usize] != OUTSIDE && scc.doomed[scc.comp[s as usize] as usize];
    // the first trigger, in the exploration's order, from which the response can be
    // avoided: a trigger happens in the initial state or on a step (counting the state it
    // leads to), and starts a wait only if the response does not happen there too
    let vacuous = !g.state_flags.iter().any(|f| f & trigger != 0)
        && !g.edge_data.iter().any(|f| f & trigger != 0);
    let mut start = None;
    if at_start(g, p).waits_after(false) && doomed(0) {
        start = Some((0, None));
    }
    'states: for s in 0..g.len() as u32 {
        if start.is_some() {
            break;
        }
        for e in g.edges(s) {
            if on_edge(g, p, e).waits_after(false) && doomed(g.targets[e]) {
                start = Some((s, Some(e)));
                break 'states;
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
    let has_fair = |t: u32| g.edges(t).any(|e| inside(e) && w.fair(t, e));
    let to_fair = shortest_path(g, entry, inside, has_fair).expect("the component has a fair edge");
    let loop_start = run.edges.len();
    run.extend(g, &to_fair);
    let fair = g
        .edges(run.last())
        .find(|&e| inside(e) && w.fair(run.last(), e))
        .expect("found by has_fair");
    run.push(g, fair);
    let back = shortest_path(g, run.last(), inside, |t| t == entry)
        .expect("a component is strongly connected");
    run.extend(g, &back);
    run.loop_start = Some(loop_start);
    Found::Fails(run)
}

/// The components of the waiting part, each marked fair (it holds a cycle that goes on
/// forever) and doomed (it holds a fair cycle or a dead end, or leads to a doomed one).
struct Components {
    /// Each state's component (`OUTSIDE` the waiting part).
    comp: Vec<u32>,
    fair: Vec<bool>,
    doomed: Vec<bool>,
}

/// The waiting part's components, marked in their numbering order, which puts a
/// component's successors before it.
fn components(w: &Waiting<'_>, watch: &Watch) -> Option<Components> {
    let g = w.g;
    let scc = scc::components(g, |s| w.state(s), |e| w.edge(e), watch)?;
    let mut fair = Vec::with_capacity(scc.len());
    let mut doomed = Vec::with_capacity(scc.len());
    for c in 0..scc.len() as u32 {
        let mut is_fair = false;
        let mut is_doomed = false;
        for &x in scc.members(c) {
            is_doomed |= w.dead(x);
            for e in g.edges(x).filter(|&e| w.edge(e)) {
                let d = scc.of[g.targets[e] as usize];
                if d == c {
                    is_fair |= w.fair(x, e);
                } else {
                    is_doomed |= doomed[d as usize];
                }
            }
        }
        fair.push(is_fair);
        doomed.push(is_doomed || is_fair);
    }
    Some(Components {
        comp: scc.of,
        fair,
        doomed,
    })
}
