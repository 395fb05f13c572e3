//! Building a [`System`] from what a compiler resolved: the parts a model states, and the
//! tables the step relation reads, derived from them here and nowhere else.

#[allow(unused_imports)]
use crate::prelude::*;

use crate::budgets::Budgets;
use crate::enable_index::EnableIndex;
use crate::genom::GenomMap;
use crate::model::{
    Atom, Component, Connector, Family, Interaction, Priority, Property, RangeError,
};
use crate::priority_graph::PriorityGraph;
use crate::priority_masks::{PriorityMasks, MAX_PAIRS};
use crate::state::{State, StateLayout};
use crate::step_tables::{StepTables, Tabulated};
use crate::steps::{Choices, Pick};
use crate::system::System;

/// What a model states once its names are resolved: the input of [`System::new`].
#[derive(Clone, Debug, Default)]
pub struct SystemParts {
    pub name: String,
    /// Real time of one model tick, for the engine's clock.
    pub tick_ms: Option<u64>,
    pub constants: Vec<(String, i64)>,
    pub atoms: Vec<Atom>,
    pub families: Vec<Family>,
    pub components: Vec<Component>,
    pub connectors: Vec<Connector>,
    pub interactions: Vec<Interaction>,
    /// The priorities as declared, without cycles (the closure is the system's).
    pub priorities: Vec<Priority>,
    pub properties: Vec<Property>,
    /// The initial value of every slot.
    pub initial: Vec<i64>,
    /// For each slot, the range of values it may hold.
    pub slot_ranges: Vec<(i64, i64)>,
    pub genom: Option<GenomMap>,
    pub budgets: Budgets,
}

impl System {
    /// The compiled system of `parts`, with the tables its step relation reads.
    ///
    /// The step tables hold the relation's own answers, one per combination of the slots
    /// an interaction reads, so they are computed by the relation of the system without
    /// them; they change how fast steps are found, never which.
    pub fn new(parts: SystemParts) -> System {
        let enable_index = EnableIndex::new(
            &parts.atoms,
            &parts.components,
            &parts.interactions,
            &parts.slot_ranges,
        );
        let priority_graph = PriorityGraph::new(&parts.priorities);
        let priority_masks = PriorityMasks::new(
            &priority_graph,
            &parts.priorities,
            parts.interactions.len(),
            MAX_PAIRS,
            |i| {
                crate::priority_masks::evaluation_cannot_fail(
                    &parts.atoms,
                    &parts.components,
                    &parts.interactions,
                    i,
                )
            },
        );
        let mut system = System {
            name: parts.name,
            tick_ms: parts.tick_ms,
            constants: parts.constants,
            atoms: parts.atoms,
            families: parts.families,
            components: parts.components,
            connectors: parts.connectors,
            interactions: parts.interactions,
            priorities: parts.priorities,
            properties: parts.properties,
            layout: StateLayout::new(&parts.slot_ranges),
            initial: State::from_slots(parts.initial),
            slot_ranges: parts.slot_ranges,
            genom: parts.genom,
            budgets: parts.budgets,
            enable_index,
            priority_graph,
            priority_masks,
        };
        system.enable_index.tables = StepTables::build(&system);
        system
    }
}

impl Tabulated for System {
    fn interactions(&self) -> u32 {
        self.interactions.len() as u32
    }

    fn initial_state(&self) -> State {
        System::initial_state(self)
    }

    fn slot_range(&self, slot: u32) -> Option<(i64, i64)> {
        self.slot_ranges.get(slot as usize).copied()
    }

    fn reads(&self, i: u32, f: &mut dyn FnMut(u32)) {
        self.interaction_reads(i, &mut |s, _| f(s));
    }

    fn picks(
        &self,
        state: &State,
        i: u32,
        scratch: &mut Choices,
        picks: &mut Vec<Pick>,
    ) -> Result<(usize, bool), RangeError> {
        self.compute_interaction_picks(state, i, scratch, picks)
    }
}
