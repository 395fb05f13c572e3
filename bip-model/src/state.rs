//! Global states: the working form (one `i64` per slot) and the packed form (each slot in
//! as few bits as its range needs), which is what the verifier stores.

/// A global state: per component, its location number then its variables' values.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct State {
    slots: Box<[i64]>,
}

impl State {
    pub fn from_slots(slots: Vec<i64>) -> State {
        State {
            slots: slots.into_boxed_slice(),
        }
    }

    pub fn slots(&self) -> &[i64] {
        &self.slots
    }

    pub fn slots_mut(&mut self) -> &mut [i64] {
        &mut self.slots
    }

    /// Copies `other` into `self` without allocating (both come from the same system).
    pub fn copy_from(&mut self, other: &State) {
        self.slots.copy_from_slice(&other.slots);
    }
}

/// Where each slot lives in a packed state.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StateLayout {
    fields: Vec<PackedField>,
    bits: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct PackedField {
    lo: i64,
    bits: u32,
    offset: u32,
}

/// Bits needed for `n` distinct values (0 for a single value).
fn bits_for(count: u128) -> u32 {
    if count <= 1 {
        0
    } else {
        128 - (count - 1).leading_zeros()
    }
}

impl StateLayout {
    /// A layout for slots with the given inclusive ranges.
    pub fn new(ranges: &[(i64, i64)]) -> StateLayout {
        let mut offset = 0;
        let fields = ranges
            .iter()
            .map(|&(lo, hi)| {
                let count = (i128::from(hi) - i128::from(lo) + 1) as u128;
                let bits = bits_for(count);
                let f = PackedField { lo, bits, offset };
                offset += bits;
                f
            })
            .collect();
        StateLayout {
            fields,
            bits: offset,
        }
    }

    /// Bits of a packed state.
    pub fn bits(&self) -> u32 {
        self.bits
    }

    /// Bytes of a packed state.
    pub fn bytes(&self) -> usize {
        self.bits.div_ceil(8) as usize
    }

    /// Writes `state` into `out` (`out.len() == self.bytes()`). Every slot must be within
    /// its range, which the step relation guarantees.
    pub fn encode(&self, state: &State, out: &mut [u8]) {
        debug_assert_eq!(out.len(), self.bytes());
        out.fill(0);
        for (f, &v) in self.fields.iter().zip(state.slots()) {
            if f.bits == 0 {
                continue;
            }
            let raw = v.wrapping_sub(f.lo) as u64;
            write_bits(out, f.offset, f.bits, raw);
        }
    }

    /// Reads a packed state into `out`, which must have this layout's number of slots.
    pub fn decode(&self, packed: &[u8], out: &mut State) {
        for (f, v) in self.fields.iter().zip(out.slots_mut()) {
            *v = if f.bits == 0 {
                f.lo
            } else {
                f.lo.wrapping_add(read_bits(packed, f.offset, f.bits) as i64)
            };
        }
    }

    /// Packs a state into a new buffer.
    pub fn pack(&self, state: &State) -> Vec<u8> {
        let mut out = vec![0; self.bytes()];
        self.encode(state, &mut out);
        out
    }

    /// Unpacks into a new state.
    pub fn unpack(&self, packed: &[u8]) -> State {
        let mut s = State::from_slots(vec![0; self.fields.len()]);
        self.decode(packed, &mut s);
        s
    }
}

fn write_bits(out: &mut [u8], offset: u32, bits: u32, mut raw: u64) {
    let mut pos = offset as usize;
    let mut left = bits;
    while left > 0 {
        let byte = pos / 8;
        let shift = (pos % 8) as u32;
        let take = (8 - shift).min(left);
        let mask = ((1u16 << take) - 1) as u8;
        out[byte] |= ((raw as u8) & mask) << shift;
        raw = raw.checked_shr(take).unwrap_or(0);
        pos += take as usize;
        left -= take;
    }
}

fn read_bits(packed: &[u8], offset: u32, bits: u32) -> u64 {
    let mut pos = offset as usize;
    let mut left = bits;
    let mut got = 0u32;
    let mut raw = 0u64;
    while left > 0 {
        let byte = pos / 8;
        let shift = (pos % 8) as u32;
        let take = (8 - shift).min(left);
        let mask = ((1u16 << take) - 1) as u8;
        raw |= u64::from((packed[byte] >> shift) & mask) << got;
        got += take;
        pos += take as usize;
        left -= take;
    }
    raw
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn widths_follow_ranges() {
        let l = StateLayout::new(&[(0, 0), (0, 1), (0, 2), (-5, 10), (i64::MIN, i64::MAX)]);
        assert_eq!(l.bits(), 1 + 2 + 4 + 64); // one value needs no bit; -5..=10 is 16 values
        assert_eq!(l.bytes(), 9);
    }

    proptest! {
        #[test]
        fn pack_unpack_round_trips(fields in prop::collection::vec((any::<i64>(), 0u64..u64::MAX, any::<u64>()), 0..20)) {
            let ranges: Vec<(i64, i64)> = fields
                .iter()
                .map(|&(lo, width, _)| (lo, lo.saturating_add((width % 1_000_000) as i64)))
                .collect();
            let values: Vec<i64> = fields
                .iter()
                .zip(&ranges)
                .map(|(&(_, _, pick), &(lo, hi))| {
                    let span = (i128::from(hi) - i128::from(lo) + 1) as u128;
                    (i128::from(lo) + (u128::from(pick) % span) as i128) as i64
                })
                .collect();
            let layout = StateLayout::new(&ranges);
            let state = State::from_slots(values);
            let packed = layout.pack(&state);
            prop_assert_eq!(packed.len(), layout.bytes());
            prop_assert_eq!(layout.unpack(&packed), state);
        }
    }
}
