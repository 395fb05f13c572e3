//! A task's exact demand per period: the most WCET of its codels that any run of the
//! model can pack between two ticks.
//!
//! The reachable states are explored with their steps (the graph is kept: the question is
//! about paths, not states). Each state is stored once, packed, in the verifier's visited
//! set; the graph numbers states in the order they were explored. A task's period is a path of steps other than the tick,
//! starting where a tick (or the start) left the model; its cost is the sum of the WCETs
//! of the task's codel runs on it. The longest such path is found on the graph of
//! non-tick steps condensed into strongly connected components: a component with a costly
//! step inside it is a loop the task can run forever in one period (no bound), the others
//! form a DAG, costed from its sinks up in the order Tarjan's algorithm completes them.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use bip_model::{Label, State, Steps, System};

use super::tasks::{TaskKind, TaskTable};
use crate::visited::{hash, StateId, Visited, SHARDS};

/// What the exploration may use.
#[derive(Clone, Copy, Debug)]
pub struct Limits<'a> {
    pub max_states: u64,
    pub max_bytes: u64,
    pub deadline: Option<Instant>,
    /// Raised by Ctrl-C.
    pub interrupt: Option<&'a AtomicBool>,
}

/// The exact demands, and the size of what was explored.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Exact {
    /// Per task of the table: its demand in microseconds, `None` if unbounded (a
    /// component's is its declared WCET).
    pub demands: Vec<Option<u64>>,
    pub states: u64,
    pub transitions: u64,
}

/// Label of an internal transition in the graph (it belongs to no task, and is no tick).
const INTERNAL: u32 = u32::MAX;

/// The explored graph, in compressed rows.
struct Graph {
    /// Edges of state `s`: `offsets[s]..offsets[s + 1]`.
    offsets: Vec<u32>,
    targets: Vec<u32>,
    labels: Vec<u32>,
    /// States a period starts in: the initial state and every tick's target.
    starts: Vec<u32>,
}

/// Explores `system` and computes every task's demand; `Err` says why it could not
/// (a limit, or a range error in the model).
pub fn exact_demands(
    system: &System,
    table: &TaskTable,
    limits: Limits<'_>,
) -> Result<Exact, String> {
    let tick = table.tick.ok_or("no task runs codels")?;
    let graph = explore(system, tick, limits)?;
    let states = graph.offsets.len() as u64 - 1;
    let transitions = graph.targets.len() as u64;
    let components = condense(&graph, tick);
    let demands = (0..table.tasks.len())
        .map(|t| match table.tasks[t].kind {
            TaskKind::Component { wcet_us, .. } => Some(wcet_us),
            TaskKind::Genom { .. } => longest_period(&graph, table, tick, t, &components),
        })
        .collect();
    Ok(Exact {
        demands,
        states,
        transitions,
    })
}

fn explore(system: &System, tick: u32, limits: Limits<'_>) -> Result<Graph, String> {
    let layout = &system.layout;
    // each state stored once, packed, in the visited set's arenas; explored level by
    // level, so that a state's number is its place in the order of exploration
    let mut visited = Visited::new(layout.bytes());
    let full = |_| "more states than the demand's graph can number".to_string();
    visited.start_level();
    let initial = layout.pack(&system.initial_state());
    let root = visited
        .insert(&initial, StateId::NONE)
        .map_err(full)?
        .ok_or("the visited set refused the first state")?;
    // a state's number, by shard and index in it, once it is explored
    let mut number: Vec<Vec<u32>> = vec![Vec::new(); SHARDS];
    let mut graph = Graph {
        offsets: vec![0],
        targets: Vec::new(),
        labels: Vec::new(),
        starts: Vec::new(),
    };
    let mut ticked: Vec<u32> = Vec::new();
    let mut steps = Steps::new();
    let mut state = system.initial_state();
    let mut next = State::from_slots(vec![0; system.slot_count()]);
    let mut packed = vec![0u8; layout.bytes()];
    let mut explored: u32 = 0;
    let mut level = 0;
    while visited.level_len(level) > 0 {
        visited.start_level();
        for chunk in visited.chunks(level, u32::MAX) {
            for local in chunk.start..chunk.end {
                let id = visited.id(chunk.shard, local);
                layout.decode(visited.state(id), &mut state);
                let numbers = &mut number[chunk.shard];
                if numbers.len() <= local as usize {
                    numbers.resize(local as usize + 1, u32::MAX);
                }
                numbers[local as usize] = explored;
                explored = explored
                    .checked_add(1)
                    .ok_or("more states than the demand's graph can number")?;
                system
                    .enabled_steps(&state, &mut steps)
                    .map_err(|e| format!("a range error ({e}); `bip verify` shows it"))?;
                for step in steps.iter() {
                    system
                        .fire(&state, step, &mut next)
                        .map_err(|e| format!("a range error ({e}); `bip verify` shows it"))?;
                    layout.encode(&next, &mut packed);
                    // most successors are known: look them up before inserting
                    let target = match visited.find(hash(&packed), &packed) {
                        Some(known) => known,
                        None => visited
                            .insert(&packed, id)
                            .map_err(full)?
                            .ok_or("the visited set lost a state")?,
                    };
                    let label = match step.label {
                        Label::Interaction(i) => i,
                        Label::Internal { .. } => INTERNAL,
                    };
                    if label == tick {
                        ticked.push(target.to_bits());
                    }
                    // the target's id for now: its number once every state has one
                    graph.targets.push(target.to_bits());
                    graph.labels.push(label);
                }
                graph.offsets.push(
                    u32::try_from(graph.targets.len())
                        .map_err(|_| "more transitions than the demand's graph can number")?,
                );
                if explored.is_multiple_of(4096) {
                    let used = visited.allocated_bytes()
                        + 8 * graph.targets.capacity() as u64
                        + 4 * (graph.offsets.capacity() + ticked.capacity()) as u64
                        + 4 * u64::from(explored);
                    if visited.len() > limits.max_states {
                        return Err(format!("more than {} states", limits.max_states));
                    }
                    if used > limits.max_bytes {
                        return Err(format!("more than {} bytes of graph", limits.max_bytes));
                    }
                    if limits.deadline.is_some_and(|d| Instant::now() >= d) {
                        return Err("the time limit".into());
                    }
                    if limits.interrupt.is_some_and(|i| i.load(Ordering::Relaxed)) {
                        return Err("interrupted".into());
                    }
                }
            }
        }
        level += 1;
    }
    let renumber = |bits: u32| {
        let id = StateId::from_bits(bits);
        number[id.shard()][id.local() as usize]
    };
    for t in graph.targets.iter_mut() {
        *t = renumber(*t);
    }
    graph.starts = ticked.into_iter().map(renumber).collect();
    graph.starts.push(renumber(root.to_bits()));
    graph.starts.sort_unstable();
    graph.starts.dedup();
    Ok(graph)
}

/// The strongly connected components of the graph's non-tick steps.
struct Components {
    /// Each state's component.
    of: Vec<u32>,
    /// The states of component `c`: `members[starts[c]..starts[c + 1]]`.
    starts: Vec<u32>,
    members: Vec<u32>,
}

impl Components {
    fn len(&self) -> usize {
        self.starts.len() - 1
    }

    fn members(&self, c: u32) -> &[u32] {
        &self.members[self.starts[c as usize] as usize..self.starts[c as usize + 1] as usize]
    }
}

/// Strongly connected components of the non-tick steps (iterative Tarjan). Components
/// are numbered in the order they were completed, so every component comes after those
/// it reaches.
fn condense(graph: &Graph, tick: u32) -> Components {
    let n = graph.offsets.len() - 1;
    const UNSEEN: u32 = u32::MAX;
    let mut index = vec![UNSEEN; n];
    let mut low = vec![0u32; n];
    let mut on_stack = vec![false; n];
    let mut stack: Vec<u32> = Vec::new();
    let mut scc_of = vec![0u32; n];
    let mut starts: Vec<u32> = vec![0];
    let mut members: Vec<u32> = Vec::with_capacity(n);
    let mut counter = 0u32;
    // (state, next edge to look at)
    let mut calls: Vec<(u32, u32)> = Vec::new();
    for root in 0..n as u32 {
        if index[root as usize] != UNSEEN {
            continue;
        }
        calls.push((root, graph.offsets[root as usize]));
        index[root as usize] = counter;
        low[root as usize] = counter;
        counter += 1;
        stack.push(root);
        on_stack[root as usize] = true;
        while let Some(&(v, e)) = calls.last() {
            if e < graph.offsets[v as usize + 1] {
                let edge = e as usize;
                if let Some(top) = calls.last_mut() {
                    top.1 += 1;
                }
                if graph.labels[edge] == tick {
                    continue;
                }
                let w = graph.targets[edge];
                if index[w as usize] == UNSEEN {
                    index[w as usize] = counter;
                    low[w as usize] = counter;
                    counter += 1;
                    stack.push(w);
                    on_stack[w as usize] = true;
                    calls.push((w, graph.offsets[w as usize]));
                } else if on_stack[w as usize] {
                    low[v as usize] = low[v as usize].min(index[w as usize]);
                }
                continue;
            }
            calls.pop();
            if let Some(&(parent, _)) = calls.last() {
                low[parent as usize] = low[parent as usize].min(low[v as usize]);
            }
            if low[v as usize] == index[v as usize] {
                let id = starts.len() as u32 - 1;
                while let Some(w) = stack.pop() {
                    on_stack[w as usize] = false;
                    scc_of[w as usize] = id;
                    members.push(w);
                    if w == v {
                        break;
                    }
                }
                starts.push(members.len() as u32);
            }
        }
    }
    Components {
        of: scc_of,
        starts,
        members,
    }
}

/// Task `task`'s costliest period, over every period start; `None` if unbounded.
fn longest_period(
    graph: &Graph,
    table: &TaskTable,
    tick: u32,
    task: usize,
    components: &Components,
) -> Option<u64> {
    let scc_of = &components.of;
    let cost = |edge: usize| -> u64 {
        match table.cost.get(graph.labels[edge] as usize) {
            Some(Some((t, w))) if *t == task => *w,
            _ => 0,
        }
    };
    // best[c]: the costliest path from any state of component c; None: unbounded
    let mut best: Vec<Option<u64>> = vec![Some(0); components.len()];
    for c in 0..components.len() as u32 {
        let mut here = Some(0u64);
        'states: for &v in components.members(c) {
            let v = v as usize;
            for edge in graph.offsets[v] as usize..graph.offsets[v + 1] as usize {
                if graph.labels[edge] == tick {
                    continue;
                }
                let w = cost(edge);
                let target = scc_of[graph.targets[edge] as usize];
                let through = if target == c {
                    (w == 0).then_some(0)
                } else {
                    best[target as usize].map(|b| b.saturating_add(w))
                };
                match (here, through) {
                    (Some(h), Some(t)) => here = Some(h.max(t)),
                    _ => {
                        here = None;
                        break 'states;
                    }
                }
            }
        }
        best[c as usize] = here;
    }
    graph.starts.iter().try_fold(0u64, |m, &s| {
        Some(m.max(best[scc_of[s as usize] as usize]?))
    })
}
