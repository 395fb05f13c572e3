//! The firings of the tabulated steps, compiled once.
//!
//! [`System::fire_in_place`] finds, for each pick of a step, its transition's action and
//! move in the system's tables, and records every slot it writes as it goes. A runtime
//! engine fires the same few steps over and over, and most of them come from the step
//! tables' pool ([`crate::EnabledSet::pooled_steps`]): [`FirePlans`] lists, once per pooled
//! step, what firing it does ([`System::fire_ops`], the same sequence `fire_in_place`
//! runs), with the moves and the constant assignments folded into plain writes, and the
//! slots it writes. [`System::fire_planned`] then runs the list. It is the same firing,
//! looked up ahead of time: an action that reads the state still runs as an action, and
//! an assignment whose constant is out of its variable's range is left to the action,
//! which reports the error.

#[allow(unused_imports)]
use crate::prelude::*;

use alloc::collections::BTreeMap;

use crate::fast_path::ActionCode;
use crate::model::RangeError;
use crate::state::State;
use crate::step::{ActionOf, FireOp};
use crate::steps::{Label, Pick, Step};
use crate::system::System;

/// No plan.
const NONE: u32 = u32::MAX;

/// A plan of [`FirePlans`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlanId(u32);

impl PlanId {
    /// Its position among the plans, as [`FirePlans::steps`] lists them: for a caller
    /// keeping something per plan.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// What firing each step of a system's step tables does (see the module documentation).
#[derive(Clone, Debug, Default)]
pub struct FirePlans {
    /// Per position in the pool of picks: the plan of the step starting there (one
    /// `u32` per pick of the pool, 4 MiB at the pool's budget: a lookup without search).
    at: Vec<u32>,
    plans: Vec<Plan>,
    ops: Vec<PlanOp>,
    written: Vec<u32>,
}

#[derive(Clone, Copy, Debug)]
struct Plan {
    interaction: u32,
    /// Where its picks are in the pool (a step of the same picks elsewhere shares it).
    picks: (u32, u32),
    ops: (u32, u32),
    written: (u32, u32),
}

#[derive(Clone, Copy, Debug)]
enum PlanOp {
    /// A move, or an assignment of a constant in range.
    Set { slot: u32, value: i64 },
    /// An action with a table of the values it writes: they go to
    /// `written[slots.0..slots.1]` (the action runs where the table has no entry).
    Table {
        code: ActionCode,
        base: u32,
        slots: (u32, u32),
        who: ActionOf,
    },
    Action {
        code: ActionCode,
        base: u32,
        who: ActionOf,
    },
}

impl FirePlans {
    /// The plan of the step of interaction `i` whose picks are `pool[at..at + width]` in
    /// the step tables' pool, as [`crate::EnabledSet::pooled_steps`] and
    /// [`crate::EnabledSet::pool_position`] locate a step of an [`crate::EnabledSet`] of
    /// this plans' system (`at` from anywhere else names nothing or another step);
    /// `None` if no step of `i` with `width` picks starts there. Nothing is compared but
    /// the place: each pick of the pool belongs to one step table entry, and the plan of
    /// a place is the plan of the step that starts there (the plan's own picks may be
    /// elsewhere: identical steps share one).
    #[inline]
    pub fn plan_at(&self, at: u32, width: u32, i: u32) -> Option<PlanId> {
        let p = *self.at.get(at as usize)?;
        let plan = self.plans.get(p as usize)?;
        let (a, b) = plan.picks;
        (plan.interaction == i && b - a == width).then_some(PlanId(p))
    }

    /// Every slot the plan's step writes, in the order [`System::fire_in_place`] lists
    /// them.
    #[inline]
    pub fn written(&self, p: PlanId) -> &[u32] {
        let (a, b) = self.plans[p.0 as usize].written;
        &self.written[a as usize..b as usize]
    }

    /// The step of plan `p`: its interaction, and where its picks are in the pool and
    /// how many (the first place, where identical steps share the plan).
    pub fn step(&self, p: PlanId) -> (u32, u32, u32) {
        let plan = &self.plans[p.0 as usize];
        (plan.interaction, plan.picks.0, plan.picks.1 - plan.picks.0)
    }

    /// [`FirePlans::step`] of every plan, in the order of [`PlanId::index`].
    pub fn steps(&self) -> impl Iterator<Item = (u32, u32, u32)> + '_ {
        (0..self.plans.len() as u32).map(|p| self.step(PlanId(p)))
    }

    /// Every plan, in the order of [`PlanId::index`].
    pub fn ids(&self) -> impl Iterator<Item = PlanId> {
        (0..self.plans.len() as u32).map(PlanId)
    }

    /// How many distinct steps have a plan.
    pub fn len(&self) -> usize {
        self.plans.len()
    }

    /// True if no step has a plan.
    pub fn is_empty(&self) -> bool {
        self.plans.is_empty()
    }
}

impl System {
    /// The plans of every step in the system's step tables.
    pub fn fire_plans(&self) -> FirePlans {
        let tables = &self.enable_index.tables;
        let pool = tables.pool();
        let mut out = FirePlans {
            at: vec![NONE; pool.len()],
            ..FirePlans::default()
        };
        // identical steps (of one interaction, in several entries) share a plan
        let mut seen: BTreeMap<(u32, Vec<(u32, u32)>), u32> = BTreeMap::new();
        for (i, at, width) in tables.pooled_steps() {
            let picks = &pool[at as usize..(at + width) as usize];
            let key = (
                i,
                picks.iter().map(|p| (p.component, p.transition)).collect(),
            );
            let p = match seen.get(&key) {
                Some(&p) => p,
                None => {
                    let p = out.plans.len() as u32;
                    self.add_plan(&mut out, i, (at, at + width), picks);
                    seen.insert(key, p);
                    p
                }
            };
            out.at[at as usize] = p;
        }
        out
    }

    fn add_plan(&self, out: &mut FirePlans, i: u32, at: (u32, u32), picks: &[Pick]) {
        let (ops0, written0) = (out.ops.len() as u32, out.written.len() as u32);
        let flat = &self.enable_index.flat;
        let step = Step {
            label: Label::Interaction(i),
            picks,
        };
        let recorded = self.fire_ops(step, |op| {
            match op {
                FireOp::Move { slot, to } => {
                    out.ops.push(PlanOp::Set {
                        slot,
                        value: i64::from(to),
                    });
                    out.written.push(slot);
                }
                FireOp::Action { code, base, who } => {
                    let assigns = flat.assigns(code);
                    let constants: Option<Vec<(u32, i64)>> = assigns
                        .iter()
                        .map(|a| {
                            let slot = a.slot(base);
                            let (lo, hi) = self.slot_ranges[slot as usize];
                            a.constant()
                                .filter(|v| (lo..=hi).contains(v))
                                .map(|v| (slot, v))
                        })
                        .collect();
                    let first = out.written.len() as u32;
                    out.written.extend(assigns.iter().map(|a| a.slot(base)));
                    let slots = (first, out.written.len() as u32);
                    // an `advance` is evaluated and checked where the step fires
                    let advance = match who {
                        ActionOf::Interaction(i) => self.interactions[i as usize].advance.is_some(),
                        ActionOf::Transition(_) => false,
                    };
                    if advance {
                        out.ops.push(PlanOp::Action { code, base, who });
                    } else if let Some(c) = constants {
                        // in order: a later assignment of the same slot wins, as it does
                        // when the action runs
                        let set = c
                            .into_iter()
                            .map(|(slot, value)| PlanOp::Set { slot, value });
                        out.ops.extend(set);
                    } else if code.has_table() {
                        out.ops.push(PlanOp::Table {
                            code,
                            base,
                            slots,
                            who,
                        });
                    } else {
                        out.ops.push(PlanOp::Action { code, base, who });
                    }
                }
            }
            Ok(())
        });
        // the closure records and never fails
        debug_assert!(recorded.is_ok());
        out.plans.push(Plan {
            interaction: i,
            picks: at,
            ops: (ops0, out.ops.len() as u32),
            written: (written0, out.written.len() as u32),
        });
    }

    /// What slots hold after firing plan `p`'s step from a state in which it is enabled,
    /// where that does not depend on the state: each written slot (and each participant's
    /// location, written or not) with its value, or `None` if an action computes it from
    /// the state (a step whose firing fails leads nowhere, so an action's constants are
    /// known even where the rest of it reads the state). A participant that stays where it is was there before: at the start of
    /// its transition.
    pub(crate) fn plan_after(&self, plans: &FirePlans, p: PlanId) -> BTreeMap<u32, Option<i64>> {
        let plan = &plans.plans[p.0 as usize];
        let pool = self.enable_index.tables.pool();
        let mut after = BTreeMap::new();
        for pick in &pool[plan.picks.0 as usize..plan.picks.1 as usize] {
            let to = self.atom_of(pick.component).transitions[pick.transition as usize].to;
            let slot = self.components[pick.component as usize].slot;
            after.insert(slot, Some(i64::from(to)));
        }
        // in firing order: a later write of a slot wins. An action writes its constants
        // whenever it runs without failing (and a step whose action fails goes nowhere)
        let flat = &self.enable_index.flat;
        for op in &plans.ops[plan.ops.0 as usize..plan.ops.1 as usize] {
            match *op {
                PlanOp::Set { slot, value } => {
                    after.insert(slot, Some(value));
                }
                PlanOp::Table { code, base, .. } | PlanOp::Action { code, base, .. } => {
                    for a in flat.assigns(code) {
                        after.insert(a.slot(base), a.constant());
                    }
                }
            }
        }
        after
    }

    /// Fires the step of plan `p` on `state` in place, as [`System::fire_in_place`] would;
    /// the slots it may write are [`FirePlans::written`]. On a range error, `state` holds
    /// a partial result. `plans` must be this system's ([`System::fire_plans`]) and `p`
    /// one of its plans ([`FirePlans::plan_at`]).
    #[inline]
    pub fn fire_planned(
        &self,
        plans: &FirePlans,
        p: PlanId,
        state: &mut State,
    ) -> Result<(), RangeError> {
        let (a, b) = plans.plans[p.0 as usize].ops;
        let flat = &self.enable_index.flat;
        for op in &plans.ops[a as usize..b as usize] {
            match *op {
                PlanOp::Set { slot, value } => state.slots_mut()[slot as usize] = value,
                PlanOp::Table {
                    code,
                    base,
                    slots: (s0, s1),
                    who,
                } => match flat.action_values(code, state.slots(), base) {
                    // the whole action's values, in range (as `run_action` takes them)
                    Some(values) => {
                        let slots = &plans.written[s0 as usize..s1 as usize];
                        for (&slot, &v) in slots.iter().zip(values) {
                            state.slots_mut()[slot as usize] = v;
                        }
                    }
                    None => self.run_who(code, base, who, state, &mut ())?,
                },
                PlanOp::Action { code, base, who } => {
                    self.run_who(code, base, who, state, &mut ())?
                }
            }
        }
        Ok(())
    }
}
