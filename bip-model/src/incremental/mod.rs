//! The enabled steps of a state, kept up to date as the state moves.
//!
//! [`System::enabled_steps`] evaluates every interaction in every state. A runtime engine
//! takes one step at a time, and a step writes a few slots: only the interactions that
//! read those slots can change. [`EnabledSet`] caches, per interaction, its steps before
//! priorities, and after a step re-evaluates only the interactions that read a slot that
//! changed where the read matters (a participant's location; a variable that a guard of a
//! participant's transitions on its port reads, while the participant is where those
//! transitions start; a slot the connector's guard reads, while a required participant
//! is where it has transitions on its port and every required port had an enabled
//! transition when the interaction was last evaluated), as the full relation does: from
//! the interaction's step table where it has one, else with
//! [`System::compute_interaction_picks`]; priorities are applied by looking
//! up, for a lower interaction, whether one of its higher interactions has steps (a sparse
//! bit mask per lower interaction), or by the relation's own search for the interactions
//! the masks leave to it (those below a `when`). It is not a second notion of "enabled": it
//! yields exactly the steps of [`System::enabled_steps`], in the same order (a property
//! test checks it on random systems), only computed from a cache.
//!
//! A step with a fire plan ([`crate::FirePlans`]) is known before it is taken: where its
//! participants go and the constants it writes. [`EnabledSet::update_planned`] uses what
//! [`EnabledSet::plan_effects`] worked out from that once per plan ([`PlanEffects`]): the
//! steps of the interactions whose table key the plan fixes are stored without looking,
//! and the interactions a written slot marks where the watched component takes part are
//! listed per slot. The rest is read from the state as above.
//!
//! An interaction that is higher in no priority and that priorities suppress now cannot
//! change anything the set answers, so it is not evaluated until it is no longer
//! suppressed (it is "stale" meanwhile). In a GenoM layer that is the tick and the
//! requests while a codel is due: most of what a codel step would otherwise re-evaluate.
//!
//! This module holds the set, its full evaluation and the evaluation of one interaction or
//! component; `update` brings it from one state to the next, `queries` answers what is
//! enabled.

#[allow(unused_imports)]
use crate::prelude::*;

mod queries;
mod update;

use alloc::sync::Arc;

use crate::enable_index::Read;
use crate::found::Found;
use crate::model::RangeError;
use crate::priority_masks::{bit, set_bit, PriorityMasks};
use crate::state::State;
use crate::step_tables::LastKey;
use crate::steps::{Choices, Pick, PrioritySearch};
use crate::system::System;
use crate::watches::{location_bit, Dep, Watches, ANYWHERE};

pub use queries::Enabled;

/// The enabled steps of one state of one system (after priorities), maintained
/// incrementally with [`EnabledSet::update`].
///
/// After [`EnabledSet::new`] or [`EnabledSet::reset`] has sized its buffers, updates
/// allocate nothing unless an interaction has more steps than it ever had.
#[derive(Clone, Debug)]
pub struct EnabledSet {
    // ---- tables of the system (fixed) ----
    /// Per slot, the component it belongs to.
    slot_comp: Vec<u32>,
    /// Per component, whether its atom has internal transitions (none in a GenoM layer),
    /// and whether any has.
    has_internal: Vec<bool>,
    any_internal: bool,
    /// Per slot, the interactions whose steps (before priorities) depend on it: a
    /// participant's location, a variable that a guard of a participant's transitions on its
    /// port reads (while the participant is where those transitions start), a slot the
    /// connector's guard reads (while a required participant is where it has transitions
    /// on its port).
    watches: Watches,
    /// The system's priorities as sparse masks over `pre`.
    masks: PriorityMasks,

    // ---- the state's enabled steps ----
    /// Per interaction, what its last evaluation found (see [`Found`]); its picks are in
    /// `pool` (the system's step tables) or in `picks` (computed).
    found: Box<[Found]>,
    picks: Vec<Vec<Pick>>,
    pool: Arc<[Pick]>,
    /// Interactions with steps before priorities (one bit each).
    pre: Box<[u64]>,
    /// Lazy interactions not evaluated since they were suppressed: their `found`,
    /// `picks` and `pre` bit are out of date (and do not matter while they stay suppressed).
    stale: Box<[u64]>,
    /// Per searched interaction (see `priority_masks`): suppressed in this state.
    search_suppressed: Box<[u64]>,
    /// Per component, its enabled internal transitions.
    internal: Vec<Vec<Pick>>,

    // ---- scratch ----
    scratch: Choices,
    search: PrioritySearch,
    stamp: Vec<u32>,
    comp_stamp: Vec<u32>,
    epoch: u32,
    dirty: Vec<u32>,
    /// The last step table key computed, valid while the state stays the same (reset by
    /// each update and reset).
    last_key: LastKey,
    /// False after an update failed: the set must be [`EnabledSet::reset`].
    valid: bool,
}

impl EnabledSet {
    /// The enabled steps of `state`, evaluated in full.
    pub fn new(system: &System, state: &State) -> Result<EnabledSet, RangeError> {
        let mut set = EnabledSet::unevaluated(system);
        set.reset(system, state)?;
        Ok(set)
    }

    /// The set's tables for `system`, with no state evaluated yet (as a failed
    /// [`EnabledSet::reset`] leaves it): [`EnabledSet::is_valid`] is false.
    pub(crate) fn unevaluated(system: &System) -> EnabledSet {
        let n_inter = system.interactions.len();
        let n_comp = system.components.len();
        let words = n_inter.div_ceil(64);

        let n_slots = system.slot_count();
        let mut slot_comp = vec![0u32; n_slots];
        for (c, comp) in system.components.iter().enumerate() {
            let end = system
                .components
                .get(c + 1)
                .map_or(n_slots, |next| next.slot as usize);
            slot_comp[comp.slot as usize..end].fill(c as u32);
        }

        // slot -> interactions whose steps read it, each with where the read matters
        let mut per_slot: Vec<Vec<Dep>> = vec![Vec::new(); n_slots];
        // the locations of a participant from which it has transitions on its port
        let ready_at = |p: &crate::model::PortRef| {
            let atom = system.atom_of(p.component);
            let from = atom.transitions.iter().filter(|t| t.port == Some(p.port));
            from.fold(0u64, |m, t| m | location_bit(t.from))
        };
        for (i, inter) in system.interactions.iter().enumerate() {
            let i = i as u32;
            let mut add = |s: u32, watch: u32, locations: u64, connector_only: bool| {
                let list = &mut per_slot[s as usize];
                let same = |d: &&mut Dep| {
                    d.interaction == i && d.watch == watch && d.connector_only == connector_only
                };
                match list.iter_mut().find(same) {
                    Some(d) => d.locations |= locations,
                    None => list.push(Dep {
                        interaction: i,
                        watch,
                        locations,
                        connector_only,
                    }),
                }
            };
            // the connector's guard matters only where a required participant is ready:
            // watch the one ready in the fewest locations
            let required = inter
                .ports
                .iter()
                .enumerate()
                .filter(|(k, _)| inter.trigger.is_none_or(|tr| tr as usize == *k));
            let watched = required
                .map(|(_, p)| (ready_at(p), system.components[p.component as usize].slot))
                .min_by_key(|(m, _)| m.count_ones());
            let (connector_at, connector_watch) = watched.unwrap_or((ANYWHERE, 0));
            system.interaction_reads(i, &mut |s, read| match read {
                Read::Location { port } => {
                    let slot = system.components[inter.ports[port].component as usize].slot;
                    add(s, slot, ANYWHERE, false);
                }
                // a transition's guard matters only where the transition starts (an
                // atom's guards read only its own variables; anything else, anywhere)
                Read::Guard { port, from } => {
                    let p = inter.ports[port];
                    let own = slot_comp[s as usize] == p.component;
                    let at = if own { location_bit(from) } else { ANYWHERE };
                    let slot = system.components[p.component as usize].slot;
                    add(s, slot, at, false);
                }
                Read::Connector => add(s, connector_watch, connector_at, true),
            });
        }
        let watches = Watches::new(&per_slot, |slot| {
            (system.slot_ranges()[slot as usize].1 + 1).clamp(1, i64::from(u32::MAX)) as u32
        });

        let has_internal: Vec<bool> = system
            .components
            .iter()
            .map(|c| {
                let atom = &system.atoms[c.atom as usize];
                atom.transitions.iter().any(|t| t.port.is_none())
            })
            .collect();
        let any_internal = has_internal.iter().any(|&h| h);
        EnabledSet {
            slot_comp,
            any_internal,
            has_internal,
            watches,
            masks: system.priority_masks.clone(),
            picks: vec![Vec::new(); n_inter],
            pool: system.enable_index.tables.pool(),
            found: vec![Found::default(); n_inter].into_boxed_slice(),
            pre: vec![0; words].into_boxed_slice(),
            stale: vec![0; words].into_boxed_slice(),
            search_suppressed: vec![0; words].into_boxed_slice(),
            internal: vec![Vec::new(); n_comp],
            scratch: Choices::default(),
            search: PrioritySearch::default(),
            stamp: vec![0; n_inter],
            comp_stamp: vec![0; n_comp],
            epoch: 0,
            dirty: Vec::with_capacity(n_inter),
            last_key: LastKey::NONE,
            valid: false,
        }
    }

    /// Re-evaluates everything for `state` (after an error, or to jump to another state).
    pub fn reset(&mut self, system: &System, state: &State) -> Result<(), RangeError> {
        self.valid = false;
        self.last_key = LastKey::NONE;
        self.pre.fill(0);
        self.search_suppressed.fill(0);
        for p in &mut self.picks {
            p.clear();
        }
        self.found.fill(Found::default());
        for c in 0..system.components.len() as u32 {
            self.eval_internal(system, state, c)?;
        }
        // the lazy ones are left for `settle`, once the others are known
        self.stale.copy_from_slice(&self.masks.lazy);
        for i in 0..system.interactions.len() as u32 {
            if !bit(&self.masks.lazy, i) {
                self.eval_interaction(system, state, i)?;
            }
        }
        self.settle(system, state)?;
        self.valid = true;
        Ok(())
    }

    /// True if everything the set knows of its state is in its [`Evaluation`]: no
    /// internal transitions, and every interaction with steps has them in the pool (the
    /// picks computed for the others are not part of an evaluation).
    pub(crate) fn fits_evaluation(&self) -> bool {
        self.valid && !self.any_internal && self.found.iter().all(|f| f.in_pool || f.width == 0)
    }

    /// Exchanges what the set knows of its state with `e`, an evaluation of the same
    /// system that [`EnabledSet::save_evaluation`] filled (the set then describes the
    /// state `e` was saved from, if [`EnabledSet::fits_evaluation`] held then).
    #[inline]
    pub(crate) fn exchange_evaluation(&mut self, e: &mut Evaluation) {
        core::mem::swap(&mut self.found, &mut e.found);
        core::mem::swap(&mut self.pre, &mut e.pre);
        core::mem::swap(&mut self.stale, &mut e.stale);
        core::mem::swap(&mut self.search_suppressed, &mut e.search_suppressed);
        // the key found last is of the state before
        self.last_key = LastKey::NONE;
    }

    /// Copies what the set knows of its state into `e` (reusing its buffers).
    pub(crate) fn save_evaluation(&self, e: &mut Evaluation) {
        fn copy<T: Copy>(to: &mut Box<[T]>, from: &[T]) {
            if to.len() == from.len() {
                to.copy_from_slice(from);
            } else {
                *to = from.into();
            }
        }
        copy(&mut e.found, &self.found);
        copy(&mut e.pre, &self.pre);
        copy(&mut e.stale, &self.stale);
        copy(&mut e.search_suppressed, &self.search_suppressed);
    }

    fn eval_internal(&mut self, system: &System, state: &State, c: u32) -> Result<(), RangeError> {
        let out = &mut self.internal[c as usize];
        out.clear();
        system.internal_picks(state, c, out)
    }

    /// The steps of interaction `i` computed from the state, into `picks` (out of line:
    /// most interactions have step tables).
    #[inline(never)]
    fn compute_interaction(
        &mut self,
        system: &System,
        state: &State,
        i: u32,
    ) -> Result<Found, RangeError> {
        let picks = &mut self.picks[i as usize];
        picks.clear();
        let (width, ready) =
            system.compute_interaction_picks(state, i, &mut self.scratch, picks)?;
        Ok(Found {
            width: width as u32,
            ready,
            ..Found::default()
        })
    }

    #[inline(always)]
    fn eval_interaction(
        &mut self,
        system: &System,
        state: &State,
        i: u32,
    ) -> Result<(), RangeError> {
        let tables = &system.enable_index.tables;
        let found = match tables.lookup_sharing(i, state.slots(), &mut self.last_key) {
            Some(e) => Found::of(e),
            None => self.compute_interaction(system, state, i)?,
        };
        self.store(i, found);
        Ok(())
    }

    #[inline(always)]
    fn store(&mut self, i: u32, found: Found) {
        set_bit(&mut self.pre, i, found.width > 0);
        self.found[i as usize] = found;
    }

    /// True if an interaction above `i` in the masks has steps.
    #[inline]
    fn blocked(&self, i: u32) -> bool {
        self.masks.blocked(i, &self.pre)
    }

    /// Decides suppression of the enabled searched interactions.
    #[inline(never)]
    fn decide_searched(&mut self, system: &System, state: &State) -> Result<(), RangeError> {
        system.search_suppressed(
            state,
            &self.pre,
            &mut self.search,
            &mut self.search_suppressed,
        )
    }
}

/// What an [`EnabledSet`] knows of the state it describes, apart from its tables: per
/// interaction what its last evaluation found, and the bits of those with steps, of the
/// stale ones and of the searched ones suppressed. [`crate::StateCache`] keeps one per
/// state it knows.
#[derive(Clone, Debug, Default)]
pub(crate) struct Evaluation {
    found: Box<[Found]>,
    pre: Box<[u64]>,
    stale: Box<[u64]>,
    search_suppressed: Box<[u64]>,
}

impl Evaluation {
    /// The bytes its buffers hold.
    pub(crate) fn bytes(&self) -> usize {
        self.found.len() * core::mem::size_of::<Found>()
            + (self.pre.len() + self.stale.len() + self.search_suppressed.len()) * 8
    }
}
