//! An activity's codel automaton: its codels, their yields, writes, ids and exceptions,
//! the places it runs from, and the checks on its graph (`stop` reaches `ether`, every
//! codel is reached), GenoM3's. An activity that cannot end from `start` (a service that
//! runs until interrupted) and a loop of plain yields (which runs while time cannot pass)
//! are accepted, as GenoM3 accepts them: the verifier shows where they lead.

use super::{Codel, Service, Yield, ACTIVITY_PORTS, ETHER, MAX_IDS_VALUES, PAUSE};
use crate::compile::{check_name, one_of, unique};
use crate::diag::{Errors, ModelError};
use crate::syntax::ServiceDef;
use petgraph::graph::{DiGraph, NodeIndex};
use petgraph::visit::Dfs;

/// Checks an activity's codel automaton and fills in its codels and locations.
pub(super) fn codels<'d>(
    errors: &mut Errors,
    ports: &[&str],
    ids: &[(&str, Option<(i64, i64)>)],
    s: &'d ServiceDef,
    out: &mut Service<'d>,
) {
    let before = errors.list.len();
    unique(errors, s.codels.iter().map(|c| &c.state), "codel state");
    let states: Vec<&str> = s.codels.iter().map(|c| c.state.as_str()).collect();
    let state_index = |name: &str| states.iter().position(|&x| x == name);
    for c in &s.codels {
        if !check_name(errors, &c.state, "codel state") {
            continue;
        }
        let n = c.state.as_str();
        if n == ETHER {
            errors.push(
                ModelError::new("`ether` is the final state; it has no codel", c.state.span)
                    .with_help("yield `ether` to end the activity"),
            );
        } else if ACTIVITY_PORTS.contains(&n) {
            errors.push(
                ModelError::new(format!("a codel state cannot be named `{n}`"), c.state.span)
                    .with_help(format!(
                        "`{n}` names a port of the activity's generated atom (docs/genom.md)"
                    )),
            );
        } else if let Some(base) = n.strip_suffix("_fail") {
            if s.codels.iter().any(|o| o.state.as_str() == base) {
                errors.push(
                    ModelError::new(format!("a codel state cannot be named `{n}`"), c.state.span)
                        .with_help(format!("`{n}` names the error port of codel `{base}`")),
                );
            }
        }
    }
    // a task's machine may have only a `stop` codel (GenoM3 runs it at shutdown)
    if state_index("start").is_none() && !s.machine {
        errors.push(
            ModelError::new(
                format!("activity `{}` has no `start` codel", s.name),
                s.name.span,
            )
            .with_help("every activity begins at its `start` codel state"),
        );
    }
    for c in &s.codels {
        let mut yields = Vec::new();
        if c.yields.is_empty() {
            errors.push(
                ModelError::new(format!("codel `{}` yields nothing", c.state), c.state.span)
                    .with_help(
                        "list the states it may go to, e.g. `yields: [\"pause::main\", \"ether\"]`",
                    ),
            );
        }
        unique(errors, c.yields.iter(), "yield");
        for y in &c.yields {
            let (paused, target) = match y.as_str().strip_prefix(PAUSE) {
                Some(t) => (true, t),
                None => (false, y.as_str()),
            };
            if target == ETHER {
                if paused {
                    errors.push(
                        ModelError::new("`pause::ether` is not a yield", y.span)
                            .with_help("an activity ends at once: yield `ether`"),
                    );
                } else {
                    yields.push(Yield::Ether);
                }
                continue;
            }
            match state_index(target) {
                Some(k) => yields.push(if paused { Yield::Pause(k) } else { Yield::Go(k) }),
                None => errors.push(
                    ModelError::new(
                        format!(
                            "codel `{}` yields to `{target}`, which is not a codel state of `{}`",
                            c.state, s.name
                        ),
                        y.span,
                    )
                    .with_label("undeclared state")
                    .with_help(one_of(
                        "yield `ether`, a codel state or `pause::` and a codel state; the codel states are",
                        states.iter().copied(),
                    )),
                ),
            }
        }
        let mut writes = Vec::new();
        let mut written_ids = Vec::new();
        let mut combinations: u128 = 1;
        unique(errors, c.writes.iter(), "written port or ids field");
        for w in &c.writes {
            let port = ports.iter().position(|&p| p == w.as_str());
            let field = ids.iter().position(|&(x, _)| x == w.as_str());
            match (port, field) {
                (Some(_), Some(_)) => errors.push(
                    ModelError::new(
                        format!("`{w}` is both an out port and an ids field of the module"),
                        w.span,
                    )
                    .with_help("rename one of them: `writes` would not say which it writes"),
                ),
                (Some(k), None) => {
                    if !writes.contains(&k) {
                        writes.push(k);
                    }
                }
                (None, Some(k)) => {
                    if written_ids.contains(&k) {
                        continue;
                    }
                    written_ids.push(k);
                    if let Some((lo, hi)) = ids[k].1 {
                        // a full 64-bit range has 2^64 values: count in 128 bits
                        let values = u128::try_from(i128::from(hi) - i128::from(lo) + 1)
                            .unwrap_or(0)
                            .max(1);
                        combinations = combinations.saturating_mul(values);
                        if combinations > MAX_IDS_VALUES {
                            errors.push(
                                ModelError::new(
                                    format!(
                                        "codel `{}` may write {combinations} combinations of ids values; at most {MAX_IDS_VALUES}",
                                        c.state
                                    ),
                                    w.span,
                                )
                                .with_label("here the count passes the limit")
                                .with_help("a codel's step takes every value its written ids may hold, so that the verifier covers them all: narrow the ranges, or write fewer fields"),
                            );
                        }
                    }
                }
                (None, None) => errors.push(
                    ModelError::new(
                        format!("the module has no out port or ids field `{w}`"),
                        w.span,
                    )
                    .with_help(one_of(
                        "its ports and ids fields are",
                        ports.iter().copied().chain(ids.iter().map(|&(x, _)| x)),
                    )),
                ),
            }
        }
        written_ids.sort_unstable();
        // a used name is a lock, never written in an expression: an imported ids member
        // may be called what the expression language reserves (`count`)
        unique(errors, c.uses.iter(), "used ids member or port");
        unique(errors, c.throws.iter(), "exception");
        for t in &c.throws {
            check_name(errors, t, "exception");
        }
        out.codels.push(Codel {
            def: c,
            state: c.state.as_str(),
            yields,
            writes,
            ids: written_ids,
            throws: c.throws.iter().map(|t| t.as_str()).collect(),
        });
    }
    if errors.list.len() > before {
        return; // the graph checks need every yield resolved
    }
    out.stop = state_index("stop");
    let mut locations: Vec<usize> = Vec::new();
    for c in &out.codels {
        for y in &c.yields {
            if let Yield::Go(k) | Yield::Pause(k) = *y {
                if !locations.contains(&k) {
                    locations.push(k);
                }
            }
        }
    }
    // an async codel's activity stays at its state while the codel runs apart
    let running_apart = out
        .codels
        .iter()
        .enumerate()
        .filter(|(_, c)| c.def.asynchronous)
        .map(|(k, _)| k);
    for k in out.stop.into_iter().chain(running_apart) {
        if !locations.contains(&k) {
            locations.push(k);
        }
    }
    locations.sort_unstable();
    out.locations = locations;
    paths(errors, s, out);
}

/// The checks on the codel graph: `stop` → `ether` (an interrupted activity must end) and
/// every codel reached from `start` or `stop`.
fn paths(errors: &mut Errors, s: &ServiceDef, out: &Service<'_>) {
    let n = out.codels.len();
    // the codels, then `ether`
    let ether = NodeIndex::new(n);
    let mut graph: DiGraph<(), (), u32> = DiGraph::with_capacity(n + 1, n);
    for _ in 0..=n {
        graph.add_node(());
    }
    for (k, c) in out.codels.iter().enumerate() {
        for y in &c.yields {
            let target = match *y {
                Yield::Go(t) | Yield::Pause(t) => NodeIndex::new(t),
                Yield::Ether => ether,
            };
            graph.update_edge(NodeIndex::new(k), target, ());
        }
    }
    let reach = |from: usize| -> Vec<bool> {
        let mut seen = vec![false; n + 1];
        let mut dfs = Dfs::new(&graph, NodeIndex::new(from));
        while let Some(k) = dfs.next(&graph) {
            seen[k.index()] = true;
        }
        seen
    };
    let mut reached = vec![false; n];
    for root in ["start", "stop"] {
        let Some(k) = out.codel(root) else { continue };
        let seen = reach(k);
        if root == "stop" && !seen[ether.index()] {
            errors.push(
                ModelError::new(
                    format!(
                        "no path from `{root}` to `ether` in {} `{}`",
                        if s.machine {
                            "the machine of task"
                        } else {
                            "activity"
                        },
                        s.name
                    ),
                    out.codels[k].def.state.span,
                )
                .with_label("the activity could never end from here")
                .with_help("some codel reachable from here must yield `ether`"),
            );
        }
        for (r, x) in reached.iter_mut().zip(seen) {
            *r |= x;
        }
    }
    for (k, c) in out.codels.iter().enumerate() {
        if !reached[k] {
            errors.push(
                ModelError::new(
                    format!(
                        "codel `{}` is never reached from `start` or `stop`",
                        c.state
                    ),
                    c.def.state.span,
                )
                .with_help("no codel yields to it; remove it or yield to it"),
            );
        }
    }
}
