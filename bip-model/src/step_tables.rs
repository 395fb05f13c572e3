//! Interactions' steps tabulated over the few values they depend on.
//!
//! The steps of an interaction in a state (before priorities) are a function of a handful
//! of slots: its participants' locations, the variables their guards on its ports read,
//! and what its connector's guard reads. Most of those slots have tiny ranges (a location
//! of two or three, a flag, a small counter), so the function has few arguments in all: a
//! GenoM codel's run interaction depends on its activity's location and `paused` flag, and
//! on the slots of the constraints that guard it. For every interaction whose arguments
//! take at most [`MAX_TABLE`] combinations, the system computes its steps once per
//! combination, when it is compiled, with the step relation itself
//! ([`System::compute_interaction_picks`]), and keeps them in a table; finding an
//! interaction's steps is then a mixed-radix index and a copy. The verifier, which
//! evaluates every interaction in every state, and the engine's [`crate::EnabledSet`], which
//! re-evaluates the interactions a step touched, both read the tables through
//! [`System::interaction_picks`].
//!
//! The table is the step relation, not a second description of it: an entry holds what the
//! relation computed for those argument values, and a combination on which the relation
//! fails (a guard's range error) has no entry, so the relation is run in that state and
//! reports the error with its details.

#[allow(unused_imports)]
use crate::prelude::*;

use alloc::sync::Arc;

use crate::step::{Choices, Pick};
use crate::system::System;

/// The most combinations one table may have.
const MAX_TABLE: u64 = 4096;
/// The most entries and picks the tables of one system may hold (about 3 MiB and 8 MiB):
/// interactions beyond the budget are computed as before.
const MAX_ENTRIES: usize = 1 << 18;
const MAX_PICKS: usize = 1 << 20;

/// No table.
const NONE: u32 = u32::MAX;

/// The tables of one system.
#[derive(Clone, Debug, Default)]
pub(crate) struct StepTables {
    /// Per interaction, its table (`entries` is [`NONE`] for none).
    of: Vec<Table>,
    inputs: Vec<Input>,
    entries: Vec<Entry>,
    /// Every entry's picks, shared with the [`crate::EnabledSet`]s of the system, which
    /// point into it instead of copying.
    picks: Arc<[Pick]>,
}

#[derive(Clone, Copy, Debug)]
struct Table {
    inputs: (u32, u32),
    entries: u32,
}

/// A slot the steps depend on: its value minus `lo` is a digit of radix `radix` and weight
/// `stride` in the index.
#[derive(Clone, Copy, Debug)]
struct Input {
    slot: u32,
    lo: i64,
    radix: u64,
    stride: u64,
}

/// The steps of one combination: `width` picks per step in `picks[start..start + len]`,
/// and whether every required port had an enabled transition; `known` is false where the
/// relation failed.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Entry {
    start: u32,
    len: u32,
    width: u16,
    ready: bool,
    known: bool,
}

impl Entry {
    /// Where its picks are in the tables' pool.
    #[inline(always)]
    pub(crate) fn span(&self) -> (u32, u32) {
        (self.start, self.len)
    }

    /// Picks per step.
    #[inline(always)]
    pub(crate) fn width(&self) -> usize {
        self.width as usize
    }

    /// Every required port had an enabled transition.
    #[inline(always)]
    pub(crate) fn ready(&self) -> bool {
        self.ready
    }
}

impl StepTables {
    /// Tabulates the interactions of `system` that fit (the system's own tables must be
    /// empty: its steps are computed by the relation).
    pub(crate) fn build(system: &System) -> StepTables {
        let none = Table {
            inputs: (0, 0),
            entries: NONE,
        };
        let mut t = StepTables {
            of: vec![none; system.interactions.len()],
            ..StepTables::default()
        };
        let mut picks = Vec::new();
        let mut state = system.initial_state();
        let mut scratch = Choices::default();
        let mut reads = Vec::new();
        for i in 0..system.interactions.len() as u32 {
            reads.clear();
            system.interaction_reads(i, &mut |s, _| reads.push(s));
            reads.sort_unstable();
            reads.dedup();
            let inputs_start = t.inputs.len();
            let mut size = 1u64;
            for &slot in &reads {
                let (lo, hi) = system.slot_ranges[slot as usize];
                // a slot of one value adds nothing to the index
                let Some(radix) = hi.checked_sub(lo).and_then(|d| (d as u64).checked_add(1)) else {
                    size = u64::MAX;
                    break;
                };
                if radix == 1 {
                    continue;
                }
                t.inputs.push(Input {
                    slot,
                    lo,
                    radix,
                    stride: size,
                });
                size = size.saturating_mul(radix);
            }
            if size > MAX_TABLE || t.entries.len() + size as usize > MAX_ENTRIES {
                t.inputs.truncate(inputs_start);
                continue;
            }
            let (entries_start, picks_start) = (t.entries.len(), picks.len());
            let inputs = inputs_start..t.inputs.len();
            for key in 0..size {
                for inp in &t.inputs[inputs.clone()] {
                    let digit = (key / inp.stride) % inp.radix;
                    state.slots_mut()[inp.slot as usize] = inp.lo + digit as i64;
                }
                let start = picks.len();
                let entry =
                    match system.compute_interaction_picks(&state, i, &mut scratch, &mut picks) {
                        Ok((width, ready)) => Entry {
                            start: start as u32,
                            len: (picks.len() - start) as u32,
                            width: width as u16,
                            ready,
                            known: u16::try_from(width).is_ok(),
                        },
                        Err(_) => {
                            picks.truncate(start);
                            Entry::default()
                        }
                    };
                t.entries.push(entry);
            }
            // the slots written go back to their initial values for the next interaction
            for inp in &t.inputs[inputs.clone()] {
                state.slots_mut()[inp.slot as usize] = system.initial.slots()[inp.slot as usize];
            }
            if picks.len() > MAX_PICKS {
                t.entries.truncate(entries_start);
                picks.truncate(picks_start);
                t.inputs.truncate(inputs_start);
                continue;
            }
            t.of[i as usize] = Table {
                inputs: (inputs.start as u32, inputs.end as u32),
                entries: entries_start as u32,
            };
        }
        t.picks = picks.into();
        t
    }

    /// The tabulated steps of interaction `i` in a state, if it has a table and an entry
    /// for the state's values.
    #[inline(always)]
    pub(crate) fn lookup(&self, i: u32, slots: &[i64]) -> Option<&Entry> {
        let table = *self.of.get(i as usize)?;
        if table.entries == NONE {
            return None;
        }
        let mut key = 0u64;
        for inp in &self.inputs[table.inputs.0 as usize..table.inputs.1 as usize] {
            let digit = slots[inp.slot as usize].wrapping_sub(inp.lo) as u64;
            // a state outside the model's ranges is left to the relation
            if digit >= inp.radix {
                return None;
            }
            key += digit * inp.stride;
        }
        let e = &self.entries[table.entries as usize + key as usize];
        e.known.then_some(e)
    }

    /// The picks of an entry, the number of picks per step, and whether every required port
    /// was ready.
    #[inline(always)]
    pub(crate) fn steps(&self, e: &Entry) -> (&[Pick], usize, bool) {
        (self.picks_of(e.span()), e.width as usize, e.ready)
    }

    /// The picks of `span` (an entry's [`Entry::span`]).
    #[inline(always)]
    pub(crate) fn picks_of(&self, (start, len): (u32, u32)) -> &[Pick] {
        &self.picks[start as usize..(start + len) as usize]
    }

    /// Every entry's picks, to share.
    pub(crate) fn pool(&self) -> Arc<[Pick]> {
        Arc::clone(&self.picks)
    }

    /// How many interactions have a table.
    pub(crate) fn tabulated(&self) -> usize {
        self.of.iter().filter(|t| t.entries != NONE).count()
    }

    /// Forgets the tables of the interactions `which` selects.
    pub(crate) fn drop_where(&mut self, which: impl Fn(u32) -> bool) {
        for (i, t) in self.of.iter_mut().enumerate() {
            if which(i as u32) {
                t.entries = NONE;
            }
        }
    }
}

impl System {
    /// Computes the steps of the interactions `which` selects from the state each time,
    /// without their step tables: for tests that check the tables against the computation,
    /// and to measure what the tables bring. The steps are the same either way.
    pub fn drop_step_tables(&mut self, which: impl Fn(u32) -> bool) {
        self.enable_index.tables.drop_where(which);
    }
}
