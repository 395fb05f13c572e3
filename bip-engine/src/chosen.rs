//! The step the engine is about to commit.
//!
//! Most steps the engine takes come from the step tables' pool
//! ([`EnabledSet::pooled_steps`]), where their picks stay for the system's lifetime: the
//! engine keeps where they are rather than a copy, and the place also names the step's
//! fire plan ([`bip_model::FirePlans::plan_at`]) without comparing picks. Steps computed
//! by the relation (or given to [`crate::Engine::step_as`]) are copied.

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::{EnabledSet, Pick, Step};

#[derive(Debug, Default)]
pub(crate) struct Chosen {
    /// The picks are `pool[at..at + width]` (`Some((at, width))`), or `copied`.
    pooled: Option<(u32, u32)>,
    copied: Vec<Pick>,
}

impl Chosen {
    pub(crate) fn with_capacity(n: usize) -> Chosen {
        Chosen {
            pooled: None,
            copied: Vec::with_capacity(n),
        }
    }

    /// Chooses `step`'s picks (none if `None`), where they are if they are in `enabled`'s
    /// pool.
    #[inline]
    pub(crate) fn set(&mut self, enabled: &EnabledSet, step: Option<Step<'_>>) {
        self.copied.clear();
        self.pooled = None;
        if let Some(s) = step {
            match enabled.pool_position(s.picks) {
                Some(at) => self.pooled = Some((at, s.picks.len() as u32)),
                None => self.copied.extend_from_slice(s.picks),
            }
        }
    }

    /// Chooses the step `pool[at..at + width]` of the pool.
    #[inline]
    pub(crate) fn set_pooled(&mut self, at: u32, width: u32) {
        self.copied.clear();
        self.pooled = Some((at, width));
    }

    /// Chooses a copy of `picks`.
    pub(crate) fn set_copied(&mut self, picks: &[Pick]) {
        self.pooled = None;
        self.copied.clear();
        self.copied.extend_from_slice(picks);
    }

    /// Where the picks are in the pool, and how many, if they are there.
    #[inline]
    pub(crate) fn pooled(&self) -> Option<(u32, u32)> {
        self.pooled
    }

    /// The picks (`enabled` must be the set the step was chosen from, or a later state of
    /// it: the pool does not change).
    #[inline]
    pub(crate) fn picks<'a>(&'a self, enabled: &'a EnabledSet) -> &'a [Pick] {
        match self.pooled {
            Some((at, width)) => &enabled.pool()[at as usize..(at + width) as usize],
            None => &self.copied,
        }
    }
}
