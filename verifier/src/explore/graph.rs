//! The explored state graph, stored once the exploration is complete, for the questions
//! about paths: each state's successors (compressed rows), with what the asker keeps of
//! each state and each step ([`Keep`]): the response properties where their triggers and
//! responses happen, the scheduling analysis each step's interaction.
//!
//! States are numbered in the exploration's order (level by level, chunk by chunk), so a
//! smaller number is never deeper, and the numbering does not depend on the number of
//! workers. The rows are computed by the step relation, chunk by chunk in parallel, in
//! batches appended in chunk order: only one batch's rows are ever held twice.

use bip_model::{State, Step, Steps, System};
use rayon::prelude::*;

use crate::visited::{hash, Chunk, StateId, Visited, SHARDS};
use crate::watch::Watch;

/// On a state, bit 0 of its flags: a state in range error (its steps could not be
/// computed, or every one of them fails). The other bits are the asker's.
pub(crate) const IN_ERROR: u32 = 1;

/// States per chunk of the rows' computation.
const CHUNK_STATES: u32 = 1024;
/// Chunks per worker in one batch.
const CHUNKS_PER_WORKER: usize = 8;
/// States a worker handles between two looks at the limits.
const STATES_PER_LOOK: usize = 64;

/// What a graph keeps of each state and each step, computed by the workers as they
/// compute the rows.
pub(crate) trait Keep: Sync {
    /// What is kept of a step.
    type Edge: Copy + Send;
    /// What the states and steps note besides (such as the first error met): one per
    /// chunk, merged in chunk order.
    type Notes: Send;

    fn notes(&self) -> Self::Notes;

    /// The flag bits of state `me` (bit 0 is [`IN_ERROR`]'s).
    fn state(&self, state: &State, me: u32, notes: &mut Self::Notes) -> u32;

    /// What is kept of `step`, which leads from state `me` to `next`.
    fn edge(
        &self,
        state: &State,
        step: Step<'_>,
        next: &State,
        me: u32,
        notes: &mut Self::Notes,
    ) -> Self::Edge;

    /// Adds the notes of a later chunk to those of the chunks before it.
    fn merge(&self, notes: &mut Self::Notes, later: Self::Notes);
}

pub(crate) struct Graph<E, N = ()> {
    /// State `s`'s edges are `offsets[s]..offsets[s + 1]`.
    pub(crate) offsets: Vec<u64>,
    pub(crate) targets: Vec<u32>,
    /// What was kept of each edge.
    pub(crate) edge_data: Vec<E>,
    pub(crate) state_flags: Vec<u32>,
    /// The stored state of each number.
    pub(crate) ids: Vec<StateId>,
    pub(crate) notes: N,
}

/// One chunk's rows.
struct Rows<E, N> {
    degrees: Vec<u32>,
    targets: Vec<u32>,
    edge_data: Vec<E>,
    state_flags: Vec<u32>,
    notes: N,
}

impl<E, N> Graph<E, N> {
    pub(crate) fn len(&self) -> usize {
        self.ids.len()
    }

    pub(crate) fn edges(&self, s: u32) -> std::ops::Range<usize> {
        self.offsets[s as usize] as usize..self.offsets[s as usize + 1] as usize
    }
}

/// Builds the graph of the states of a complete exploration, keeping what `keep` says;
/// `None` if the run must stop (a limit of `watch`), or if a successor is not stored.
pub(crate) fn build<K: Keep>(
    system: &System,
    visited: &Visited,
    keep: &K,
    watch: &Watch,
) -> Option<Graph<K::Edge, K::Notes>> {
    let mut chunks: Vec<Chunk> = Vec::new();
    for level in 0..visited.levels() {
        chunks.extend(visited.chunks(level, CHUNK_STATES));
    }
    let n = visited.len() as usize;
    // the numbers of the states, by shard and index
    let mut number: Vec<Vec<u32>> = (0..SHARDS).map(|_| Vec::new()).collect();
    // per state its number, id, offset and flags
    if !watch.expect(n as u64 * 20) {
        return None;
    }
    let mut ids = Vec::with_capacity(n);
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
    let mut g = Graph {
        offsets: Vec::with_capacity(n + 1),
        targets: Vec::new(),
        edge_data: Vec::new(),
        state_flags: Vec::with_capacity(n),
        ids,
        notes: keep.notes(),
    };
    g.offsets.push(0);
    let edge_bytes = (4 + std::mem::size_of::<K::Edge>()) as u64;
    let batch = rayon::current_num_threads().max(1) * CHUNKS_PER_WORKER;
    let mut first = 0u32;
    for group in chunks.chunks(batch) {
        let mut starts = Vec::with_capacity(group.len());
        for c in group {
            starts.push(first);
            first += c.end - c.start;
        }
        let rows: Vec<Option<Rows<K::Edge, K::Notes>>> = group
            .par_iter()
            .zip(starts.par_iter())
            .map_init(
                || (system.initial_state(), system.initial_state(), Steps::new()),
                |(state, next, steps), (chunk, &first)| {
                    rows_of(
                        system, visited, &number, keep, watch, *chunk, first, state, next, steps,
                    )
                },
            )
            .collect();
        let rows = rows.into_iter().collect::<Option<Vec<_>>>()?;
        let edges: usize = rows.iter().map(|r| r.targets.len()).sum();
        // the rows' copy in the graph
        if !watch.expect(edges as u64 * edge_bytes) {
            return None;
        }
        for r in rows {
            for d in &r.degrees {
                let last = *g.offsets.last().unwrap_or(&0);
                g.offsets.push(last + u64::from(*d));
            }
            g.targets.extend_from_slice(&r.targets);
            g.edge_data.extend_from_slice(&r.edge_data);
            g.state_flags.extend_from_slice(&r.state_flags);
            keep.merge(&mut g.notes, r.notes);
        }
    }
    Some(g)
}

#[allow(clippy::too_many_arguments)]
fn rows_of<K: Keep>(
    system: &System,
    visited: &Visited,
    number: &[Vec<u32>],
    keep: &K,
    watch: &Watch,
    chunk: Chunk,
    first: u32,
    state: &mut State,
    next: &mut State,
    steps: &mut Steps,
) -> Option<Rows<K::Edge, K::Notes>> {
    let layout = &system.layout;
    let mut rows = Rows {
        degrees: Vec::new(),
        targets: Vec::new(),
        edge_data: Vec::new(),
        state_flags: Vec::new(),
        notes: keep.notes(),
    };
    let mut packed = vec![0u8; layout.bytes()];
    for (k, local) in (chunk.start..chunk.end).enumerate() {
        if k.is_multiple_of(STATES_PER_LOOK) && watch.stopped().is_some() {
            return None;
        }
        let me = first + k as u32;
        let current = visited.state(visited.id(chunk.shard, local));
        layout.decode(current, state);
        let mut flags = keep.state(state, me, &mut rows.notes);
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
                rows.targets.push(number[id.shard()][id.local() as usize]);
                let kept = keep.edge(state, step, next, me, &mut rows.notes);
                rows.edge_data.push(kept);
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
