//! The gate of a runtime engine: a state of the model, its enabled steps, and the one way
//! to move it, by a step of those.
//!
//! An engine asks two things of the model, over and over: which steps are enabled now,
//! and the state after the step it chose. [`System::enabled_steps`] and [`System::fire`]
//! answer both, and so does a [`Gate`], much faster, with what bip-model offers to keep
//! up with a state as it moves: an [`EnabledSet`] updated by what a step wrote, the
//! [`FirePlans`] of the pooled steps and their [`PlanEffects`] on the set, and a
//! [`StateCache`] of the states met and the steps between them. Those pieces have a
//! protocol between them (which state the cache's evaluation belongs to, which slots a
//! step wrote, what to do when a step is not known); the gate keeps it, so a caller
//! cannot get it wrong. `tests/suite/gate.rs` compares every state's steps with
//! [`System::enabled_steps`] and every commit with [`System::fire`].

#[allow(unused_imports)]
use crate::prelude::*;

use crate::fire_plan::{FirePlans, PlanId};
use crate::incremental::EnabledSet;
use crate::model::RangeError;
use crate::plan_effects::PlanEffects;
use crate::state::State;
use crate::state_cache::{CacheStats, StateCache};
use crate::steps::{Label, Step};
use crate::system::System;

/// A state of a system and its enabled steps, moved only by committing one of them (see
/// the module documentation).
///
/// Invariants, and why they hold:
/// - `enabled` describes `state`: every commit fires a step into the scratch state and
///   updates the set from the old state to the new one before they change roles. A
///   known step (the cache's) brings both along in one exchange.
/// - `scratch` equals `state` except in the slots `stale` names (the last step's), so a
///   step is fired onto it after copying only those back: the state is never copied
///   whole, and after a commit the state before it is still whole for the caller
///   ([`Gate::previous`]).
/// - The cache's idea of where the set is stays true: a step with a plan is offered to
///   it first ([`StateCache::take_known`]); a step without one, and any other change,
///   is announced with [`StateCache::leave`]; after a step the cache did not know it is
///   told where the set arrived ([`StateCache::arrive`]), and only if the update
///   succeeded (it would link the plan to a state the set does not describe).
/// - A pooled step fires by its plan: the place of its picks in the pool names it, and
///   the plan's effects spare the set reading what the plan makes known. The firing is
///   the same as [`System::fire_in_place`]'s (a debug build checks that the place names
///   the very step).
#[derive(Clone, Debug)]
pub struct Gate {
    system: System,
    state: State,
    scratch: State,
    stale: Last,
    /// The slots [`System::fire_in_place`] wrote, for a step without a plan.
    written: Vec<u32>,
    enabled: EnabledSet,
    plans: FirePlans,
    effects: PlanEffects,
    cache: StateCache,
}

/// Where the slots the last commit wrote are listed.
#[derive(Clone, Copy, Debug)]
enum Last {
    Nothing,
    Known,
    Plan(PlanId),
    Written,
}

/// A step of the gate's current state, by where its picks are.
#[derive(Clone, Copy, Debug)]
pub enum GateStep<'a> {
    /// The step of interaction `interaction` whose picks are `pool[at..at + width]` of
    /// [`EnabledSet::pool`] (as [`EnabledSet::pool_position`] or
    /// [`EnabledSet::pooled_steps`] tell): its plan is found by its place.
    Pooled {
        interaction: u32,
        at: u32,
        width: u32,
    },
    /// Any step, with its picks: fired as the relation says.
    Given(Step<'a>),
}

/// What a commit did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Committed {
    /// The plan the step was fired by (`None`: fired by [`System::fire_in_place`]).
    pub plan: Option<PlanId>,
    /// True if the cache knew the step: the step was looked up, not fired.
    pub known: bool,
}

/// A commit that failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CommitError {
    /// Firing the step is a range error: the gate stays where it was.
    Fire(RangeError),
    /// The step was taken, but the new state's enabled steps cannot be evaluated: the
    /// gate is in the new state, and its enabled steps are unknown until
    /// [`Gate::set_state`].
    Evaluate {
        error: RangeError,
        committed: Committed,
    },
}

impl CommitError {
    pub fn range_error(&self) -> &RangeError {
        match self {
            CommitError::Fire(e) | CommitError::Evaluate { error: e, .. } => e,
        }
    }
}

impl Gate {
    /// A gate at `system`'s initial state, whose cache remembers up to `cache_states`
    /// states (0: none).
    pub fn new(system: System, cache_states: usize) -> Result<Gate, RangeError> {
        match Gate::at_initial(system, cache_states) {
            (gate, None) => Ok(gate),
            (_, Some(e)) => Err(e),
        }
    }

    /// Like [`Gate::new`], but a range error in the initial state's enabled steps still
    /// gives the gate, in the initial state with no enabled steps known (as a failed
    /// [`Gate::set_state`] leaves it), and the error beside it: for a runtime that reports
    /// that error as its first finding, as the verifier does.
    pub fn at_initial(system: System, cache_states: usize) -> (Gate, Option<RangeError>) {
        let state = system.initial_state();
        let mut enabled = EnabledSet::unevaluated(&system);
        let error = enabled.reset(&system, &state).err();
        let plans = system.fire_plans();
        let effects = enabled.plan_effects(&system, &plans);
        let mut cache = StateCache::new(&system, cache_states);
        if error.is_none() {
            cache.enter(&enabled, &state);
        }
        let gate = Gate {
            scratch: state.clone(),
            state,
            stale: Last::Nothing,
            written: Vec::new(),
            enabled,
            plans,
            effects,
            cache,
            system,
        };
        (gate, error)
    }

    #[inline]
    pub fn system(&self) -> &System {
        &self.system
    }

    /// The current state.
    #[inline]
    pub fn state(&self) -> &State {
        &self.state
    }

    /// The state before the last commit (the current one if nothing was committed since
    /// the gate was made or set).
    #[inline]
    pub fn previous(&self) -> &State {
        &self.scratch
    }

    /// The enabled steps of the current state.
    #[inline]
    pub fn enabled(&self) -> &EnabledSet {
        &self.enabled
    }

    /// The plans the gate fires pooled steps by (for a caller keeping something per
    /// plan, by [`PlanId::index`]).
    pub fn plans(&self) -> &FirePlans {
        &self.plans
    }

    /// The slots the last commit changed (at least those; it may list slots it wrote
    /// with the value they had).
    pub fn written(&self) -> &[u32] {
        match self.stale {
            Last::Nothing => &[],
            Last::Known => self.cache.last_changed(),
            Last::Plan(p) => self.plans.written(p),
            Last::Written => &self.written,
        }
    }

    /// Commits `step`, which must be enabled in the current state: the gate moves to
    /// the state it leads to, with that state's enabled steps.
    #[inline]
    pub fn commit(&mut self, step: GateStep<'_>) -> Result<Committed, CommitError> {
        self.catch_up();
        let plan = match step {
            GateStep::Pooled {
                interaction,
                at,
                width,
            } => self.plans.plan_at(at, width, interaction),
            GateStep::Given(_) => None,
        };
        #[cfg(debug_assertions)]
        if let (
            Some(p),
            GateStep::Pooled {
                at,
                width,
                interaction,
            },
        ) = (plan, step)
        {
            // the place named the plan of the very step chosen
            let (pi, p_at, p_width) = self.plans.step(p);
            let pool = self.enabled.pool();
            debug_assert_eq!(pi, interaction);
            debug_assert_eq!(
                &pool[p_at as usize..(p_at + p_width) as usize],
                &pool[at as usize..(at + width) as usize]
            );
        }
        // the steady state of a run is a step the cache knows: kept short, as it is most
        // of an engine's steps
        match plan {
            Some(p) => {
                if self
                    .cache
                    .take_known(p, &mut self.enabled, &mut self.scratch)
                {
                    self.stale = Last::Known;
                    core::mem::swap(&mut self.state, &mut self.scratch);
                    return Ok(Committed { plan, known: true });
                }
            }
            None => self.cache.leave(&self.enabled),
        }
        self.fire_and_update(step, plan)
    }

    /// Fires a step the cache did not know onto the scratch state and brings the set
    /// there.
    #[inline(never)]
    fn fire_and_update(
        &mut self,
        step: GateStep<'_>,
        plan: Option<PlanId>,
    ) -> Result<Committed, CommitError> {
        let committed = Committed { plan, known: false };
        let fired = match (plan, step) {
            (Some(p), _) => self.system.fire_planned(&self.plans, p, &mut self.scratch),
            (None, step) => {
                self.written.clear();
                let step = match step {
                    GateStep::Pooled {
                        interaction,
                        at,
                        width,
                    } => Step {
                        label: Label::Interaction(interaction),
                        picks: &self.enabled.pool()[at as usize..(at + width) as usize],
                    },
                    GateStep::Given(s) => s,
                };
                self.system
                    .fire_in_place(step, &mut self.scratch, &mut self.written)
            }
        };
        if let Err(e) = fired {
            // the scratch state may be half written
            self.scratch.copy_from(&self.state);
            self.stale = Last::Nothing;
            return Err(CommitError::Fire(e));
        }
        self.stale = plan.map_or(Last::Written, Last::Plan);
        let (system, before, after) = (&self.system, &self.state, &self.scratch);
        let updated = match plan {
            Some(p) => self
                .enabled
                .update_planned(system, &self.effects, p, before, after),
            None => self
                .enabled
                .update_written(system, before, after, &self.written),
        };
        if updated.is_ok() {
            let written = match plan {
                Some(p) => self.plans.written(p),
                None => &self.written,
            };
            self.cache.arrive(&self.enabled, before, after, written);
        }
        core::mem::swap(&mut self.state, &mut self.scratch);
        match updated {
            Ok(()) => Ok(committed),
            Err(error) => Err(CommitError::Evaluate { error, committed }),
        }
    }

    /// Brings the scratch state back to the current one, in the slots the last commit
    /// wrote.
    #[inline]
    fn catch_up(&mut self) {
        let written = match self.stale {
            Last::Nothing => return,
            Last::Known => self.cache.last_changed(),
            Last::Plan(p) => self.plans.written(p),
            Last::Written => &self.written,
        };
        let (scratch, state) = (self.scratch.slots_mut(), self.state.slots());
        for &s in written {
            scratch[s as usize] = state[s as usize];
        }
        self.stale = Last::Nothing;
    }

    /// Moves the gate to `state` (of its system), re-evaluating everything. On a range
    /// error the gate is in `state` with no enabled steps known until it is set again.
    pub fn set_state(&mut self, state: &State) -> Result<(), RangeError> {
        self.cache.leave(&self.enabled);
        self.state.copy_from(state);
        self.scratch.copy_from(state);
        self.stale = Last::Nothing;
        self.enabled.reset(&self.system, state)?;
        self.cache.enter(&self.enabled, state);
        Ok(())
    }

    /// Back to the initial state.
    pub fn reset(&mut self) -> Result<(), RangeError> {
        let init = self.system.initial_state();
        self.set_state(&init)
    }

    /// The index of the current state in the cache, if the cache knows it: indices count
    /// from 0 in the order the states were met and a known state is never forgotten, so
    /// a caller may keep what it works out from a state by its index.
    #[inline]
    pub fn cached_state(&self) -> Option<usize> {
        self.cache.current()
    }

    /// What the cache holds and how often it knew the step.
    pub fn cache_stats(&self) -> CacheStats {
        self.cache.stats()
    }

    /// The bytes the cache holds.
    pub fn cache_bytes(&self) -> usize {
        self.cache.bytes()
    }

    /// How the cache gives up when it seldom knows the step
    /// ([`StateCache::rest_policy`]).
    pub fn cache_rest_policy(&mut self, window: u32, rest: u32) {
        self.cache.rest_policy(window, rest);
    }
}
