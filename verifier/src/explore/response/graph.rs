//! The explored state graph, stored once the exploration is complete, for the response
//! properties: each state's successors (compressed rows), which steps are ticks, and
//! where each property's trigger and response happen, on states and on steps.
//!
//! States are numbered in the exploration's order (level by level, chunk by chunk), so a
//! smaller number is never deeper, and the numbering does not depend on the number of
//! workers. The rows are computed chunk by chunk in parallel, by the step relation.

use bip_model::{Happens, State, Steps, System};
use rayon::prelude::*;

use crate::visited::{hash, Chunk, StateId, Visited};
use crate::watch::Watch;

/// A response property's trigger and response.
pub(crate) struct Watched<'a> {
    /// What a range error in them is reported in: `property NAME`.
    pub(crate) context: String,
    pub(crate) trigger: &'a Happens,
    pub(crate) response: &'a Happens,
}

/// Flag bits: on an edge, bit 0 is a tick; on a state, bit 0 is a state in range error
/// (its steps could not be computed, or every one of them fails). Property `p`'s trigger
/// is bit `1 + 2p`, its response bit `2 + 2p`, on the steps and states where they happen.
pub(crate) const TICK: u32 = 1;
pub(crate) const IN_ERROR: u32 = 1;
/// The properties one graph can flag.
pub(crate) const MAX_WATCHED: usize = 15;

pub(crate) fn trigger_bit(p: usize) -> u32 {
    1 << (1 + 2 * p)
}

pub(crate) fn response_bit(p: usize) -> u32 {
    1 << (2 + 2 * p)
}

/// The first range error met in evaluating a property's trigger or response: in a state
/// (or on a step out of it), with the message.
pub(crate) struct EvalFailure {
    pub(crate) state: u32,
    pub(crate) message: String,
}

pub(crate) struct Graph {
    /// State `s`'s edges are `offsets[s]..offsets[s + 1]`.
    pub(crate) offsets: Vec<u64>,
    pub(crate) targets: Vec<u32>,
    pub(crate) edge_flags: Vec<u32>,
    pub(crate) state_flags: Vec<u32>,
    /// The stored state of each number.
    pub(crate) ids: Vec<StateId>,
    pub(crate) failures: Vec<Option<EvalFailure>>,
    /// The model has a `Time` connector: only runs with infinitely many ticks count.
    pub(crate) timed: bool,
}

/// One chunk's rows.
#[derive(Default)]
struct Rows {
    degrees: Vec<u32>,
    targets: Vec<u32>,
    edge_flags: Vec<u32>,
    state_flags: Vec<u32>,
    failures: Vec<Option<EvalFailure>>,
}

impl Graph {
    pub(crate) fn len(&self) -> usize {
        self.ids.len()
    }

    pub(crate) fn edges(&self, s: u32) -> std::ops::Range<usize> {
        self.offsets[s as usize] as usize..self.offsets[s as usize + 1] as usize
    }

    /// Builds the graph of the explored states, or `None` if the run must stop.
    pub(crate) fn build(
        system: &System,
        visited: &Visited,
        watched: &[Watched<'_>],
        watch: &Watch,
    ) -> Option<Graph> {
        let mut chunks: Vec<Chunk> = Vec::new();
        for level in 0..visited.levels() {
            chunks.extend(visited.chunks(level, 1024));
        }
        let n = visited.len() as usize;
        // the numbers of the states, by shard and index
        let mut number: Vec<Vec<u32>> = (0..crate::visited::SHARDS).map(|_| Vec::new()).collect();
        let mut ids = Vec::with_capacity(n);
        if !watch.expect(n as u64 * 12) {
            return None;
        }
        for c in &chunks {
            let v = &mut number[c.shard];
            if v.len() < c.end as usize {
                v.resize(c.end as usize, u32::MAX);
            }
            for local in c.start..c.end {
                v[local as usize] = ids.len() as u32;
                ids.push(visited.id(c.shard, local));
            }
        }
        let mut starts = Vec::with_capacity(chunks.len());
        let mut at = 0u32;
        for c in &chunks {
            starts.push(at);
            at += c.end - c.start;
        }
        let rows: Vec<Option<Rows>> = chunks
            .par_iter()
            .zip(starts.par_iter())
            .map_init(
                || (system.initial_state(), system.initial_state(), Steps::new()),
                |(state, next, steps), (chunk, &first)| {
                    rows_of(
                        system, visited, &number, watched, watch, *chunk, first, state, next, steps,
                    )
                },
            )
            .collect();
        let rows = rows.into_iter().collect::<Option<Vec<Rows>>>()?;
        let edges: usize = rows.iter().map(|r| r.targets.len()).sum();
        if !watch.expect(edges as u64 * 8) {
            return None;
        }
        let mut g = Graph {
            offsets: Vec::with_capacity(n + 1),
            targets: Vec::with_capacity(edges),
            edge_flags: Vec::with_capacity(edges),
            state_flags: Vec::with_capacity(n),
            ids,
            failures: (0..watched.len()).map(|_| None).collect(),
            timed: system.has_time(),
        };
        g.offsets.push(0);
        for r in rows {
            for d in &r.degrees {
                let last = *g.offsets.last().unwrap_or(&0);
                g.offsets.push(last + u64::from(*d));
            }
            g.targets.extend_from_slice(&r.targets);
            g.edge_flags.extend_from_slice(&r.edge_flags);
            g.state_flags.extend_from_slice(&r.state_flags);
            for (mine, theirs) in g.failures.iter_mut().zip(r.failures) {
                if mine.is_none() {
                    *mine = theirs;
                }
            }
        }
        Some(g)
    }
}

#[allow(clippy::too_many_arguments)]
fn rows_of(
    system: &System,
    visited: &Visited,
    number: &[Vec<u32>],
    watched: &[Watched<'_>],
    watch: &Watch,
    chunk: Chunk,
    first: u32,
    state: &mut State,
    next: &mut State,
    steps: &mut Steps,
) -> Option<Rows> {
    let layout = &system.layout;
    let mut rows = Rows {
        failures: (0..watched.len()).map(|_| None).collect(),
        ..Rows::default()
    };
    let mut packed = vec![0u8; layout.bytes()];
    for (k, local) in (chunk.start..chunk.end).enumerate() {
        if k.is_multiple_of(64) && watch.stopped().is_some() {
            return None;
        }
        let me = first + k as u32;
        let current = visited.state(visited.id(chunk.shard, local));
        layout.decode(current, state);
        let mut flags = 0u32;
        for (p, w) in watched.iter().enumerate() {
            for (bit, h) in [(trigger_bit(p), w.trigger), (response_bit(p), w.response)] {
                match system.happens_in(h, state, &w.context) {
                    Ok(true) => flags |= bit,
                    Ok(false) => {}
                    Err(e) => fail(&mut rows.failures[p], me, e.to_string()),
                }
            }
        }
        let before = rows.targets.len();
        if system.enabled_steps(state, steps).is_err() {
            flags |= IN_ERROR;
        } else {
            let mut fired = 0usize;
            for step in steps.iter() {
                if system.fire(state, step, next).is_err() {
                    continue;
                }
                fired += 1;
                layout.encode(next, &mut packed);
                let Some(id) = visited.find(hash(&packed), &packed) else {
                    // every successor of a state of a complete exploration is stored
                    return None;
                };
                let to = number[id.shard()][id.local() as usize];
                let mut e = if system.role(step.label) == bip_model::Role::Time {
                    TICK
                } else {
                    0
                };
                for (p, w) in watched.iter().enumerate() {
                    for (bit, h) in [(trigger_bit(p), w.trigger), (response_bit(p), w.response)] {
                        match system.happens_on(h, state, step, next, &w.context) {
                            Ok(true) => e |= bit,
                            Ok(false) => {}
                            Err(err) => fail(&mut rows.failures[p], me, err.to_string()),
                        }
                    }
                }
                rows.targets.push(to);
                rows.edge_flags.push(e);
            }
            if fired == 0 && !steps.is_empty() {
                flags |= IN_ERROR;
            }
        }
        rows.degrees.push((rows.targets.len() - before) as u32);
        rows.state_flags.push(flags);
    }
    Some(rows)
}

fn fail(slot: &mut Option<EvalFailure>, state: u32, message: String) {
    if slot.is_none() {
        *slot = Some(EvalFailure { state, message });
    }
}
