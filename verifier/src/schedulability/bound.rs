//! A task's demand per period bounded from its activities' codel automata alone, without
//! exploring states: in one period an activity runs one chain of codels, from where it
//! was released (its `start`, a `pause::` target, or `stop` when interrupted) along
//! yields that do not pause, until one pauses, ends or throws. The bound is the sum over
//! the task's activities of their longest chains, as if all ran their worst chain in the
//! same period: never below the demand the model can reach.

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
fn longest_chain(service: &ServiceMap) -> Option<u64> {
    let codels = &service.codels;
    let index = |state: &str| codels.iter().position(|c| c.state == state);
    // entries: where a period can begin
    let mut entries: Vec<usize> = ["start", "stop"].into_iter().filter_map(index).collect();
    for c in codels {
        for y in &c.yields {
            if let Some(i) = y.target.strip_prefix("pause::").and_then(index) {
                entries.push(i);
            }
        }
    }
    // the yields that go on in the same period; a cycle among them has no bound
    let mut graph: DiGraph<(), (), u32> = DiGraph::with_capacity(codels.len(), codels.len());
    for _ in codels {
        graph.add_node(());
    }
    for (k, c) in codels.iter().enumerate() {
        for y in &c.yields {
            if let Some(t) = index(&y.target) {
                graph.update_edge(NodeIndex::new(k), NodeIndex::new(t), ());
            }
        }
    }
    let order = toposort(&graph, None).ok()?;
    // the costliest chain from each codel, its successors' first
    let mut cost = vec![0u64; codels.len()];
    for &k in order.iter().rev() {
        let next = graph.neighbors(k).map(|t| cost[t.index()]).max();
        // an async codel runs apart from its task: it costs the task nothing
        let own = codels[k.index()]
            .wcet_us
            .filter(|_| codels[k.index()].apart.is_none());
        cost[k.index()] = own.unwrap_or(0).saturating_add(next.unwrap_or(0));
    }
    Some(entries.into_iter().map(|e| cost[e]).max().unwrap_or(0))
}
