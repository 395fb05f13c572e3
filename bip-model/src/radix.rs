//! Mixed-radix keys over a few slots of small ranges: the index of a table that holds a
//! function of those slots for every combination of their values. The step tables
//! (`step_tables.rs`) and the expression and action tables (`fast_path/`) are indexed
//! this way.

#[allow(unused_imports)]
use crate::prelude::*;

/// A slot a key is made of: its value minus `lo` is a digit of radix `radix` and weight
/// `stride`; relative to the component's variables (the `base` of [`key`]) if `local`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Digit {
    slot: u32,
    local: bool,
    lo: i64,
    radix: u64,
    stride: u64,
}

impl Digit {
    /// The slot (relative to a `base` if local).
    pub(crate) fn slot(&self) -> u32 {
        self.slot
    }
}

/// The digits of a key, the slots of one value (no digit: `(slot, local, value)`), and how
/// many keys there are.
#[derive(Clone, Debug)]
pub(crate) struct Digits {
    pub digits: Vec<Digit>,
    fixed: Vec<(u32, bool, i64)>,
    pub size: u64,
}

impl Digits {
    /// The digits of the slots in `read` (`(slot, local)`, with repeats), whose ranges
    /// `range` gives; `None` if one has no range or the keys do not fit in a `u64`.
    pub(crate) fn new(
        read: &mut Vec<(u32, bool)>,
        range: impl Fn(u32, bool) -> Option<(i64, i64)>,
    ) -> Option<Digits> {
        read.sort_unstable();
        read.dedup();
        let mut d = Digits {
            digits: Vec::with_capacity(read.len()),
            fixed: Vec::new(),
            size: 1,
        };
        for &(slot, local) in read.iter() {
            let (lo, hi) = range(slot, local)?;
            let radix = (hi.checked_sub(lo)? as u64).checked_add(1)?;
            if radix == 1 {
                d.fixed.push((slot, local, lo));
                continue;
            }
            d.digits.push(Digit {
                slot,
                local,
                lo,
                radix,
                stride: d.size,
            });
            d.size = d.size.checked_mul(radix)?;
        }
        Some(d)
    }

    /// Writes into `slots` the values whose key is `key` (`key` below `size`), and the
    /// slots of one value: every slot the key is made of is then set.
    pub(crate) fn set(&self, key: u64, slots: &mut [i64], base: u32) {
        for &(slot, local, v) in &self.fixed {
            slots[at(slot, local, base)] = v;
        }
        for d in &self.digits {
            slots[at(d.slot, d.local, base)] = d.lo + ((key / d.stride) % d.radix) as i64;
        }
    }
}

/// The key of the values in `slots`, or `None` if one is outside the range its digit was
/// made for (such a state is left to whatever computes without the table).
#[inline(always)]
pub(crate) fn key(digits: &[Digit], slots: &[i64], base: u32) -> Option<u64> {
    let mut key = 0u64;
    for d in digits {
        let digit = slots[at(d.slot, d.local, base)].wrapping_sub(d.lo) as u64;
        if digit >= d.radix {
            return None;
        }
        key += digit * d.stride;
    }
    Some(key)
}

#[inline(always)]
fn at(slot: u32, local: bool, base: u32) -> usize {
    (if local { base + slot } else { slot }) as usize
}
