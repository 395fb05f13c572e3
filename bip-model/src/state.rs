//! Global states: the working form (one `i64` per slot) and the packed form (each slot in
//! as few bits as its range needs), which is what the verifier stores.

#[allow(unused_imports)]
use crate::prelude::*;

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
    ///
    /// Fields are laid out one after the other from bit 0 (little-endian bit order), so
    /// packing streams them through a 128-bit accumulator and writes whole words: the
    /// verifier packs every successor it generates.
    pub fn encode(&self, state: &State, out: &mut [u8]) {
        debug_assert_eq!(out.len(), self.bytes());
        let mut acc: u128 = 0;
        let mut acc_bits = 0u32;
        let mut pos = 0usize;
        for (f, &v) in self.fields.iter().zip(state.slots()) {
            if f.bits == 0 {
                continue;
            }
            let raw = v.wrapping_sub(f.lo) as u64 & mask(f.bits);
            acc |= u128::from(raw) << acc_bits;
            acc_bits += f.bits;
            if acc_bits >= 64 {
                out[pos..pos + 8].copy_from_slice(&(acc as u64).to_le_bytes());
                pos += 8;
                acc >>= 64;
                acc_bits -= 64;
            }
        }
        let rest = acc_bits.div_ceil(8) as usize;
        out[pos..pos + rest].copy_from_slice(&(acc as u64).to_le_bytes()[..rest]);
    }

    /// Packs `after` into `out` given `before` and its packing: copies `before_packed` and
    /// rewrites only the fields whose slot differs. A step changes a few slots of many, so
    /// this is much cheaper than [`StateLayout::encode`] for successors; the result is the
    /// same.
    pub fn encode_changed(
        &self,
        before: &State,
        before_packed: &[u8],
        after: &State,
        out: &mut [u8],
    ) {
        out.copy_from_slice(before_packed);
        let (a, b) = (before.slots(), after.slots());
        let n = self.fields.len().min(a.len()).min(b.len());
        // compare 8 slots at a time (the compiler vectorises this); look closer only where
        // something changed
        let mut base = 0;
        while base < n {
            let end = (base + 8).min(n);
            let differs = a[base..end]
                .iter()
                .zip(&b[base..end])
                .fold(0u64, |acc, (x, y)| acc | (x ^ y) as u64);
            if differs != 0 {
                for k in base..end {
                    let f = &self.fields[k];
                    if a[k] != b[k] && f.bits > 0 {
                        let raw = b[k].wrapping_sub(f.lo) as u64 & mask(f.bits);
                        overwrite_bits(out, f.offset, f.bits, raw);
                    }
                }
            }
            base = end;
        }
    }

    /// Reads a packed state into `out`, which must have this layout's number of slots.
    pub fn decode(&self, packed: &[u8], out: &mut State) {
        let mut acc: u128 = 0;
        let mut acc_bits = 0u32;
        let mut pos = 0usize;
        for (f, v) in self.fields.iter().zip(out.slots_mut()) {
            if f.bits == 0 {
                *v = f.lo;
                continue;
            }
            if acc_bits < f.bits {
                let take = (packed.len() - pos).min(8);
                let mut word = [0u8; 8];
                word[..take].copy_from_slice(&packed[pos..pos + take]);
                acc |= u128::from(u64::from_le_bytes(word)) << acc_bits;
                acc_bits += take as u32 * 8;
                pos += take;
            }
            *v = f.lo.wrapping_add((acc as u64 & mask(f.bits)) as i64);
            acc >>= f.bits;
            acc_bits -= f.bits;
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

/// Writes `raw` into bits `offset..offset + bits` of `out`, least significant bit first.
fn overwrite_bits(out: &mut [u8], offset: u32, bits: u32, mut raw: u64) {
    let mut pos = offset as usize;
    let mut left = bits;
    while left > 0 {
        let byte = pos / 8;
        let shift = (pos % 8) as u32;
        let take = (8 - shift).min(left);
        let m = (((1u16 << take) - 1) as u8) << shift;
        out[byte] = (out[byte] & !m) | (((raw as u8) << shift) & m);
        raw = raw.checked_shr(take).unwrap_or(0);
        pos += take as usize;
        left -= take;
    }
}

/// The low `bits` bits set (`bits` from 1 to 64).
fn mask(bits: u32) -> u64 {
    u64::MAX >> (64 - bits)
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

    /// The packed format, one bit at a time: field `k` at bit offset `offset`, least
    /// significant bit first.
    fn pack_bit_by_bit(layout: &StateLayout, state: &State) -> Vec<u8> {
        let mut out = vec![0u8; layout.bytes()];
        for (f, &v) in layout.fields.iter().zip(state.slots()) {
            let raw = v.wrapping_sub(f.lo) as u64;
            for b in 0..f.bits {
                if raw >> b & 1 == 1 {
                    let at = (f.offset + b) as usize;
                    out[at / 8] |= 1 << (at % 8);
                }
            }
        }
        out
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
            prop_assert_eq!(&packed, &pack_bit_by_bit(&layout, &state));
            // patching from another state gives the same bytes
            let zero_slots: Vec<i64> = ranges.iter().map(|&(lo, _)| lo).collect();
            let zero = State::from_slots(zero_slots);
            let mut patched = vec![0xa5; layout.bytes()];
            layout.encode_changed(&zero, &layout.pack(&zero), &state, &mut patched);
            prop_assert_eq!(&patched, &packed);
            layout.encode_changed(&state, &packed, &zero, &mut patched);
            prop_assert_eq!(&patched, &layout.pack(&zero));
            prop_assert_eq!(layout.unpack(&packed), state);
        }
    }
}
