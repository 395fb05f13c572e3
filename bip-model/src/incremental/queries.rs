//! What an [`EnabledSet`] answers: the enabled interactions (after priorities) and their
//! steps, read from the set without evaluating anything.

#[allow(unused_imports)]
use crate::prelude::*;

use crate::priority_masks::bit;
use crate::steps::{Label, Pick, Step, Steps};

use super::EnabledSet;

impl EnabledSet {
    /// True unless the last update or reset failed.
    pub fn is_valid(&self) -> bool {
        self.valid
    }

    /// True if interaction `i` has steps before priorities are applied; `None` if the
    /// set did not evaluate it because it is suppressed and higher in no priority.
    pub fn has_steps_before_priorities(&self, i: u32) -> Option<bool> {
        (!bit(&self.stale, i)).then(|| bit(&self.pre, i))
    }

    /// True if interaction `i` has enabled steps (after priorities).
    #[inline(always)]
    pub fn is_enabled(&self, i: u32) -> bool {
        bit(&self.pre, i) && !self.is_suppressed(i)
    }

    #[inline]
    fn is_suppressed(&self, i: u32) -> bool {
        if bit(&self.masks.searched, i) {
            bit(&self.search_suppressed, i)
        } else {
            self.blocked(i)
        }
    }

    /// The interactions with enabled steps (after priorities), in index order.
    pub fn interactions(&self) -> Enabled<'_> {
        self.enabled_among(None)
    }

    /// The interactions with enabled steps (after priorities) among those whose bit is set
    /// in `mask` (bit `i % 64` of word `i / 64` for interaction `i`), in index order.
    /// Cheaper than filtering [`EnabledSet::interactions`]: priorities are looked at only
    /// for the interactions in the mask.
    pub fn interactions_in<'a>(&'a self, mask: &'a [u64]) -> Enabled<'a> {
        self.enabled_among(Some(mask))
    }

    fn enabled_among<'a>(&'a self, mask: Option<&'a [u64]>) -> Enabled<'a> {
        Enabled {
            set: self,
            mask,
            word: 0,
            bits: 0,
        }
    }

    /// The steps of interaction `i` (none if it is not enabled after priorities).
    pub fn steps_of(&self, i: u32) -> impl Iterator<Item = Step<'_>> + '_ {
        let enabled = self.is_enabled(i);
        let f = self.found[i as usize];
        let w = f.width.max(1) as usize;
        let picks: &[Pick] = if !enabled {
            &[]
        } else if f.in_pool {
            &self.pool[f.start as usize..(f.start + f.len) as usize]
        } else {
            &self.picks[i as usize]
        };
        picks.chunks(w).map(move |p| Step {
            label: Label::Interaction(i),
            picks: p,
        })
    }

    /// Where the steps of interaction `i` are in [`EnabledSet::pool`] (the start, the
    /// number of picks per step, and the number of steps), if it is enabled and they come
    /// from its step table. The pool never changes, so two states in which `i`'s steps
    /// start at the same place have the same steps: a caller may remember what it found
    /// among them.
    #[inline]
    pub fn pooled_steps(&self, i: u32) -> Option<(u32, u32, u32)> {
        let f = self.found[i as usize];
        // enabled means it has steps (`pre` is set exactly when `width > 0`)
        (f.in_pool && self.is_enabled(i)).then(|| (f.start, f.width, f.len / f.width))
    }

    /// Where the picks of a step that [`EnabledSet::steps_of`] gave start in
    /// [`EnabledSet::pool`], if they are in it (the step came from a step table); `None`
    /// for picks anywhere else. It compares addresses only and reads nothing.
    #[inline]
    pub fn pool_position(&self, picks: &[Pick]) -> Option<u32> {
        let size = core::mem::size_of::<Pick>();
        let base = self.pool.as_ptr() as usize;
        let at = picks.as_ptr() as usize;
        (at >= base && at < base + self.pool.len() * size).then(|| ((at - base) / size) as u32)
    }

    /// The picks of every step table entry (see [`EnabledSet::pooled_steps`]).
    pub fn pool(&self) -> &[Pick] {
        &self.pool
    }

    /// The enabled internal transitions, by component then transition.
    pub fn internal_steps(&self) -> impl Iterator<Item = Step<'_>> + '_ {
        self.internal.iter().enumerate().flat_map(|(c, picks)| {
            picks.chunks(1).map(move |p| Step {
                label: Label::Internal {
                    component: c as u32,
                },
                picks: p,
            })
        })
    }

    /// Every enabled step, in the order of [`System::enabled_steps`](crate::System::enabled_steps).
    pub fn steps(&self) -> impl Iterator<Item = Step<'_>> + '_ {
        self.internal_steps()
            .chain(self.interactions().flat_map(move |i| self.steps_of(i)))
    }

    /// Writes the enabled steps into `out`, as [`System::enabled_steps`](crate::System::enabled_steps) would.
    pub fn copy_to(&self, out: &mut Steps) {
        out.clear();
        for s in self.steps() {
            out.push(s.label, s.picks.iter().copied());
        }
    }

    /// True if no step is enabled.
    pub fn is_empty(&self) -> bool {
        self.internal.iter().all(Vec::is_empty) && self.interactions().next().is_none()
    }
}

/// The interactions with enabled steps (after priorities), in index order, optionally
/// among those of a mask: [`EnabledSet::interactions`], [`EnabledSet::interactions_in`].
#[derive(Clone, Debug)]
pub struct Enabled<'a> {
    set: &'a EnabledSet,
    mask: Option<&'a [u64]>,
    /// The next word of `pre` to load.
    word: usize,
    /// The candidates of word `word - 1` not yet looked at.
    bits: u64,
}

impl Iterator for Enabled<'_> {
    type Item = u32;

    #[inline]
    fn next(&mut self) -> Option<u32> {
        loop {
            while self.bits != 0 {
                let i = ((self.word - 1) * 64) as u32 + self.bits.trailing_zeros();
                self.bits &= self.bits - 1;
                if !self.set.is_suppressed(i) {
                    return Some(i);
                }
            }
            let pre = self.set.pre.get(self.word)?;
            self.bits = match self.mask {
                None => *pre,
                Some(m) => pre & m.get(self.word).copied().unwrap_or(0),
            };
            self.word += 1;
        }
    }
}
