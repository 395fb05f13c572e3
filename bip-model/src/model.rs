//! The parts of a compiled model: atoms, components, connectors and their interactions,
//! priorities, properties, and the range errors a step can meet. Every name is resolved
//! to a dense index and every expression compiled; [`crate::System`] holds them together.

#[allow(unused_imports)]
use crate::prelude::*;

use core::ops::Range;

use crate::eval::Expr;

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
    /// Of a `Time` connector: the time units its step stands for, evaluated on the state
    /// the step leaves, at least 1 (a smaller value is a range error of the step); its
    /// action reads it as [`Expr::Advance`]. None: 1.
    pub advance: Option<Expr>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PortRef {
    pub component: u32,
    pub port: u32,
}

/// A priority as declared: an interaction in `low` is suppressed in a state where an
/// interaction in `high` is enabled and `when` holds. The system closes the declared ones
/// transitively without listing the closure (docs/model.md, "Priorities").
#[derive(Clone, Debug)]
pub struct Priority {
    pub low: Range<u32>,
    pub high: Range<u32>,
    pub when: Option<Expr>,
    /// `low < high` as written.
    pub text: String,
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
    DeadlockFree {
        terminal: Option<Expr>,
    },
    Invariant(Expr),
    Reachable(Expr),
    /// Whenever `trigger` happens, `response` happens later: within `within` ticks
    /// (`Response`, `Replies(within)`), or eventually (`LeadsTo`, `Replies`, `Terminates`)
    /// on every run in which time diverges (docs/model.md, "Response and liveness").
    Response {
        trigger: Happens,
        response: Happens,
        within: Option<u64>,
    },
}

/// What a response property watches for: a state condition, or a step.
#[derive(Clone, Debug)]
pub enum Happens {
    /// A state in which the expression holds.
    State(Expr),
    /// A step that matches one of the patterns.
    Step(Vec<StepPattern>),
}

/// Steps of some connectors (any, if `connectors` is empty) from a state where `before`
/// holds to one where `after` holds (each true if absent).
#[derive(Clone, Debug, Default)]
pub struct StepPattern {
    pub connectors: Vec<u32>,
    pub before: Option<Expr>,
    pub after: Option<Expr>,
}

/// A range error: the model computed a value it cannot hold or an operation that has no
/// value. The model language makes this a violation (docs/model.md, "Range errors"), reported with a trace like a failed invariant.
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
    /// A `Time` connector's `advance` evaluated to less than 1.
    AdvanceBelowOne {
        value: i64,
    },
}

impl core::fmt::Display for RangeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match &self.kind {
            RangeErrorKind::OutOfRange { var, value, lo, hi } => write!(
                f,
                "{var} = {value} is outside its range Int({lo}, {hi}) in the {}",
                self.context
            ),
            RangeErrorKind::DivisionByZero => write!(f, "division by zero in the {}", self.context),
            RangeErrorKind::Overflow => write!(f, "integer overflow in the {}", self.context),
            RangeErrorKind::AdvanceBelowOne { value } => write!(
                f,
                "advance = {value} is below 1 (a time step stands for at least one unit) in the {}",
                self.context
            ),
            RangeErrorKind::IndexOutOfBounds {
                family,
                index,
                count,
            } => write!(
                f,
                "index {index} is outside `{family}`, {}, in the {}",
                family_indices(*count),
                self.context
            ),
        }
    }
}

impl core::error::Error for RangeError {}

/// The indices of a family of `count` components, for messages.
pub fn family_indices(count: u32) -> String {
    match count {
        0 => "which has no components".into(),
        1 => "whose only index is 0".into(),
        n => format!("whose indices run from 0 to {}", n - 1),
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
