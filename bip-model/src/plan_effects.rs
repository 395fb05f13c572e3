//! What firing each fire plan does to an [`crate::EnabledSet`], worked out once.
//!
//! After a step, the set re-evaluates the interactions that read a slot that changed
//! where the read matters ([`crate::EnabledSet::update_written`]): for each changed slot it
//! reads, in the new state, the location of each component it watches, and for each
//! interaction it marks it computes a table key from the state. For a step with a fire
//! plan ([`crate::FirePlans`]) much of that is known before the step is ever taken: the
//! participants' new locations, and the values the plan writes as constants (a codel
//! that pauses sets its activity's `paused` flag; a tick clears it). [`PlanEffects`] keeps,
//! per plan and per slot it writes, the interactions a change of that slot marks where
//! the watched location is one of those known ones, and, per plan, the steps of every
//! interaction it may mark whose table key is made only of known values: the entry
//! [`crate::EnabledSet`] would look up is then the same in every state the step leads to.
//! What depends on the state (a watched component that does not take part, a value an
//! action computes) is still read from the state, as `update_written` does.
//! [`crate::EnabledSet::update_planned`] applies it; the result is the same set.

#[allow(unused_imports)]
use crate::prelude::*;

use crate::found::Found;
use crate::watches::Mark;

/// What firing each plan of a [`crate::FirePlans`] does to the
/// [`crate::EnabledSet`]s of its system ([`crate::EnabledSet::plan_effects`]).
#[derive(Clone, Debug, Default)]
pub struct PlanEffects {
    /// Per plan: the slots it writes, `slots[p.0..p.1]`, and its known evaluations,
    /// `found[p.2..p.3]`.
    pub(crate) plans: Vec<(u32, u32, u32, u32)>,
    pub(crate) slots: Vec<SlotEffect>,
    pub(crate) marks: Vec<Mark>,
    pub(crate) dynamic: Vec<u32>,
    /// An interaction and what its evaluation finds in every state the plan leads to.
    pub(crate) found: Vec<(u32, Found)>,
}

/// A slot a plan writes: if it changes, the interactions to mark, `marks[m.0..m.1]`,
/// and the watches whose location the state tells, `dynamic[d.0..d.1]`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SlotEffect {
    pub slot: u32,
    pub marks: (u32, u32),
    pub dynamic: (u32, u32),
}

impl PlanEffects {
    /// How many plans it describes.
    pub fn len(&self) -> usize {
        self.plans.len()
    }

    /// True if it describes no plan.
    pub fn is_empty(&self) -> bool {
        self.plans.is_empty()
    }

    /// How many interactions' evaluations it knows, over all plans (a measure of what
    /// [`crate::EnabledSet::update_planned`] spares).
    pub fn known_evaluations(&self) -> usize {
        self.found.len()
    }
}
