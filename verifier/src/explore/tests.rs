//! The state graph and the worst responses recorded during the exploration, against
//! what the passes they replace computed from the stored states: each state expanded
//! again on its own into its row of the graph, and each state read again for the tasks'
//! figures. With one worker or three, and with a state limit that makes batches stop
//! and start again (their rows are written twice), the recording is the same.

use std::collections::HashMap;

use bip_lang::load_str;
use bip_model::{Steps, System};

use super::graph::{Keep, IN_ERROR};
use super::response::watched::Flagged;
use super::targets::{counts_units, targets, watched, watching};
use super::worst::{read_states, Seen};
use super::{workers, Explorer};
use crate::options::Options;
use crate::visited::Visited;
use crate::watch::Watch;

/// The timed GenoM layer of the robots' tests, with two response properties: every
/// question of a timed model is asked (time progress, the responses, the worst
/// responses).
fn timed() -> System {
    let text = include_str!("../../../robots/tests/timed.ron").replace(
        "    time: Exact,\n",
        "    time: Exact,\n    properties: [Replies(service: \"nav.Log\"), \
         Replies(name: \"log_soon\", service: \"nav.Log\", within: 6)],\n",
    );
    load_str("timed.ron", &text).expect("the model loads")
}

/// What an exploration recorded: the graph, the tasks' figures, and the states.
struct Recorded {
    graph: Flagged,
    seen: Vec<Seen>,
    visited: Visited,
}

fn record(system: &System, jobs: usize, max_states: Option<u64>) -> Recorded {
    let options = Options {
        jobs,
        max_states,
        ..Options::default()
    };
    let (pool, jobs) = workers(&options).expect("the workers start");
    let watch = Watch::new(&options, None);
    let targets = targets(system);
    let watched = watched(&targets);
    let watching = watching(system, &targets, &watched);
    pool.install(|| {
        let mut explorer = Explorer::new(system, &options, jobs, &watch, targets, Some(&watching));
        let stopped = explorer.explore(&|_| {}).expect("the exploration runs");
        assert!(stopped.is_none(), "the exploration completes: {stopped:?}");
        let recorder = explorer.recorder.take().expect("the graph is recorded");
        let graph = recorder
            .finish(&explorer.visited, &watch)
            .expect("every successor is recorded");
        Recorded {
            graph,
            seen: explorer.seen.expect("every state's steps are computed"),
            visited: explorer.visited,
        }
    })
}

/// Checks `r` against each stored state expanded again, in the exploration's order.
fn check_against_the_stored_states(system: &System, r: &Recorded) {
    let g = &r.graph;
    let visited = &r.visited;
    assert_eq!(g.len() as u64, visited.len());
    // numbered level by level, chunk by chunk
    let order: Vec<_> = (0..visited.levels())
        .flat_map(|l| visited.chunks(l, u32::MAX))
        .flat_map(|c| (c.start..c.end).map(move |local| visited.id(c.shard, local)))
        .collect();
    assert_eq!(g.ids, order);
    let number: HashMap<_, u32> = g
        .ids
        .iter()
        .enumerate()
        .map(|(n, &id)| (id, n as u32))
        .collect();
    let targets = targets(system);
    let watched = watched(&targets);
    let keep = watching(system, &targets, &watched);
    let mut notes = keep.notes();
    let (mut state, mut next, mut steps) =
        (system.initial_state(), system.initial_state(), Steps::new());
    let mut edges = 0usize;
    for (n, &id) in g.ids.iter().enumerate() {
        let me = n as u32;
        system.layout.decode(visited.state(id), &mut state);
        let mut flags = keep.state(&state, me, &mut notes);
        let mut row = Vec::new();
        if system.enabled_steps(&state, &mut steps).is_err() {
            flags |= IN_ERROR;
        } else {
            for step in steps.iter() {
                if system.fire(&state, step, &mut next).is_err() {
                    continue;
                }
                let to = visited
                    .find(
                        crate::visited::hash(&system.layout.pack(&next)),
                        &system.layout.pack(&next),
                    )
                    .expect("a successor is stored");
                row.push((number[&to], keep.edge(&state, step, &next, me, &mut notes)));
            }
            if row.is_empty() && !steps.is_empty() {
                flags |= IN_ERROR;
            }
        }
        let recorded: Vec<(u32, u32)> = g
            .edges(me)
            .map(|e| (g.targets[e], g.edge_data[e]))
            .collect();
        assert_eq!(recorded, row, "the row of state {n}");
        assert_eq!(g.state_flags[n], flags, "the flags of state {n}");
        edges += row.len();
    }
    assert_eq!(g.targets.len(), edges);
    assert_eq!(g.notes.units, notes.units, "the ticks' time units");
    assert!(g.notes.failures.iter().all(Option::is_none));
    let tasks = super::worst::Tasks::of(system);
    let read = read_states(system, visited, &tasks).expect("the states are read");
    assert_eq!(r.seen, read, "the tasks' figures");
}

/// Checks the recording of `system` by one worker, then by three, and with a state
/// limit of `states + 1..=states + 2`, against the stored states.
fn check(system: &System) {
    let one = record(system, 1, None);
    check_against_the_stored_states(system, &one);
    let states = one.visited.len();
    let limits = [None, Some(states + 1), Some(states + 2)];
    for (jobs, limit) in [1, 3].into_iter().flat_map(|j| limits.map(|l| (j, l))) {
        let other = record(system, jobs, limit);
        check_against_the_stored_states(system, &other);
        let name = format!("{jobs} workers, limit {limit:?}");
        assert_eq!(other.graph.ids, one.graph.ids, "{name}");
        assert_eq!(other.graph.offsets, one.graph.offsets, "{name}");
        assert_eq!(other.graph.targets, one.graph.targets, "{name}");
        assert_eq!(other.graph.edge_data, one.graph.edge_data, "{name}");
    }
}

#[test]
fn a_timed_models_recorded_graph_and_figures_are_those_of_its_stored_states() {
    let system = timed();
    assert!(system.has_time() && !super::worst::Tasks::of(&system).is_empty());
    assert!(
        counts_units(&system, &targets(&system)),
        "the ticks' units are noted"
    );
    check(&system);
}

/// The philosophers' 11 states are found in one batch whose candidates, duplicates
/// mostly, pass the room a limit of 12 or 13 leaves: the batch stops and is expanded
/// again, its rows written anew.
#[test]
fn a_batch_expanded_again_records_its_rows_once() {
    let text = include_str!("../../../robots/philosophers-atomic.ron");
    check(&load_str("philosophers-atomic.ron", text).expect("the model loads"));
}
