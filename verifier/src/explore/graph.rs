//! The explored state graph, for the questions about paths: each state's successors
//! (compressed rows), with what the asker keeps of each state and each step ([`Keep`]):
//! the response properties where their triggers and responses happen, the scheduling
//! analysis each step's interaction.
//!
//! The exploration records it as it goes ([`Recorder`]): the expansion of a chunk, which
//! computes each state's steps and fires them anyway, also writes the chunk's rows, and
//! the rows of a batch are appended in chunk order once the batch is stored. States are
//! numbered in the exploration's order (level by level, chunk by chunk), so a smaller
//! number is never deeper, and the numbering does not depend on the number of workers.
//! A successor is named by its stored id while the exploration runs (one found new is
//! looked up once its batch is stored), and by its number once it is complete.

use bip_model::{State, Step};

use crate::visited::{hash, Chunk, StateId, Visited};
use crate::watch::Watch;

/// On a state, bit 0 of its flags: a state in range error (its steps could not be
/// computed, or every one of them fails). The other bits are the asker's.
pub(crate) const IN_ERROR: u32 = 1;

/// What a graph keeps of each state and each step, computed by the workers as they
/// expand the states.
pub(crate) trait Keep: Sync {
    /// What is kept of a step.
    type Edge: Copy + Send + Sync;
    /// What the states and steps note besides (such as the first error met): one per
    /// chunk, merged in chunk order.
    type Notes: Send + Sync;

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

impl<E, N> Graph<E, N> {
    pub(crate) fn len(&self) -> usize {
        self.ids.len()
    }

    pub(crate) fn edges(&self, s: u32) -> std::ops::Range<usize> {
        self.offsets[s as usize] as usize..self.offsets[s as usize + 1] as usize
    }

    fn allocated(&self) -> usize {
        self.offsets.capacity() * 8
            + self.targets.capacity() * 4
            + self.edge_data.capacity() * std::mem::size_of::<E>()
            + self.state_flags.capacity() * 4
            + self.ids.capacity() * 4
    }
}

/// One chunk's rows, written as its states are expanded. A successor not stored yet
/// when it is found is a candidate record of the chunk: its target waits in `pending`
/// until the batch is stored.
pub(super) struct Rows<E, N> {
    degrees: Vec<u32>,
    /// Each edge's target, as a stored state's id (bits).
    targets: Vec<u32>,
    edge_data: Vec<E>,
    state_flags: Vec<u32>,
    notes: N,
    /// (edge, candidate record) for the targets found new.
    pending: Vec<(u32, u32)>,
    /// The number of edges when the state being expanded started.
    open: usize,
}

impl<E, N> Rows<E, N> {
    pub(super) fn new<K: Keep<Edge = E, Notes = N>>(keep: &K) -> Rows<E, N> {
        Rows {
            degrees: Vec::new(),
            targets: Vec::new(),
            edge_data: Vec::new(),
            state_flags: Vec::new(),
            notes: keep.notes(),
            pending: Vec::new(),
            open: 0,
        }
    }

    pub(super) fn reset<K: Keep<Edge = E, Notes = N>>(&mut self, keep: &K) {
        self.degrees.clear();
        self.targets.clear();
        self.edge_data.clear();
        self.state_flags.clear();
        self.notes = keep.notes();
        self.pending.clear();
        self.open = 0;
    }

    pub(super) fn allocated(&self) -> usize {
        self.degrees.capacity() * 4
            + self.targets.capacity() * 4
            + self.edge_data.capacity() * std::mem::size_of::<E>()
            + self.state_flags.capacity() * 4
            + self.pending.capacity() * 8
    }

    /// Starts the row of state `me`: its flags by `keep`.
    pub(super) fn open<K: Keep<Edge = E, Notes = N>>(
        &mut self,
        keep: &K,
        state: &State,
        me: u32,
    ) -> u32 {
        self.open = self.targets.len();
        keep.state(state, me, &mut self.notes)
    }

    /// Adds the edge of `step` to the open row, to stored state `to`, or else to the
    /// chunk's candidate record `candidate`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn edge<K: Keep<Edge = E, Notes = N>>(
        &mut self,
        keep: &K,
        state: &State,
        step: Step<'_>,
        next: &State,
        me: u32,
        to: Option<StateId>,
        candidate: u32,
    ) {
        match to {
            Some(id) => self.targets.push(id.to_bits()),
            None => {
                self.pending.push((self.targets.len() as u32, candidate));
                self.targets.push(StateId::NONE.to_bits());
            }
        }
        let kept = keep.edge(state, step, next, me, &mut self.notes);
        self.edge_data.push(kept);
    }

    /// Ends the open row with the state's flags; `error`: its steps could not be
    /// computed, or (`steps` of them) none fired.
    pub(super) fn close(&mut self, flags: u32, error: bool, steps: usize) {
        let degree = self.targets.len() - self.open;
        let in_error = error || (degree == 0 && steps > 0);
        self.degrees.push(degree as u32);
        self.state_flags
            .push(flags | if in_error { IN_ERROR } else { 0 });
    }

    /// Names the targets found new by their ids, now that the batch is stored (`raw`:
    /// the chunk's candidate records, `rec` bytes each, `header` before the state);
    /// false if one is not stored.
    pub(super) fn resolve(
        &mut self,
        visited: &Visited,
        raw: &[u8],
        rec: usize,
        header: usize,
    ) -> bool {
        for &(edge, candidate) in &self.pending {
            let r = &raw[candidate as usize * rec..(candidate as usize + 1) * rec];
            let packed = &r[header..];
            let Some(id) = visited.find(hash(packed), packed) else {
                return false;
            };
            self.targets[edge as usize] = id.to_bits();
        }
        self.pending.clear();
        true
    }
}

/// The graph an exploration records: the rows of the states expanded so far, in order.
pub(super) struct Recorder<'k, K: Keep> {
    keep: &'k K,
    graph: Graph<K::Edge, K::Notes>,
}

impl<'k, K: Keep> Recorder<'k, K> {
    pub(super) fn new(keep: &'k K) -> Self {
        Recorder {
            keep,
            graph: Graph {
                offsets: vec![0],
                targets: Vec::new(),
                edge_data: Vec::new(),
                state_flags: Vec::new(),
                ids: Vec::new(),
                notes: keep.notes(),
            },
        }
    }

    pub(super) fn keep(&self) -> &'k K {
        self.keep
    }

    /// States whose rows are recorded.
    pub(super) fn states(&self) -> u32 {
        self.graph.ids.len() as u32
    }

    pub(super) fn allocated(&self) -> usize {
        self.graph.allocated()
    }

    /// Appends the rows of `chunk`, whose targets are resolved; false if they do not fit
    /// (the run is not stopped: the caller decides).
    pub(super) fn append(
        &mut self,
        chunk: Chunk,
        visited: &Visited,
        rows: &mut Rows<K::Edge, K::Notes>,
        watch: &Watch,
    ) -> bool {
        let g = &mut self.graph;
        let states = rows.degrees.len();
        let edges = rows.targets.len();
        if !(watch.grow(&mut g.offsets, states)
            && watch.grow(&mut g.state_flags, states)
            && watch.grow(&mut g.ids, states)
            && watch.grow(&mut g.targets, edges)
            && watch.grow(&mut g.edge_data, edges))
        {
            return false;
        }
        let mut last = *g.offsets.last().unwrap_or(&0);
        for d in &rows.degrees {
            last += u64::from(*d);
            g.offsets.push(last);
        }
        g.targets.extend_from_slice(&rows.targets);
        g.edge_data.extend_from_slice(&rows.edge_data);
        g.state_flags.extend_from_slice(&rows.state_flags);
        g.ids
            .extend((chunk.start..chunk.end).map(|local| visited.id(chunk.shard, local)));
        let notes = std::mem::replace(&mut rows.notes, self.keep.notes());
        self.keep.merge(&mut g.notes, notes);
        true
    }

    /// The graph of a complete exploration, its targets named by their numbers; `None`
    /// if the run must stop (a limit of `watch`) or a target is not a recorded state.
    pub(super) fn finish(
        self,
        visited: &Visited,
        watch: &Watch,
    ) -> Option<Graph<K::Edge, K::Notes>> {
        let mut g = self.graph;
        if g.ids.len() as u64 != visited.len() || !watch.expect(visited.len() * 4) {
            return None;
        }
        // the numbers of the states, by shard and index
        let mut number: Vec<Vec<u32>> = (0..crate::visited::SHARDS).map(|_| Vec::new()).collect();
        for (n, id) in g.ids.iter().enumerate() {
            let v = &mut number[id.shard()];
            if v.len() <= id.local() as usize {
                v.resize(id.local() as usize + 1, u32::MAX);
            }
            v[id.local() as usize] = n as u32;
        }
        for t in &mut g.targets {
            let id = StateId::from_bits(*t);
            let n = *number.get(id.shard())?.get(id.local() as usize)?;
            if n == u32::MAX {
                return None;
            }
            *t = n;
        }
        Some(g)
    }
}
