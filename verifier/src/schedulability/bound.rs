//! A task's demand per period bounded from its activities' codel automata alone, without
//! exploring states: in one period an activity runs one chain of codels, from where it
//! was released (its `start`, a `pause::` target, or `stop` when interrupted) along
//! yields that do not pause, until one pauses, ends or throws. The bound is the sum over
//! the task's activities of their longest chains, as if all ran their worst chain in the
//! same period: never below the demand the model can reach.

use bip_model::genom::map::{CodelMap, ServiceMap};
use bip_model::GenomMap;

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
    let mut memo: Vec<Walk> = vec![Walk::New; codels.len()];
    entries
        .into_iter()
        .try_fold(0u64, |best, e| Some(best.max(chain(codels, e, &mut memo)?)))
}

#[derive(Clone, Copy)]
enum Walk {
    New,
    OnPath,
    Done(u64),
}

/// The costliest chain from codel `at` (depth-first; the automata are small).
fn chain(codels: &[CodelMap], at: usize, memo: &mut [Walk]) -> Option<u64> {
    match memo[at] {
        Walk::Done(cost) => return Some(cost),
        Walk::OnPath => return None,
        Walk::New => {}
    }
    memo[at] = Walk::OnPath;
    let mut next = 0u64;
    for y in &codels[at].yields {
        let target = y.target.as_str();
        if target == "ether" || target.starts_with("pause::") {
            continue;
        }
        if let Some(i) = codels.iter().position(|c| c.state == target) {
            next = next.max(chain(codels, i, memo)?);
        }
    }
    let cost = codels[at].wcet_us.unwrap_or(0).saturating_add(next);
    memo[at] = Walk::Done(cost);
    Some(cost)
}
