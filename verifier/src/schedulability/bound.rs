//! A task's demand per period bounded from its activities' codel automata alone, without
//! exploring states: in one period an activity runs one chain of codels, from where it
//! was released (its `start`, a `pause::` target, or `stop` when interrupted) along
//! yields that do not pause, until one pauses, ends or throws. An interrupt that comes
//! while a codel runs (in a timed model a codel takes time) or between two codels of the
//! chain sends the activity to its `stop` codel in the same period, from where the chain
//! goes on. The bound is the sum over the task's
//! activities of their longest chains, as if all ran their worst chain in the same period:
//! never below the demand the model can reach.

use bip_model::genom::map::ServiceMap;
use bip_model::GenomMap;
use petgraph::algo::toposort;
use petgraph::graph::{DiGraph, NodeIndex};

/// The bound for task `task` of module `module`, in microseconds; `None` if a chain can
/// loop without pausing (the activity could run forever in one period).
pub fn demand_bound(map: &GenomMap, module: usize, task: usize) -> Option<u64> {
    map.modules[module]
        .services
        .iter()
        .filter(|s| s.task == Some(task))
        .try_fold(0u64, |sum, s| Some(sum.saturating_add(longest_chain(s)?)))
}

/// The costliest chain of one period of `service`; `None` if a chain has a loop.
///
/// The chains run over codels paired with whether the activity is stopping: an interrupt
/// takes any codel of a running activity to `stop`, and a stopping one goes on along its
/// yields without a second interrupt sending it back.
fn longest_chain(service: &ServiceMap) -> Option<u64> {
    let codels = &service.codels;
    let n = codels.len();
    let index = |state: &str| codels.iter().position(|c| c.state == state);
    let node = |k: usize, stopping: bool| NodeIndex::new(k + if stopping { n } else { 0 });
    let stop = index("stop");
    // entries: where a period can begin
    let mut entries: Vec<NodeIndex<u32>> =
        index("start").map(|k| node(k, false)).into_iter().collect();
    entries.extend(stop.map(|k| node(k, true)));
    for c in codels {
        for y in &c.yields {
            if let Some(i) = y.target.strip_prefix("pause::").and_then(index) {
                entries.extend([node(i, false), node(i, true)]);
            }
        }
    }
    // the steps that go on in the same period; a cycle among them has no bound
    let mut graph: DiGraph<(), (), u32> = DiGraph::with_capacity(2 * n, 3 * n);
    for _ in 0..2 * n {
        graph.add_node(());
    }
    for (k, c) in codels.iter().enumerate() {
        for y in &c.yields {
            if let Some(t) = index(&y.target) {
                for stopping in [false, true] {
                    graph.update_edge(node(k, stopping), node(t, stopping), ());
                }
            }
        }
        if let Some(stop) = stop {
            graph.update_edge(node(k, false), node(stop, true), ());
        }
    }
    let order = toposort(&graph, None).ok()?;
    // the costliest chain from each node, its successors' first
    let mut cost = vec![0u64; 2 * n];
    for &v in order.iter().rev() {
        let next = graph.neighbors(v).map(|t| cost[t.index()]).max();
        let codel = &codels[v.index() % n];
        // an async codel runs apart from its task: it costs the task nothing
        let own = codel.wcet_us.filter(|_| codel.apart.is_none());
        cost[v.index()] = own.unwrap_or(0).saturating_add(next.unwrap_or(0));
    }
    Some(
        entries
            .into_iter()
            .map(|e| cost[e.index()])
            .max()
            .unwrap_or(0),
    )
}
