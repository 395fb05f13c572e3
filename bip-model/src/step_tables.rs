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
//! evaluates every interaction in every state ([`System::enabled_steps`]), and the engine's
//! [`crate::EnabledSet`], which re-evaluates the interactions a step touched, both read the
//! tables with [`StepTables::lookup_sharing`] and fall back on
//! [`System::compute_interaction_picks`].
//!
//! The table is the step relation, not a second description of it: an entry holds what the
//! relation computed for those argument values, and a combination on which the relation
//! fails (a guard's range error) has no entry, so the relation is run in that state and
//! reports the error with its details.

#[allow(unused_imports)]
use crate::prelude::*;

use alloc::sync::Arc;

use crate::model::RangeError;
use crate::radix::{key, Digit, Digits};
use crate::state::State;
use crate::steps::{Choices, Pick};

/// The most combinations one table may have.
const MAX_TABLE: u64 = 4096;
/// The most entries and picks the tables of one system may hold (about 3 MiB and 8 MiB):
/// interactions beyond the budget are computed as before.
const MAX_ENTRIES: usize = 1 << 18;
const MAX_PICKS: usize = 1 << 20;

/// No table.
const NONE: u32 = u32::MAX;

/// The step relation as the tables see it: what each interaction's steps read, and its
/// steps before priorities in a state. The tables are its answers, kept.
pub(crate) trait Tabulated {
    fn interactions(&self) -> u32;
    /// A state whose slots all hold values of their ranges.
    fn initial_state(&self) -> State;
    fn slot_range(&self, slot: u32) -> Option<(i64, i64)>;
    /// Every slot the steps of interaction `i` read (a slot may come more than once).
    fn reads(&self, i: u32, f: &mut dyn FnMut(u32));
    /// The steps of interaction `i` in `state` before priorities, into `picks`: how many
    /// picks a step has, and whether the interaction is ready.
    fn picks(
        &self,
        state: &State,
        i: u32,
        scratch: &mut Choices,
        picks: &mut Vec<Pick>,
    ) -> Result<(usize, bool), RangeError>;
}

/// The tables of one system.
#[derive(Clone, Debug, Default)]
pub(crate) struct StepTables {
    /// Per interaction, its table (`entries` is [`NONE`] for none).
    of: Vec<Table>,
    digits: Vec<Digit>,
    entries: Vec<Entry>,
    /// Every entry's picks, shared with the [`crate::EnabledSet`]s of the system, which
    /// point into it instead of copying.
    picks: Arc<[Pick]>,
}

/// The key's digits in `digits`, its `size` entries from `entries` on.
#[derive(Clone, Copy, Debug)]
struct Table {
    digits: (u32, u32),
    entries: u32,
    size: u32,
}

/// The key last computed by [`StepTables::lookup_sharing`], and of which digits.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LastKey {
    digits: (u32, u32),
    key: Option<u64>,
}

impl LastKey {
    /// No key: the next lookup computes its own.
    pub(crate) const NONE: LastKey = LastKey {
        digits: (u32::MAX, u32::MAX),
        key: None,
    };
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
    // systems are compiled with `std` (loading needs it); a no-std build receives them
    pub(crate) fn build(relation: &impl Tabulated) -> StepTables {
        let none = Table {
            digits: (0, 0),
            entries: NONE,
            size: 0,
        };
        let mut t = StepTables {
            of: vec![none; relation.interactions() as usize],
            ..StepTables::default()
        };
        let mut picks = Vec::new();
        let mut state = relation.initial_state();
        let mut scratch = Choices::default();
        let mut reads = Vec::new();
        let mut last_digits: Option<(u32, u32)> = None;
        for i in 0..relation.interactions() {
            reads.clear();
            relation.reads(i, &mut |s| reads.push((s, false)));
            let Some(d) = Digits::new(&mut reads, |s, _| relation.slot_range(s)) else {
                continue;
            };
            if d.size > MAX_TABLE || t.entries.len() + d.size as usize > MAX_ENTRIES {
                continue;
            }
            let (entries_start, picks_start) = (t.entries.len(), picks.len());
            let mut fits = true;
            for key in 0..d.size {
                // every slot the steps read is set; the others do not matter
                d.set(key, state.slots_mut(), 0);
                let start = picks.len();
                let entry = match relation.picks(&state, i, &mut scratch, &mut picks) {
                    Ok((width, ready)) => Entry {
                        start: start as u32,
                        len: (picks.len() - start) as u32,
                        width: width as u16,
                        ready,
                        // (no interaction has so many participants)
                        known: u16::try_from(width).is_ok(),
                    },
                    Err(_) => {
                        picks.truncate(start);
                        Entry::default()
                    }
                };
                t.entries.push(entry);
                // give up on a table as soon as it is too large (no interaction has more
                // than `choices::MAX_CHOICES` steps in one state)
                if picks.len() > MAX_PICKS {
                    fits = false;
                    break;
                }
            }
            if !fits {
                t.entries.truncate(entries_start);
                picks.truncate(picks_start);
                continue;
            }
            // an interaction that reads the same slots as the one tabulated before it (a
            // codel's error path after its run) shares its digits, so that one key serves
            // both ([`StepTables::lookup_sharing`])
            let digits = match last_digits {
                Some((a, b)) if t.digits[a as usize..b as usize] == d.digits[..] => (a, b),
                _ => {
                    let start = t.digits.len() as u32;
                    t.digits.extend_from_slice(&d.digits);
                    (start, t.digits.len() as u32)
                }
            };
            last_digits = Some(digits);
            t.of[i as usize] = Table {
                digits,
                entries: entries_start as u32,
                // at most MAX_TABLE
                size: d.size as u32,
            };
        }
        t.picks = picks.into();
        t
    }

    /// The tabulated steps of interaction `i` in a state, if it has a table and an entry
    /// for the state's values. Between calls that pass the same `last` the state must stay
    /// the same (`last` is reset to [`LastKey::NONE`] when it changes): an interaction that
    /// reads the same slots as the one looked up before it reuses its key.
    #[inline(always)]
    pub(crate) fn lookup_sharing(
        &self,
        i: u32,
        slots: &[i64],
        last: &mut LastKey,
    ) -> Option<&Entry> {
        let table = *self.of.get(i as usize)?;
        if table.entries == NONE {
            return None;
        }
        let key = if last.digits == table.digits {
            last.key?
        } else {
            let (a, b) = table.digits;
            let k = key(&self.digits[a as usize..b as usize], slots, 0);
            *last = LastKey {
                digits: table.digits,
                key: k,
            };
            k?
        };
        let e = &self.entries[table.entries as usize + key as usize];
        e.known.then_some(e)
    }

    /// The digits of interaction `i`'s table key (slots of the state, none local), if it
    /// has a table. Slots of one value are no digit: the key does not read them.
    pub(crate) fn key_digits(&self, i: u32) -> Option<&[Digit]> {
        let table = self.of.get(i as usize)?;
        let (a, b) = table.digits;
        (table.entries != NONE).then(|| &self.digits[a as usize..b as usize])
    }

    /// The picks of an entry's steps, one step after the other.
    #[inline(always)]
    pub(crate) fn picks(&self, e: &Entry) -> &[Pick] {
        &self.picks[e.start as usize..(e.start + e.len) as usize]
    }

    /// Every tabulated step: its interaction, where its picks start in the pool, and how
    /// many picks it has.
    pub(crate) fn pooled_steps(&self) -> impl Iterator<Item = (u32, u32, u32)> + '_ {
        self.of.iter().enumerate().flat_map(move |(i, t)| {
            let (start, n) = match t.entries {
                NONE => (0, 0),
                e => (e as usize, t.size as usize),
            };
            let entries = self.entries[start..start + n].iter();
            entries
                .filter(|e| e.known && e.width > 0)
                .flat_map(move |e| {
                    let w = u32::from(e.width);
                    (e.start..e.start + e.len)
                        .step_by(w as usize)
                        .map(move |at| (i as u32, at, w))
                })
        })
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
