//! Building a [`System`] from what a compiler resolved: the parts a model states, and the
//! tables the step relation reads, derived from them here and nowhere else.

#[allow(unused_imports)]
use crate::prelude::*;

use core::ops::Range;

use crate::genom::GenomMap;
use crate::priority_masks::PriorityMasks;
use crate::state::{State, StateLayout};
use crate::step::EnableIndex;
use crate::step_tables::StepTables;
use crate::system::{
    Atom, Component, Connector, Family, Interaction, PriorityRule, Property, System, Transition,
    Var,
};

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
    /// The transitive closure of the declared priorities.
    pub priorities: Vec<PriorityRule>,
    /// How many priorities the file declares.
    pub declared_priorities: usize,
    pub properties: Vec<Property>,
    /// The initial value of every slot.
    pub initial: Vec<i64>,
    /// For each slot, the range of values it may hold.
    pub slot_ranges: Vec<(i64, i64)>,
    pub genom: Option<GenomMap>,
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
        let mut rules_by_low = vec![Vec::new(); parts.interactions.len()];
        for (r, rule) in parts.priorities.iter().enumerate() {
            for i in rule.low.clone() {
                rules_by_low[i as usize].push(r as u32);
            }
        }
        let priority_masks =
            PriorityMasks::new(&parts.priorities, &rules_by_low, parts.interactions.len());
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
            declared_priorities: parts.declared_priorities,
            properties: parts.properties,
            layout: StateLayout::new(&parts.slot_ranges),
            initial: State::from_slots(parts.initial),
            rules_by_low,
            slot_ranges: parts.slot_ranges,
            genom: parts.genom,
            enable_index,
            priority_masks,
        };
        system.enable_index.tables = StepTables::build(&system);
        system
    }
}

impl Atom {
    /// An atom type whose transitions are indexed by (location, port); transitions that
    /// share a location and a port keep their written order.
    pub fn new(
        name: String,
        locations: Vec<String>,
        initial: u32,
        ports: Vec<String>,
        vars: Vec<Var>,
        mut transitions: Vec<Transition>,
    ) -> Atom {
        let cols = ports.len() + 1;
        let col = |t: &Transition| t.port.map_or(cols - 1, |p| p as usize);
        transitions.sort_by_key(|t| (t.from as usize, col(t)));
        let mut by_loc_port: Vec<Range<u32>> = vec![0..0; locations.len() * cols];
        for (k, t) in transitions.iter().enumerate() {
            let cell = &mut by_loc_port[t.from as usize * cols + col(t)];
            if cell.start == cell.end {
                *cell = k as u32..k as u32 + 1;
            } else {
                cell.end = k as u32 + 1;
            }
        }
        Atom {
            name,
            locations,
            initial,
            ports,
            vars,
            transitions,
            by_loc_port,
        }
    }
}
