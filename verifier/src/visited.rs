//! The visited set: every reached state stored once, packed, with a link to the state it
//! was first reached from.
//!
//! States live in [`SHARDS`] shards chosen by the top bits of their hash. A shard is a flat
//! byte arena (state `k` of the shard at `k * width`), a parallel array of parent links and
//! an open-addressing table of `u32` entries: 8 bits of the hash as a tag (so a probe rarely
//! has to read the arena) and the state's index in the shard plus one (0 marks an empty
//! entry). A [`StateId`] is the shard number in the top 8 bits and the index in the shard
//! in the low 24, so a parent link costs 4 bytes and the set holds up to about 2^32 states.
//!
//! The explorer reads the set from every worker at once (`&Visited`) and inserts shard by
//! shard in parallel (`&mut Shard`), so no locks are needed.

use crate::memory::fallibly;

/// Number of shards; a power of two.
pub const SHARDS: usize = 1 << SHARD_BITS;
const SHARD_BITS: u32 = 8;
const LOCAL_BITS: u32 = 32 - SHARD_BITS;
const LOCAL_MASK: u32 = (1 << LOCAL_BITS) - 1;
/// A shard holds at most this many states (index + 1 must fit in the entry's low bits).
const SHARD_CAPACITY: u32 = LOCAL_MASK - 1;
const FIRST_TABLE: usize = 4;

/// A stored state: its shard and its index in the shard.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct StateId(u32);

impl StateId {
    /// The parent link of the initial state.
    pub const NONE: StateId = StateId(u32::MAX);

    fn new(shard: usize, local: u32) -> StateId {
        StateId(((shard as u32) << LOCAL_BITS) | local)
    }

    /// The id as 32 bits, for storing it elsewhere.
    pub fn to_bits(self) -> u32 {
        self.0
    }

    pub fn from_bits(bits: u32) -> StateId {
        StateId(bits)
    }

    pub fn shard(self) -> usize {
        (self.0 >> LOCAL_BITS) as usize
    }

    pub fn local(self) -> u32 {
        self.0 & LOCAL_MASK
    }
}

/// Why a state could not be stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refused {
    /// A shard ran out of indices: the model has more states than the set can number.
    ShardFull,
    /// The allocator refused the growth of a shard (the address-space limit, or the
    /// memory): the run stops at its memory limit rather than aborting.
    NoMemory,
}

/// 64-bit hash of a packed state. Its top bits pick the shard, the next 8 the tag, the
/// low bits the table slot; the final mix makes all of them depend on every input bit.
pub fn hash(bytes: &[u8]) -> u64 {
    const K: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut h = K ^ bytes.len() as u64;
    let mut words = bytes.chunks_exact(8);
    for w in &mut words {
        let mut buf = [0u8; 8];
        buf.copy_from_slice(w);
        h = (h ^ u64::from_le_bytes(buf))
            .wrapping_mul(K)
            .rotate_left(29);
    }
    let rest = words.remainder();
    if !rest.is_empty() {
        let mut buf = [0u8; 8];
        buf[..rest.len()].copy_from_slice(rest);
        h = (h ^ u64::from_le_bytes(buf))
            .wrapping_mul(K)
            .rotate_left(29);
    }
    fmix64(h)
}

fn fmix64(mut h: u64) -> u64 {
    h ^= h >> 33;
    h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
    h ^= h >> 33;
    h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    h ^ (h >> 33)
}

pub fn shard_of(hash: u64) -> usize {
    (hash >> (64 - SHARD_BITS)) as usize
}

fn tag_of(hash: u64) -> u32 {
    ((hash >> (64 - SHARD_BITS - 8)) & 0xff) as u32
}

/// One shard of the visited set.
#[derive(Debug)]
pub struct Shard {
    width: usize,
    arena: Vec<u8>,
    parents: Vec<StateId>,
    table: Vec<u32>,
    /// Index of the first state of each level (levels are appended in order).
    level_starts: Vec<u32>,
}

impl Shard {
    fn new(width: usize) -> Shard {
        Shard {
            width,
            arena: Vec::new(),
            parents: Vec::new(),
            table: vec![0; FIRST_TABLE],
            level_starts: Vec::new(),
        }
    }

    pub fn len(&self) -> u32 {
        self.parents.len() as u32
    }

    pub fn state(&self, local: u32) -> &[u8] {
        let start = local as usize * self.width;
        &self.arena[start..start + self.width]
    }

    /// The index of the state with these bytes, if stored.
    pub fn find(&self, hash: u64, bytes: &[u8]) -> Option<u32> {
        let mask = self.table.len() - 1;
        let tag = tag_of(hash);
        let mut i = hash as usize & mask;
        loop {
            let e = self.table[i];
            if e == 0 {
                return None;
            }
            if e >> LOCAL_BITS == tag {
                let local = (e & LOCAL_MASK) - 1;
                if self.state(local) == bytes {
                    return Some(local);
                }
            }
            i = (i + 1) & mask;
        }
    }

    /// Stores a state unless it is there already; returns its index if it is new.
    pub fn insert(
        &mut self,
        hash: u64,
        bytes: &[u8],
        parent: StateId,
    ) -> Result<Option<u32>, Refused> {
        let tag = tag_of(hash);
        let mut i = self.probe(hash, bytes, tag);
        if self.table[i] != 0 {
            return Ok(None);
        }
        let local = self.len();
        if local >= SHARD_CAPACITY {
            return Err(Refused::ShardFull);
        }
        // grow only for a state that is really new, so that the table's size depends on
        // the states stored and not on how many duplicates were offered
        if (self.parents.len() + 1) * 4 > self.table.len() * 3 {
            self.grow()?;
            i = self.probe(hash, bytes, tag);
        }
        let room = fallibly(|| {
            self.arena.try_reserve(bytes.len())?;
            self.parents.try_reserve(1)
        });
        if room.is_err() {
            return Err(Refused::NoMemory);
        }
        self.table[i] = (tag << LOCAL_BITS) | (local + 1);
        self.arena.extend_from_slice(bytes);
        self.parents.push(parent);
        Ok(Some(local))
    }

    /// The table entry holding these bytes, or the empty entry where they would go.
    fn probe(&self, hash: u64, bytes: &[u8], tag: u32) -> usize {
        let mask = self.table.len() - 1;
        let mut i = hash as usize & mask;
        loop {
            let e = self.table[i];
            if e == 0 || (e >> LOCAL_BITS == tag && self.state((e & LOCAL_MASK) - 1) == bytes) {
                return i;
            }
            i = (i + 1) & mask;
        }
    }

    /// Doubles the table and re-enters every state (hashes are recomputed from the arena,
    /// which is cheaper than storing them).
    fn grow(&mut self) -> Result<(), Refused> {
        let size = self.table.len() * 2;
        let mask = size - 1;
        let mut table = Vec::new();
        fallibly(|| table.try_reserve_exact(size)).map_err(|_| Refused::NoMemory)?;
        table.resize(size, 0u32);
        for local in 0..self.len() {
            let h = hash(self.state(local));
            let mut i = h as usize & mask;
            while table[i] != 0 {
                i = (i + 1) & mask;
            }
            table[i] = (tag_of(h) << LOCAL_BITS) | (local + 1);
        }
        self.table = table;
        Ok(())
    }

    /// Bytes allocated by this shard.
    fn allocated(&self) -> usize {
        self.arena.capacity()
            + self.parents.capacity() * std::mem::size_of::<StateId>()
            + self.table.capacity() * 4
            + self.level_starts.capacity() * 4
    }

    /// Bytes in use (without the spare capacity of the arrays).
    fn used(&self) -> usize {
        self.arena.len()
            + self.parents.len() * std::mem::size_of::<StateId>()
            + self.table.len() * 4
    }

    /// The indices of the states of `level` in this shard.
    fn level_range(&self, level: usize) -> std::ops::Range<u32> {
        let start = self.level_starts.get(level).copied().unwrap_or(self.len());
        let end = self
            .level_starts
            .get(level + 1)
            .copied()
            .unwrap_or(self.len());
        start..end
    }
}

/// Every state reached so far.
#[derive(Debug)]
pub struct Visited {
    width: usize,
    shards: Vec<Shard>,
}

/// A run of consecutive states of one level in one shard: the unit of work of a worker.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Chunk {
    pub shard: usize,
    pub start: u32,
    pub end: u32,
}

impl Visited {
    /// An empty set for packed states of `width` bytes.
    pub fn new(width: usize) -> Visited {
        Visited {
            width,
            shards: (0..SHARDS).map(|_| Shard::new(width)).collect(),
        }
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn len(&self) -> u64 {
        self.shards.iter().map(|s| u64::from(s.len())).sum()
    }

    pub fn shards_mut(&mut self) -> &mut [Shard] {
        &mut self.shards
    }

    pub fn find(&self, hash: u64, bytes: &[u8]) -> Option<StateId> {
        let s = shard_of(hash);
        self.shards[s].find(hash, bytes).map(|l| StateId::new(s, l))
    }

    pub fn insert(&mut self, bytes: &[u8], parent: StateId) -> Result<Option<StateId>, Refused> {
        let h = hash(bytes);
        let s = shard_of(h);
        Ok(self.shards[s]
            .insert(h, bytes, parent)?
            .map(|l| StateId::new(s, l)))
    }

    pub fn state(&self, id: StateId) -> &[u8] {
        self.shards[id.shard()].state(id.local())
    }

    pub fn parent(&self, id: StateId) -> StateId {
        self.shards[id.shard()].parents[id.local() as usize]
    }

    /// The states from the root to `id`, root first.
    pub fn path_to(&self, id: StateId) -> Vec<StateId> {
        let mut path = vec![id];
        let mut cur = id;
        while self.parent(cur) != StateId::NONE {
            cur = self.parent(cur);
            path.push(cur);
        }
        path.reverse();
        path
    }

    /// Marks the start of a new level: states inserted from now on belong to it.
    pub fn start_level(&mut self) {
        for s in &mut self.shards {
            let len = s.len();
            s.level_starts.push(len);
        }
    }

    /// Number of levels started.
    pub fn levels(&self) -> usize {
        self.shards.first().map_or(0, |s| s.level_starts.len())
    }

    /// Number of states in `level`.
    pub fn level_len(&self, level: usize) -> u64 {
        self.shards
            .iter()
            .map(|s| u64::from(s.level_range(level).len() as u32))
            .sum()
    }

    /// The states of `level` cut into chunks of at most `size` states, in a fixed order
    /// (shard by shard, by index) that does not depend on the number of workers.
    pub fn chunks(&self, level: usize, size: u32) -> Vec<Chunk> {
        let mut out = Vec::new();
        for (shard, s) in self.shards.iter().enumerate() {
            let r = s.level_range(level);
            let mut start = r.start;
            while start < r.end {
                let end = r.end.min(start.saturating_add(size));
                out.push(Chunk { shard, start, end });
                start = end;
            }
        }
        out
    }

    pub fn id(&self, shard: usize, local: u32) -> StateId {
        StateId::new(shard, local)
    }

    /// Bytes allocated for the set.
    pub fn allocated_bytes(&self) -> u64 {
        (self.shards.iter().map(Shard::allocated).sum::<usize>()
            + self.shards.capacity() * std::mem::size_of::<Shard>()) as u64
    }

    /// Bytes the stored states need: packed state, parent link and table entries.
    pub fn used_bytes(&self) -> u64 {
        self.shards.iter().map(Shard::used).sum::<usize>() as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::collections::HashMap;

    #[test]
    fn ids_split_shard_and_index() {
        let id = StateId::new(200, 123_456);
        assert_eq!((id.shard(), id.local()), (200, 123_456));
        assert_ne!(StateId::new(SHARDS - 1, SHARD_CAPACITY - 1), StateId::NONE);
    }

    #[test]
    fn zero_width_states_are_one_state() {
        let mut v = Visited::new(0);
        assert!(v.insert(&[], StateId::NONE).unwrap().is_some());
        assert!(v.insert(&[], StateId::NONE).unwrap().is_none());
        assert_eq!(v.len(), 1);
    }

    proptest! {
        /// The set agrees with a HashMap on what is new, keeps the first parent and
        /// returns the bytes it was given, across table growth.
        #[test]
        fn behaves_like_a_map(width in 0usize..12, keys in prop::collection::vec(any::<u64>(), 0..3000)) {
            let mut v = Visited::new(width);
            let mut model: HashMap<Vec<u8>, StateId> = HashMap::new();
            let mut parent = StateId::NONE;
            for k in keys {
                let bytes: Vec<u8> = (0..width).map(|i| (k >> ((i % 8) * 8)) as u8 ^ (i as u8 / 8)).collect();
                let got = v.insert(&bytes, parent).unwrap();
                match model.get(&bytes) {
                    Some(&id) => {
                        prop_assert!(got.is_none());
                        prop_assert_eq!(v.find(hash(&bytes), &bytes), Some(id));
                    }
                    None => {
                        let id = got.unwrap();
                        prop_assert_eq!(v.state(id), &bytes[..]);
                        prop_assert_eq!(v.parent(id), parent);
                        model.insert(bytes, id);
                        parent = id;
                    }
                }
            }
            prop_assert_eq!(v.len(), model.len() as u64);
        }
    }

    #[test]
    fn levels_and_chunks_cover_each_state_once() {
        let mut v = Visited::new(4);
        v.start_level();
        v.insert(&0u32.to_le_bytes(), StateId::NONE).unwrap();
        v.start_level();
        for i in 1..5000u32 {
            v.insert(&i.to_le_bytes(), StateId::NONE).unwrap();
        }
        assert_eq!(v.level_len(0), 1);
        assert_eq!(v.level_len(1), 4999);
        let chunks = v.chunks(1, 7);
        let total: u32 = chunks.iter().map(|c| c.end - c.start).sum();
        assert_eq!(total, 4999);
        assert!(chunks.iter().all(|c| c.end - c.start <= 7));
        assert_eq!(v.chunks(2, 7), vec![]);
    }
}
