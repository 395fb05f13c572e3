//! The compiled system: every name resolved to a dense index, every expression compiled.
//!
//! A state is a vector of slots (see [`crate::State`]): for each component, in order, one
//! slot for its location and one per variable. The step relation over these states lives in
//! `step.rs`; it is the only one in the project.

#[allow(unused_imports)]
use crate::prelude::*;

use crate::eval::{Env, EvalError, Expr};
use crate::model::{
    Atom, Component, Connector, Family, Interaction, Priority, Property, RangeError,
    RangeErrorKind, Role,
};
use crate::priority_graph::PriorityGraph;
use crate::state::{State, StateLayout};

/// A compiled model.
#[derive(Clone, Debug)]
pub struct System {
    pub name: String,
    /// Real time of one model tick, for the engine's clock.
    pub tick_ms: Option<u64>,
    pub constants: Vec<(String, i64)>,
    pub atoms: Vec<Atom>,
    pub families: Vec<Family>,
    pub components: Vec<Component>,
    pub connectors: Vec<Connector>,
    pub interactions: Vec<Interaction>,
    /// The priorities as declared; the step relation closes them transitively.
    pub priorities: Vec<Priority>,
    pub properties: Vec<Property>,
    pub layout: StateLayout,
    pub(crate) initial: State,
    /// For each slot, the range of values it may hold.
    pub(crate) slot_ranges: Vec<(i64, i64)>,
    /// The GenoM layer the system was expanded from, if any: what the engine binds codels
    /// and sends requests with (docs/genom.md, "The engine's map").
    pub genom: Option<crate::genom::GenomMap>,
    /// The CPUs, and the components that stand for periodic tasks (docs/model.md, "Time
    /// budgets").
    pub budgets: crate::budgets::Budgets,
    /// Flat tables for the step relation's inner loop.
    pub(crate) enable_index: crate::enable_index::EnableIndex,
    /// The priorities as a graph, whose reachability is their closure.
    pub(crate) priority_graph: PriorityGraph,
    /// The closure as sparse bit masks, where it fits, for deciding suppression quickly.
    pub(crate) priority_masks: crate::priority_masks::PriorityMasks,
}

impl System {
    /// The services a client of the GenoM layer may request, as `(module, service)`
    /// (none without a layer): see [`crate::GenomMap::requestable`].
    pub fn requestable(&self) -> impl Iterator<Item = (&str, &str)> + '_ {
        self.genom.iter().flat_map(|g| g.requestable())
    }

    /// The priorities as a graph: its reachability is their transitive closure.
    pub fn priority_graph(&self) -> &PriorityGraph {
        &self.priority_graph
    }

    /// The initial state.
    pub fn initial_state(&self) -> State {
        self.initial.clone()
    }

    /// Number of slots of a state.
    pub fn slot_count(&self) -> usize {
        self.slot_ranges.len()
    }

    /// Range of values of each slot (location numbers for location slots).
    pub fn slot_ranges(&self) -> &[(i64, i64)] {
        &self.slot_ranges
    }

    pub fn component_index(&self, name: &str) -> Option<u32> {
        self.components
            .iter()
            .position(|c| c.name == name)
            .map(|i| i as u32)
    }

    pub fn interaction_index(&self, name: &str) -> Option<u32> {
        self.interactions
            .iter()
            .position(|c| c.name == name)
            .map(|i| i as u32)
    }

    pub fn atom_of(&self, component: u32) -> &Atom {
        &self.atoms[self.components[component as usize].atom as usize]
    }

    /// Location number of a component in a state.
    pub fn location(&self, state: &State, component: u32) -> u32 {
        state.slots()[self.components[component as usize].slot as usize] as u32
    }

    /// Location name of a component in a state.
    pub fn location_name(&self, state: &State, component: u32) -> &str {
        let atom = self.atom_of(component);
        &atom.locations[self.location(state, component) as usize]
    }

    /// Value of variable `var` of a component in a state.
    pub fn value(&self, state: &State, component: u32, var: u32) -> i64 {
        state.slots()[self.components[component as usize].var_slot(var) as usize]
    }

    /// Evaluates a compiled property or priority expression on a state.
    pub fn eval(&self, expr: &Expr, state: &State) -> Result<i64, EvalError> {
        expr.eval(&mut Env::new(state.slots(), 0))
    }

    /// Evaluates a boolean expression, turning an evaluation failure into a range error
    /// described by `context`.
    pub fn holds(&self, expr: &Expr, state: &State, context: &str) -> Result<bool, RangeError> {
        expr.holds(&mut Env::new(state.slots(), 0))
            .map_err(|e| self.range_error(e, context))
    }

    /// Names an evaluation failure.
    pub fn range_error(&self, e: EvalError, context: &str) -> RangeError {
        let kind = match e {
            EvalError::DivisionByZero => RangeErrorKind::DivisionByZero,
            EvalError::Overflow => RangeErrorKind::Overflow,
            EvalError::IndexOutOfBounds {
                family,
                index,
                count,
            } => RangeErrorKind::IndexOutOfBounds {
                family: self.families[family as usize].name.clone(),
                index,
                count,
            },
        };
        RangeError {
            context: context.to_string(),
            kind,
        }
    }

    /// Name of a state slot: `fork[2]` for a location slot, `buf.count` for a variable.
    pub fn slot_name(&self, slot: u32) -> String {
        let c = self.component_of_slot(slot);
        let comp = &self.components[c as usize];
        if slot == comp.slot {
            comp.name.clone()
        } else {
            let atom = &self.atoms[comp.atom as usize];
            format!(
                "{}.{}",
                comp.name,
                atom.vars[(slot - comp.slot - 1) as usize].name
            )
        }
    }

    /// The component a slot belongs to.
    pub fn component_of_slot(&self, slot: u32) -> u32 {
        let i = self.components.partition_point(|c| c.slot <= slot);
        (i - 1) as u32
    }

    /// The role of a step's interaction (internal transitions are progress).
    pub fn role(&self, label: crate::steps::Label) -> Role {
        match label {
            crate::steps::Label::Internal { .. } => Role::Progress,
            crate::steps::Label::Interaction(i) => {
                let c = self.interactions[i as usize].connector;
                self.connectors[c as usize].role
            }
        }
    }

    /// True if the system is a timed model (docs/model.md, "Timed semantics"): its codels
    /// hold its CPUs' cores for their durations.
    pub fn is_timed(&self) -> bool {
        self.genom
            .as_ref()
            .is_some_and(|g| g.time_unit_us.is_some())
    }

    /// True if the system has connectors with the `Time` role.
    pub fn has_time(&self) -> bool {
        self.connectors.iter().any(|c| c.role == Role::Time)
    }

    /// The time units a step stands for: 0 for a step that is not of a `Time` connector,
    /// its interaction's `advance` evaluated on `state` (the state the step leaves) for one
    /// that is, 1 without one. Where the step fires, this is its value; where the
    /// evaluation fails or gives less than 1, the step is a range error.
    pub fn time_advance(
        &self,
        state: &State,
        step: crate::steps::Step<'_>,
    ) -> Result<u64, RangeError> {
        match step.label {
            crate::steps::Label::Interaction(i) if self.role(step.label) == Role::Time => {
                self.advance_of(i, state)
            }
            _ => Ok(0),
        }
    }

    /// Interaction `i`'s `advance` on `state`: 1 without one.
    pub(crate) fn advance_of(&self, i: u32, state: &State) -> Result<u64, RangeError> {
        let inter = &self.interactions[i as usize];
        let Some(e) = &inter.advance else {
            return Ok(1);
        };
        let context = || format!("advance of {}", inter.name);
        let index = &self.enable_index;
        let flat = index.inter_advance[i as usize].and_then(|c| c.eval(&index.flat, state.slots()));
        let value = match flat {
            Some(v) => v,
            None => e
                .eval(&mut Env::new(state.slots(), 0))
                .map_err(|err| self.range_error(err, &context()))?,
        };
        if value < 1 {
            return Err(RangeError {
                context: context(),
                kind: RangeErrorKind::AdvanceBelowOne { value },
            });
        }
        Ok(value as u64)
    }

    /// True if some interaction has an `advance`: its `Time` steps stand for more than one
    /// unit, or for a number that depends on the state.
    pub fn has_advance(&self) -> bool {
        self.interactions.iter().any(|i| i.advance.is_some())
    }

    /// Human description of a transition: `phil[0]: thinking -take_left-> hungry`.
    pub fn describe_transition(&self, component: u32, transition: u32) -> String {
        let comp = &self.components[component as usize];
        let atom = &self.atoms[comp.atom as usize];
        let t = &atom.transitions[transition as usize];
        let port = t
            .port
            .map_or("internal", |p| atom.ports[p as usize].as_str());
        format!(
            "{}: {} -{}-> {}",
            comp.name, atom.locations[t.from as usize], port, atom.locations[t.to as usize]
        )
    }
}

/// Sizes of a compiled system, as `bip check` prints them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Summary {
    pub atoms: usize,
    pub families: usize,
    pub components: usize,
    pub connectors: usize,
    pub interactions: usize,
    /// Interactions whose steps are tabulated over the slots they depend on (the rest are
    /// computed from the state each time).
    pub tabulated_interactions: usize,
    pub internal_transitions: usize,
    /// Locations summed over components.
    pub locations: usize,
    /// Variables summed over components.
    pub variables: usize,
    pub priorities_declared: usize,
    /// The most declared priorities one chain of their closure goes through.
    pub priority_depth: u32,
    pub properties: usize,
    pub bits_per_state: u32,
}

impl System {
    pub fn summary(&self) -> Summary {
        let per_comp = |f: &dyn Fn(&Atom) -> usize| -> usize {
            self.components
                .iter()
                .map(|c| f(&self.atoms[c.atom as usize]))
                .sum()
        };
        Summary {
            atoms: self.atoms.len(),
            families: self.families.len(),
            components: self.components.len(),
            connectors: self.connectors.len(),
            interactions: self.interactions.len(),
            tabulated_interactions: self.enable_index.tables.tabulated(),
            internal_transitions: per_comp(&|a| {
                a.transitions.iter().filter(|t| t.port.is_none()).count()
            }),
            locations: per_comp(&|a| a.locations.len()),
            variables: per_comp(&|a| a.vars.len()),
            priorities_declared: self.priorities.len(),
            priority_depth: self.priority_graph.depth(),
            properties: self.properties.len(),
            bits_per_state: self.layout.bits(),
        }
    }
}

impl System {
    /// Computes the steps of the interactions `which` selects from the state each time,
    /// without their step tables: for tests that check the tables against the computation,
    /// and to measure what the tables bring. The steps are the same either way.
    pub fn drop_step_tables(&mut self, which: impl Fn(u32) -> bool) {
        self.enable_index.tables.drop_where(which);
    }

    /// Decides the suppression of every interaction below a priority by searching the
    /// priority graph, as for those whose closure does not fit the masks: for tests that
    /// check the masks against the search. The steps are the same either way.
    pub fn drop_priority_masks(&mut self) {
        self.priority_masks = crate::priority_masks::PriorityMasks::new(
            &self.priority_graph,
            &self.priorities,
            self.interactions.len(),
            0,
            |i| {
                crate::priority_masks::evaluation_cannot_fail(
                    &self.atoms,
                    &self.components,
                    &self.interactions,
                    i,
                )
            },
        );
    }
}
