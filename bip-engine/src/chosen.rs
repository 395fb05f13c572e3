//! The step the engine is about to commit.
//!
//! Most steps the engine takes come from the step tables' pool
//! ([`EnabledSet::pooled_steps`]), where their picks stay for the system's lifetime: the
//! engine keeps where they are rather than a copy, and the place also names the step's
//! fire plan ([`bip_model::GateStep::Pooled`]) without comparing picks. Steps computed by
//! the relation (or given to `Engine::step_as`) are copied.

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::{EnabledSet, GateStep, Label, Pick, Step};

#[derive(Debug)]
pub(crate) struct Chosen {
    label: Label,
    /// The picks are `pool[at..at + width]` (`Some((at, width))`, for an interaction's
    /// step), or `copied`.
    pooled: Option<(u32, u32)>,
    copied: Vec<Pick>,
}

impl Chosen {
    pub(crate) fn with_capacity(n: usize) -> Chosen {
        Chosen {
            label: Label::Interaction(0),
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
            self.label = s.label;
            match (s.label, enabled.pool_position(s.picks)) {
                (Label::Interaction(_), Some(at)) => self.pooled = Some((at, s.picks.len() as u32)),
                _ => self.copied.extend_from_slice(s.picks),
            }
        }
    }

    /// Chooses the step `pool[at..at + width]` of the pool, of interaction `i`.
    #[inline]
    pub(crate) fn set_pooled(&mut self, i: u32, at: u32, width: u32) {
        self.copied.clear();
        self.label = Label::Interaction(i);
        self.pooled = Some((at, width));
    }

    /// Chooses a copy of `step`.
    pub(crate) fn set_copied(&mut self, step: Step<'_>) {
        self.label = step.label;
        self.pooled = None;
        self.copied.clear();
        self.copied.extend_from_slice(step.picks);
    }

    #[inline]
    pub(crate) fn label(&self) -> Label {
        self.label
    }

    /// The step, for [`bip_model::Gate::commit`].
    #[inline]
    pub(crate) fn step(&self) -> GateStep<'_> {
        match (self.label, self.pooled) {
            (Label::Interaction(interaction), Some((at, width))) => GateStep::Pooled {
                interaction,
                at,
                width,
            },
            (label, _) => GateStep::Given(Step {
                label,
                picks: &self.copied,
            }),
        }
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
