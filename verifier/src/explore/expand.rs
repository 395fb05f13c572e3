//! Phase 1 on one chunk: each state's properties checked, its steps fired, and the
//! successors not yet stored kept as candidate records, bucketed by shard; and, when the
//! run needs them, the chunk's rows of the state graph and what its states show of the
//! tasks' responses, from the same steps.

use std::sync::atomic::Ordering;

use bip_model::eval::Env;
use bip_model::Liveness;

use crate::visited::{hash, shard_of, Chunk, SHARDS};

use super::graph::{Keep, Rows};
use super::targets::Check;
use super::worst::Tasks;
use super::{ChunkOut, Ctx, Finding, Found, Scratch, SUCCESSORS_PER_LOOK};

/// Candidate records a chunk finds before it announces them (bytes, records).
const ANNOUNCED_BYTES: usize = 64 << 10;
const ANNOUNCED_RECORDS: usize = 256;
/// A candidate record is held three times before it is stored: found, sorted by shard,
/// and stored; announced to the watch at that cost.
const RECORD_COPIES: u64 = 3;

impl<K: Keep> ChunkOut<K> {
    pub(super) fn new(keep: Option<&K>, tasks: &Tasks) -> ChunkOut<K> {
        ChunkOut {
            raw: Vec::new(),
            sorted: Vec::new(),
            offsets: Vec::new(),
            transitions: 0,
            findings: Vec::new(),
            liveness_unknown: 0,
            cut: false,
            rows: keep.map(Rows::new),
            seen: Ok(tasks.unseen()),
        }
    }

    pub(super) fn reset(&mut self, targets: usize, keep: Option<&K>, tasks: &Tasks) {
        if let (Some(rows), Some(keep)) = (&mut self.rows, keep) {
            rows.reset(keep);
        }
        self.seen = Ok(tasks.unseen());
        self.cut = false;
        self.raw.clear();
        self.sorted.clear();
        self.offsets.clear();
        self.transitions = 0;
        self.findings.clear();
        self.findings.resize(targets, None);
        self.liveness_unknown = 0;
    }

    pub(super) fn allocated(&self) -> usize {
        self.raw.capacity()
            + self.sorted.capacity()
            + self.offsets.capacity() * 4
            + self.rows.as_ref().map_or(0, Rows::allocated)
    }

    /// Groups the raw records by shard (a counting sort, stable: order within a shard is
    /// the order found).
    fn sort_by_shard(&mut self, rec: usize) {
        let n = self.raw.len() / rec;
        self.offsets.clear();
        self.offsets.resize(SHARDS + 1, 0);
        for r in self.raw.chunks_exact(rec) {
            self.offsets[shard_of(read_hash(r)) + 1] += 1;
        }
        for s in 0..SHARDS {
            self.offsets[s + 1] += self.offsets[s];
        }
        let mut next: Vec<u32> = self.offsets[..SHARDS].to_vec();
        self.sorted.clear();
        self.sorted.resize(n * rec, 0);
        for r in self.raw.chunks_exact(rec) {
            let s = shard_of(read_hash(r));
            let at = next[s] as usize * rec;
            self.sorted[at..at + rec].copy_from_slice(r);
            next[s] += 1;
        }
    }

    pub(super) fn bucket(&self, shard: usize, rec: usize) -> &[u8] {
        if self.offsets.is_empty() {
            return &[];
        }
        &self.sorted[self.offsets[shard] as usize * rec..self.offsets[shard + 1] as usize * rec]
    }
}

pub(super) fn read_hash(rec: &[u8]) -> u64 {
    let mut b = [0u8; 8];
    b.copy_from_slice(&rec[..8]);
    u64::from_le_bytes(b)
}

pub(super) fn read_parent(rec: &[u8]) -> u32 {
    let mut b = [0u8; 4];
    b.copy_from_slice(&rec[8..12]);
    u32::from_le_bytes(b)
}

pub(super) const REC_HEADER: usize = 12;

impl<K: Keep> Ctx<'_, '_, K> {
    /// Expands `chunk`, whose first state is state `first` of the recorded graph.
    pub(super) fn expand_chunk(
        &self,
        chunk: Chunk,
        first: u32,
        s: &mut Scratch,
        out: &mut ChunkOut<K>,
    ) {
        let sys = self.system;
        let layout = &sys.layout;
        let width = self.visited.width();
        let rec = REC_HEADER + width;
        let range_target = self.targets.len() - 1;
        let mut announced = 0usize;
        for local in chunk.start..chunk.end {
            if self.must_stop(out, &mut announced, rec, false) {
                out.cut = true;
                break;
            }
            let id = self.visited.id(chunk.shard, local);
            let current = self.visited.state(id);
            layout.decode(current, &mut s.state);
            let found = |p: usize, what: Found, out: &mut ChunkOut<K>| {
                if out.findings[p].is_none() {
                    out.findings[p] = Some(Finding { state: id, what });
                }
            };
            let mut deadlock_target = None;
            for (p, t) in self.targets.iter().enumerate() {
                if !self.open[p] || out.findings[p].is_some() {
                    continue;
                }
                let (e, wanted, what) = match &t.check {
                    Check::Invariant(e) => (*e, false, Found::Violation),
                    Check::Reachable(e) => (*e, true, Found::Witness),
                    Check::Deadlock { .. } => {
                        deadlock_target = Some(p);
                        continue;
                    }
                    Check::RangeErrors | Check::Response { .. } | Check::TimeProgress => continue,
                };
                // the context string is built only on an error: this runs for every state
                match e.holds(&mut Env::new(s.state.slots(), 0)) {
                    Ok(v) if v == wanted => found(p, what, out),
                    Ok(_) => {}
                    Err(err) => {
                        let err = sys.range_error(err, &format!("property {}", t.name));
                        found(p, Found::RangeError(err.to_string()), out);
                    }
                }
            }
            let me = first + (local - chunk.start);
            let flags = match (self.keep, &mut out.rows) {
                (Some(keep), Some(rows)) => rows.open(keep, &s.state, me),
                _ => 0,
            };
            if let Err(err) = sys.enabled_steps(&s.state, &mut s.steps) {
                if let Some(rows) = &mut out.rows {
                    rows.close(flags, true, 0);
                }
                if out.seen.is_ok() {
                    out.seen = Err(err.to_string());
                }
                found(range_target, Found::RangeError(err.to_string()), out);
                continue;
            }
            if let Ok(seen) = &mut out.seen {
                if !seen.is_empty() {
                    self.tasks.see(sys, &s.state, &s.steps, id, seen);
                }
            }
            if let Some(p) = deadlock_target {
                match sys.liveness(&s.state, &s.steps, &mut s.checker) {
                    Ok(Liveness::Deadlock) => {
                        let Check::Deadlock { terminal } = &self.targets[p].check else {
                            unreachable!("deadlock_target is a deadlock check")
                        };
                        match terminal
                            .map(|e| sys.holds(e, &s.state, "terminal condition of DeadlockFree"))
                        {
                            None | Some(Ok(false)) => found(p, Found::Deadlock, out),
                            Some(Ok(true)) => {}
                            Some(Err(err)) => found(p, Found::RangeError(err.to_string()), out),
                        }
                    }
                    Ok(Liveness::Unknown) | Err(_) => out.liveness_unknown += 1,
                    Ok(Liveness::Progress | Liveness::AfterTime { .. }) => {}
                }
            }
            let Scratch {
                state,
                next,
                steps,
                packed,
                ..
            } = s;
            for (k, step) in steps.iter().enumerate() {
                if k % SUCCESSORS_PER_LOOK == SUCCESSORS_PER_LOOK - 1
                    && self.must_stop(out, &mut announced, rec, false)
                {
                    // the state is only partly expanded: its chunk ends here
                    out.cut = true;
                    break;
                }
                if let Err(err) = sys.fire(state, step, next) {
                    found(range_target, Found::RangeError(err.to_string()), out);
                    continue;
                }
                out.transitions += 1;
                layout.encode_changed(state, current, next, packed);
                let h = hash(packed);
                let stored = self.visited.find(h, packed);
                if let (Some(keep), Some(rows)) = (self.keep, &mut out.rows) {
                    let candidate = (out.raw.len() / rec) as u32;
                    rows.edge(keep, state, step, next, me, stored, candidate);
                }
                if stored.is_none() {
                    if !self.watch.reserve(&mut out.raw, rec) {
                        out.cut = true;
                        break;
                    }
                    out.raw.extend_from_slice(&h.to_le_bytes());
                    out.raw.extend_from_slice(&id.to_bits().to_le_bytes());
                    out.raw.extend_from_slice(packed);
                }
            }
            if let Some(rows) = &mut out.rows {
                rows.close(flags, false, steps.len());
            }
        }
        self.must_stop(out, &mut announced, rec, true);
        // a stopped run inserts nothing: sorting a wide batch's records would cost time
        out.sorted.clear();
        if self.watch.stopped().is_none() && self.watch.reserve(&mut out.sorted, out.raw.len()) {
            out.sort_by_shard(rec);
        }
    }

    /// Announces the records found since the last call, and says whether the chunk must
    /// stop: a limit of the run is reached, or the batch has found `room` new states.
    /// The records are announced in groups (or all, with `flush`), to keep the shared
    /// counters off the path of every state.
    fn must_stop(&self, out: &ChunkOut<K>, announced: &mut usize, rec: usize, flush: bool) -> bool {
        let new = out.raw.len() - *announced;
        if new >= ANNOUNCED_BYTES || new >= ANNOUNCED_RECORDS * rec || (flush && new > 0) {
            *announced = out.raw.len();
            let records = (new / rec) as u64;
            let found = self.found.fetch_add(records, Ordering::Relaxed) + records;
            if found >= self.room {
                self.full.store(true, Ordering::Relaxed);
            }
            self.watch.expect(new as u64 * RECORD_COPIES);
        }
        self.watch.stopped().is_some() || self.full.load(Ordering::Relaxed)
    }
}
