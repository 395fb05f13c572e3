//! The compiled system: every name resolved to a dense index, every expression compiled.
//!
//! A state is a vector of slots (see [`crate::State`]): for each component, in order, one
//! slot for its location and one per variable. The step relation over these states lives in
//! `step.rs`; it is the only one in the project.

#[allow(unused_imports)]
use crate::prelude::*;

use core::ops::Range;

use crate::eval::{Env, EvalError, Expr};
use crate::state::{State, StateLayout};

#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Deserialize, serde::Serialize,
)]
pub enum Role {
    /// The system's own work (the default; every internal transition is progress).
    #[default]
    Progress,
    /// The passage of time (a clock tick).
    Time,
    /// A stimulus the environment may give at any time (a request); not progress.
    Environment,
}

impl Role {
    pub fn is_progress(&self) -> bool {
        *self == Role::Progress
    }
}

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
    /// The transitive closure of the declared priorities.
    pub priorities: Vec<PriorityRule>,
    /// How many priorities the file declares.
    pub declared_priorities: usize,
    pub properties: Vec<Property>,
    pub layout: StateLayout,
    pub(crate) initial: State,
    /// For each interaction, the priority rules in which it is the lower one.
    pub(crate) rules_by_low: Vec<Vec<u32>>,
    /// For each slot, the range of values it may hold.
    pub(crate) slot_ranges: Vec<(i64, i64)>,
    /// The GenoM layer the system was expanded from, if any: what the engine binds codels
    /// and sends requests with (docs/genom.md, "The engine's map").
    pub genom: Option<crate::genom::GenomMap>,
    /// Flat tables for the step relation's inner loop.
    pub(crate) enable_index: crate::step::EnableIndex,
    /// The priorities as sparse bit masks, for deciding suppression quickly.
    pub(crate) priority_masks: crate::priority_masks::PriorityMasks,
}

/// An atom type: locations, ports, variables and transitions.
#[derive(Clone, Debug)]
pub struct Atom {
    pub name: String,
    pub locations: Vec<String>,
    pub initial: u32,
    pub ports: Vec<String>,
    pub vars: Vec<Var>,
    /// Sorted by (from, port) so that `by_loc_port` can index them.
    pub transitions: Vec<Transition>,
    /// Transitions from location `l` on port `p` are `transitions[by_loc_port[l * (ports+1) + p]]`;
    /// the last column (`p == ports.len()`) holds the internal transitions.
    pub(crate) by_loc_port: Vec<Range<u32>>,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum VarType {
    Bool,
    Int { lo: i64, hi: i64 },
}

impl VarType {
    pub fn range(&self) -> (i64, i64) {
        match self {
            VarType::Bool => (0, 1),
            VarType::Int { lo, hi } => (*lo, *hi),
        }
    }
}

#[derive(Clone, Debug)]
pub struct Var {
    pub name: String,
    pub ty: VarType,
    pub init: i64,
}

#[derive(Clone, Debug)]
pub struct Transition {
    pub from: u32,
    /// `None` for an internal transition.
    pub port: Option<u32>,
    pub to: u32,
    pub guard: Option<Expr>,
    pub action: Vec<Assign>,
}

/// `target = value`.
#[derive(Clone, Debug, PartialEq)]
pub struct Assign {
    pub target: Target,
    pub value: Expr,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// A variable of the component taking the transition (offset from its slot base).
    Local(u32),
    /// A fixed slot (connector actions).
    Slot(u32),
}

/// A `components` entry: `count` instances of one atom (or a single one).
#[derive(Clone, Debug)]
pub struct Family {
    pub name: String,
    pub atom: u32,
    /// `None` for a single instance named like the family.
    pub count: Option<u32>,
    pub first: u32,
}

impl Family {
    pub fn members(&self) -> Range<u32> {
        self.first..self.first + self.count.unwrap_or(1)
    }
}

/// A component instance.
#[derive(Clone, Debug)]
pub struct Component {
    /// `fork[2]`, or `battery` for a single instance.
    pub name: String,
    pub family: u32,
    pub atom: u32,
    /// Slot of its location; its variables follow.
    pub slot: u32,
}

impl Component {
    /// Slot of its variable `n`.
    pub fn var_slot(&self, n: u32) -> u32 {
        self.slot + 1 + n
    }
}

/// A `connectors` entry, instantiated once per `forall` value.
#[derive(Clone, Debug)]
pub struct Connector {
    pub name: String,
    pub interactions: Range<u32>,
    pub broadcast: bool,
    pub role: Role,
    /// The `forall` variable's values, one per interaction; empty without `forall`.
    pub indices: Vec<i64>,
}

/// One connector instance.
#[derive(Clone, Debug)]
pub struct Interaction {
    /// `left[3]`, or the connector's name without `forall`.
    pub name: String,
    pub connector: u32,
    /// The ports in the order written (the broadcast trigger first if it was not listed).
    pub ports: Vec<PortRef>,
    /// For a broadcast, the position of the trigger in `ports`.
    pub trigger: Option<u32>,
    pub guard: Option<Expr>,
    pub action: Vec<Assign>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PortRef {
    pub component: u32,
    pub port: u32,
}

/// After transitive closure: an interaction in `low` is suppressed in a state where an
/// interaction in `high` is enabled and every `when` holds.
#[derive(Clone, Debug)]
pub struct PriorityRule {
    pub low: Range<u32>,
    pub high: Range<u32>,
    pub when: Vec<Expr>,
    /// `low < high` as written, or the chain it was derived from.
    pub origin: String,
}

#[derive(Clone, Debug)]
pub struct Property {
    pub name: String,
    pub kind: PropertyKind,
    /// The expression as written, for reports.
    pub text: String,
}

#[derive(Clone, Debug)]
pub enum PropertyKind {
    DeadlockFree { terminal: Option<Expr> },
    Invariant(Expr),
    Reachable(Expr),
}

/// A range error: the model computed a value it cannot hold or an operation that has no
/// value. MODEL.md makes this a violation, reported with a trace like a failed invariant.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RangeError {
    /// What was being evaluated: `guard of phil[0] (thinking -take-> hungry)`,
    /// `action of left[0]`, or a property name.
    pub context: String,
    pub kind: RangeErrorKind,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RangeErrorKind {
    OutOfRange {
        var: String,
        value: i64,
        lo: i64,
        hi: i64,
    },
    DivisionByZero,
    Overflow,
    IndexOutOfBounds {
        family: String,
        index: i64,
        count: u32,
    },
}

impl core::fmt::Display for RangeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match &self.kind {
            RangeErrorKind::OutOfRange { var, value, lo, hi } => write!(
                f,
                "{var} = {value} is outside {lo}..={hi} in the {}",
                self.context
            ),
            RangeErrorKind::DivisionByZero => write!(f, "division by zero in the {}", self.context),
            RangeErrorKind::Overflow => write!(f, "integer overflow in the {}", self.context),
            RangeErrorKind::IndexOutOfBounds {
                family,
                index,
                count,
            } => write!(
                f,
                "index {index} is outside {family}[0..{count}] in the {}",
                self.context
            ),
        }
    }
}

impl core::error::Error for RangeError {}

impl System {
    /// The services a client of the GenoM layer may request, as `(module, service)`
    /// (none without a layer): see [`crate::GenomMap::requestable`].
    pub fn requestable(&self) -> impl Iterator<Item = (&str, &str)> + '_ {
        self.genom.iter().flat_map(|g| g.requestable())
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
    pub fn role(&self, label: crate::step::Label) -> Role {
        match label {
            crate::step::Label::Internal { .. } => Role::Progress,
            crate::step::Label::Interaction(i) => {
                let c = self.interactions[i as usize].connector;
                self.connectors[c as usize].role
            }
        }
    }

    /// True if the system has connectors with the `Time` role.
    pub fn has_time(&self) -> bool {
        self.connectors.iter().any(|c| c.role == Role::Time)
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

impl Atom {
    /// Transitions from `loc` on `port` (`None`: internal ones).
    pub fn transitions_from(&self, loc: u32, port: Option<u32>) -> Range<u32> {
        let cols = self.ports.len() + 1;
        let col = port.map_or(self.ports.len(), |p| p as usize);
        self.by_loc_port[loc as usize * cols + col].clone()
    }

    pub fn location_index(&self, name: &str) -> Option<u32> {
        self.locations
            .iter()
            .position(|l| l == name)
            .map(|i| i as u32)
    }

    pub fn port_index(&self, name: &str) -> Option<u32> {
        self.ports.iter().position(|l| l == name).map(|i| i as u32)
    }

    pub fn var_index(&self, name: &str) -> Option<u32> {
        self.vars
            .iter()
            .position(|v| v.name == name)
            .map(|i| i as u32)
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
    pub priority_rules: usize,
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
            priorities_declared: self.declared_priorities,
            priority_rules: self.priorities.len(),
            properties: self.properties.len(),
            bits_per_state: self.layout.bits(),
        }
    }
}
