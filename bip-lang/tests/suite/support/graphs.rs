//! The reachable graph of a naive interpreter or of an expanded system, for the property
//! tests that compare the two.

use std::collections::{BTreeSet, HashSet, VecDeque};
use std::hash::Hash;

/// Every step reachable from `first`, breadth first: `steps(s)` lists the steps out of `s`
/// as (label, next state), and each state is shown in the graph as `view(s)`.
pub fn reachable_graph<S, L, V>(
    first: S,
    mut steps: impl FnMut(&S) -> Vec<(L, S)>,
    mut view: impl FnMut(&S) -> V,
) -> BTreeSet<(V, L, V)>
where
    S: Clone + Eq + Hash,
    L: Ord,
    V: Ord,
{
    let mut seen = HashSet::from([first.clone()]);
    let mut queue = VecDeque::from([first]);
    let mut out = BTreeSet::new();
    while let Some(s) = queue.pop_front() {
        for (label, next) in steps(&s) {
            out.insert((view(&s), label, view(&next)));
            if seen.insert(next.clone()) {
                queue.push_back(next);
            }
        }
    }
    out
}

#[test]
fn the_reachable_graph_has_every_reachable_step_once() {
    // 0 -> 1 -> 2 -> 0 and 2 -> 3, with 4 unreachable; states shown by their parity
    let next = |&s: &u32| -> Vec<(char, u32)> {
        match s {
            0 => vec![('a', 1)],
            1 => vec![('b', 2)],
            2 => vec![('c', 0), ('d', 3)],
            4 => vec![('e', 0)],
            _ => vec![],
        }
    };
    let graph = reachable_graph(0u32, next, |&s| s % 2);
    let want = BTreeSet::from([(0, 'a', 1), (1, 'b', 0), (0, 'c', 0), (0, 'd', 1)]);
    assert_eq!(graph, want);
}

/// The expanded system's graph `got` against the reference's `want`, for the model `text`:
/// equal, and not vacuously (time passes in it, by a step labelled `tick`); on a
/// difference, the first few steps each has that the other has not.
pub fn same_graph<V: Ord + std::fmt::Debug>(
    got: &BTreeSet<(V, String, V)>,
    want: &BTreeSet<(V, String, V)>,
    text: &str,
) -> Result<(), proptest::test_runner::TestCaseError> {
    proptest::prop_assert!(
        got.iter().any(|(_, label, _)| label == "tick"),
        "no tick: {}",
        text
    );
    let extra: Vec<_> = got.difference(want).take(3).collect();
    let missing: Vec<_> = want.difference(got).take(3).collect();
    proptest::prop_assert!(
        extra.is_empty() && missing.is_empty(),
        "steps the reference does not take: {:?}\nsteps the system lacks: {:?}\n{}",
        extra,
        missing,
        text
    );
    Ok(())
}
