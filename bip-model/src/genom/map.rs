//! The engine's map of a GenoM layer: for each codel, the interactions that run it and the
//! transition of each yield; for each service, its request interaction and the conditions
//! that can refuse it; for each task, its period; the tick. This is the contract between
//! the expansion and `bip-engine` (docs/genom.md, "The engine's map").
//!
//! The expansion writes the map with names (a recipe); once the expanded model is
//! compiled, the names become indices into the [`System`]: the [`GenomMap`].

#[allow(unused_imports)]
use crate::prelude::*;

use core::ops::Range;

use crate::eval;

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
pub enum ServiceKind {
    /// Runs at once, in the control task, when requested.
    Function,
    /// Like a function; in GenoM it sets or reads ids fields.
    Attribute,
    /// Runs an automaton of codels in an execution task.
    Activity,
}

/// The GenoM layer of a compiled system, in the system's indices.
#[derive(Clone, Debug)]
pub struct GenomMap {
    /// The clock tick interaction (role `Time`): the engine fires it once per `tick_ms`.
    pub tick: u32,
    /// Real time of one tick in milliseconds (`tick_ms` of the model), if given.
    pub tick_ms: Option<u64>,
    /// In a timed model (`time: Exact`), its time unit in microseconds: codels hold
    /// cores for their execution times, and the tick is one unit.
    pub time_unit_us: Option<u64>,
    pub modules: Vec<ModuleMap>,
    /// "No activity has work outstanding" (every activity at `ether` and not requested),
    /// which `DeadlockFree` excuses when requests come from the environment; `None` if
    /// the model has no activity or its requests all come from components of the model.
    pub idle: Option<eval::Expr>,
}

#[derive(Clone, Debug)]
pub struct ModuleMap {
    pub name: String,
    /// The module's component: its ids, port ages, and the request ports of its
    /// functions and attributes.
    pub component: u32,
    pub tasks: Vec<TaskMap>,
    pub ports: Vec<PortMap>,
    /// The in ports, each with the out port it reads if a connection says which.
    pub in_ports: Vec<InPortMap>,
    /// The ids fields, in order.
    pub ids: Vec<IdsField>,
    pub services: Vec<ServiceMap>,
}

/// An ids field of a module.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IdsField {
    pub name: String,
    /// Index of the field among the module atom's variables.
    pub var: u32,
    /// Its slot in the state.
    pub slot: u32,
    pub lo: i64,
    pub hi: i64,
    /// A `Bool` variable (`lo..=hi` is `0..=1`): generated bindings read and write it as
    /// a `bool`.
    pub is_bool: bool,
}

impl IdsField {
    /// Its type as a data type: `Bool`, or `Int(lo, hi)`.
    pub fn ty(&self) -> DataType {
        match self.is_bool {
            true => DataType::Bool,
            false => DataType::Int {
                lo: self.lo,
                hi: self.hi,
            },
        }
    }
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TaskMap {
    pub name: String,
    /// In ticks; `None` for an aperiodic task (it runs its codels as soon as they are
    /// ready, docs/genom.md, "Aperiodic tasks").
    pub period: Option<u32>,
    /// The offset of its period boundaries in ticks, below the period: they fall on the
    /// ticks `delay + k * period` after the start.
    pub delay: u32,
    /// In a timed model, the core of its CPU it is pinned to; `None`: any free core.
    pub core: Option<u32>,
    /// Index into the system's [`Budgets::cpus`](crate::Budgets::cpus) (0 if the model
    /// declares none).
    pub cpu: u32,
    /// Larger is more urgent; `None` on every task of its CPU: rate-monotonic.
    pub priority: Option<i64>,
    /// How long after its release a period's work must be done; `None`: the period.
    pub deadline_us: Option<u64>,
    /// In a timed model, the task's atom (`None` for a task that runs no codel).
    pub timed: Option<TimedTaskMap>,
}

/// A task of a timed model as the engine reads it (docs/genom.md, "Timed models").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimedTaskMap {
    /// The task's component (`m_t_task`).
    pub component: u32,
    /// The slot of its `x`: the running codel's elapsed time units.
    pub elapsed_slot: u32,
    /// Index into the system's properties of the invariant that the task meets its
    /// deadline.
    pub deadline: Option<u32>,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PortMap {
    pub name: String,
    /// The type of its data, if the model declares one.
    pub ty: Option<DataType>,
    /// Where the port's age lives, if any expression or constraint reads it.
    pub age: Option<AgeMap>,
}

/// An in port: a name under which a module's codels read another module's out port.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InPortMap {
    pub name: String,
    /// The type of its data, if the model declares one (the out port's, when both do).
    pub ty: Option<DataType>,
    /// The out port it reads, `(module, port)` indices into the map, if connected.
    pub reads: Option<(u32, u32)>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AgeMap {
    /// The state slot of the age (ticks since a codel that writes the port last ended).
    pub slot: u32,
    /// The age saturates at this value, which also stands for "never written".
    pub cap: i64,
}

#[derive(Clone, Debug)]
pub struct ServiceMap {
    pub name: String,
    pub kind: ServiceKind,
    /// Index of the activity's task in [`ModuleMap::tasks`].
    pub task: Option<usize>,
    /// The activity's component; `None` for functions and attributes.
    pub component: Option<u32>,
    /// The interaction that accepts a request; `None` for a task's machine (docs/genom.md,
    /// "Task machines"), which starts with the component and which nothing requests.
    pub request: Option<u32>,
    /// The interaction by which a pending request interrupts again the activities it
    /// interrupts that were requested since (docs/genom.md, "Interrupts"); `None` if the
    /// service interrupts no other activity.
    pub interrupt: Option<u32>,
    /// True if a component of the model sends the requests (a user connector took the
    /// request connector over with a role other than `Environment`): the engine must
    /// not send them itself.
    pub owned_by_model: bool,
    /// What must hold for a request to be accepted; the failed ones say why it is refused.
    pub refusals: Vec<Condition>,
    /// Services (of the same module) a request interrupts.
    pub interrupts: Vec<String>,
    pub codels: Vec<CodelMap>,
    /// A function's or attribute's codel, which runs when its request arrives
    /// (docs/genom.md, "Codels at the request"): its normal outcome is a step of
    /// [`ServiceMap::request`] (whose module pick is among the `ether` yield's
    /// `transitions`, of the module's component, or [`CodelMap::ids_transition`] when it
    /// writes ids), its exceptions and faults a step of [`CodelMap::fail`]: the request
    /// accepted, its reply an error.
    pub function: Option<CodelMap>,
    /// The service's `validate` codel, which runs when a request arrives that the model
    /// would accept: its success, its one yield `ether` (with no transitions: any step),
    /// is the request's step, its exceptions and faults a step of [`CodelMap::fail`],
    /// which refuses the request.
    pub validate: Option<CodelMap>,
    /// The type of a request's arguments, if the model declares one.
    pub args: Option<DataType>,
    /// The type of the service's output, if the model declares one.
    pub output: Option<DataType>,
}

/// The type of a port's data, a service's arguments or its output (docs/model.md,
/// "Data types"). The verifier models ports by their age, not their values: types are
/// for the engine, which checks the values codels and clients give, and for generated
/// bindings.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DataType {
    Bool,
    /// A bounded integer, both bounds included: an `i64` at run time.
    Int {
        lo: i64,
        hi: i64,
    },
    /// An `f64` at run time.
    Float,
    /// A record of named fields: a Rust struct named `name` at run time.
    Record {
        name: String,
        fields: Vec<(String, DataType)>,
    },
    /// A Rust type, opaque to the model, named by its path (`rover::Odometry`).
    Rust(String),
}

impl DataType {
    /// The Rust type a value of this type has: `bool`, `i64`, `f64`, the record's name,
    /// or the path.
    pub fn rust_name(&self) -> &str {
        match self {
            DataType::Bool => "bool",
            DataType::Int { .. } => "i64",
            DataType::Float => "f64",
            DataType::Record { name, .. } => name,
            DataType::Rust(path) => path,
        }
    }

    /// Whether a Rust value whose type is named `type_name` (as `core::any::type_name`
    /// gives it: `bool`, `f32`, `my_crate::nav::Pose`) is of this type: the same name, or
    /// a path that ends with this type's name after a `::`.
    pub fn accepts(&self, type_name: &str) -> bool {
        let want = self.rust_name();
        match self {
            DataType::Bool | DataType::Int { .. } | DataType::Float => type_name == want,
            DataType::Record { .. } | DataType::Rust(_) => {
                type_name == want
                    || type_name
                        .strip_suffix(want)
                        .is_some_and(|rest| rest.ends_with("::"))
            }
        }
    }
}

impl DataType {
    /// The type in full, as a model file writes it: a record with its fields
    /// (`Record(name: "Pose", fields: [(name: "x", ty: Float)])`), where `Display` names
    /// it only. Two types are the same exactly when they are written the same.
    pub fn written(&self) -> String {
        match self {
            DataType::Record { name, fields } => {
                let fields: Vec<String> = fields
                    .iter()
                    .map(|(f, t)| format!("(name: \"{f}\", ty: {})", t.written()))
                    .collect();
                format!("Record(name: \"{name}\", fields: [{}])", fields.join(", "))
            }
            other => other.to_string(),
        }
    }
}

/// A module's data types, each written in full ([`DataType::written`]; `""` where the
/// model declares none), by name in the model's order: what generated bindings record of
/// the model they were made from, and what the engine checks them against.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WrittenTypes<'m> {
    /// Its ids fields: `Bool` or `Int(lo, hi)`.
    pub ids: Vec<(&'m str, String)>,
    pub ports: Vec<(&'m str, String)>,
    /// Its services' arguments.
    pub args: Vec<(&'m str, String)>,
    /// Its services' outputs.
    pub outputs: Vec<(&'m str, String)>,
}

impl ModuleMap {
    pub fn written_types(&self) -> WrittenTypes<'_> {
        let written = |ty: &Option<DataType>| ty.as_ref().map_or(String::new(), DataType::written);
        let services = |f: fn(&ServiceMap) -> &Option<DataType>| {
            self.services
                .iter()
                .map(|s| (s.name.as_str(), written(f(s))))
                .collect()
        };
        WrittenTypes {
            ids: self
                .ids
                .iter()
                .map(|f| (f.name.as_str(), f.ty().written()))
                .collect(),
            ports: self
                .ports
                .iter()
                .map(|p| (p.name.as_str(), written(&p.ty)))
                .collect(),
            args: services(|s| &s.args),
            outputs: services(|s| &s.output),
        }
    }
}

impl core::fmt::Display for DataType {
    /// As the model writes it: `Bool`, `Int(0, 3)`, `Float`, `Record Pose`,
    /// `Rust("rover::Odometry")`.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DataType::Bool => f.write_str("Bool"),
            DataType::Int { lo, hi } => write!(f, "Int({lo}, {hi})"),
            DataType::Float => f.write_str("Float"),
            DataType::Record { name, .. } => write!(f, "Record {name}"),
            DataType::Rust(path) => write!(f, "Rust(\"{path}\")"),
        }
    }
}

#[derive(Clone, Debug)]
pub struct CodelMap {
    /// The codel state, as bound by the engine: `("module", "Service", state)`.
    pub state: String,
    /// The interaction of the codel's normal outcomes: one step per yield.
    pub run: u32,
    /// The interaction of the codel's error path: it ends with one of its `throws`, or the
    /// engine found it faulty (a panic, an undeclared yield, an ids value out of range).
    /// The activity ends without success.
    pub fail: u32,
    pub yields: Vec<YieldMap>,
    pub throws: Vec<String>,
    /// The out ports it writes.
    pub writes: Vec<String>,
    /// The ids fields it writes, in the module's order. A step of [`CodelMap::run`] picks
    /// one transition of the module's component among [`CodelMap::ids_transitions`]: the
    /// one for the values written ([`CodelMap::ids_transition`]).
    pub ids: Vec<IdsWrite>,
    /// The module atom's transitions that write the ids (empty if the codel writes none).
    pub ids_transitions: Range<u32>,
    /// What must hold for the codel to run; the failed ones say why it is held.
    pub holds: Vec<Condition>,
    /// Its worst-case execution time in microseconds, if declared.
    pub wcet_us: Option<u64>,
    /// Its best-case execution time in microseconds, if declared.
    pub bcet_us: Option<u64>,
    /// An async codel's start and return (docs/genom.md, "Async codels"); its outcome
    /// is then [`CodelMap::run`] or [`CodelMap::fail`], at its task's next cycle.
    pub apart: Option<Apart>,
    /// In a timed model, the codel's start (its finish is [`CodelMap::run`] or
    /// [`CodelMap::fail`]).
    pub timed: Option<TimedCodelMap>,
}

/// The steps of a codel of a timed model besides its finish: its start takes its task's
/// core, and the finish that drops its outcome frees the core when its activity left it
/// while it ran (`None` for a task machine's codel, never interrupted).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimedCodelMap {
    pub start: u32,
    pub dropped: Option<u32>,
}

/// The steps of an async codel besides its outcome: it starts apart from its task (its
/// conditions gate this step) and returns, whenever the world lets it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Apart {
    pub start: u32,
    pub returned: u32,
}

/// An ids field a codel writes (docs/genom.md, "Codels that write ids").
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IdsWrite {
    pub name: String,
    /// Index of the field among the module atom's variables.
    pub var: u32,
    /// Its slot in the state.
    pub slot: u32,
    pub lo: i64,
    pub hi: i64,
    /// How many transitions apart two consecutive values of this field are.
    pub stride: u32,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct YieldMap {
    /// As written: `"main"`, `"pause::main"` or `"ether"`.
    pub target: String,
    /// The transitions of the activity's atom that take this yield (one per place the
    /// codel runs from: its location, and `ether` for `start`). A step of [`CodelMap::run`]
    /// takes this yield if the activity's pick is one of them.
    pub transitions: Vec<u32>,
}

/// A condition of a request or a codel, with the reason it stands for. It prints as its
/// reason, in the model's terms.
#[derive(Clone, Debug)]
pub struct Condition {
    pub reason: Reason,
    /// The condition as an expression of the expanded model.
    pub text: String,
    pub expr: eval::Expr,
}

/// Why a request is refused or a codel held.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Reason {
    /// The activity is already requested or active and does not interrupt itself.
    AlreadyRequested,
    /// `after`: this service has not completed successfully yet.
    After { service: String },
    /// The activity waits for a service it interrupts to end.
    Interrupting { service: String },
    /// A constraint of the model's `constraints`.
    Constraint(ConstraintRef),
    /// The guard of a user connector that extends the request connector.
    Connector { connector: String, guard: String },
}

/// A constraint of the model, as reports show it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ConstraintRef {
    /// Its index in the model's `constraints`, counting from 0.
    pub index: usize,
    /// `Requires`, `Fresh`, …
    pub kind: String,
    /// The name the model gives it, if any.
    pub name: Option<String>,
    /// The constraint as written, without its name:
    /// `Requires(service: "ndd.GoTo", active: ["sick.Scan"])`.
    pub written: String,
    /// Its line in the model's file (from 1), when the model was read from text.
    pub line: Option<u32>,
}

impl core::fmt::Display for Reason {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Reason::AlreadyRequested => f.write_str("already requested or active"),
            Reason::After { service } => write!(f, "after {service}"),
            Reason::Interrupting { service } => write!(f, "waits for {service} to end"),
            Reason::Constraint(c) => c.fmt(f),
            Reason::Connector { connector, guard } => {
                write!(f, "the guard of connector {connector}: {guard}")
            }
        }
    }
}

/// `fresh_pose (line 42): Fresh(service: "ndd.GoTo", port: "pom.pose", max_age: 2)`; without
/// a name, `line 42: Fresh(…)`.
impl core::fmt::Display for ConstraintRef {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match (&self.name, self.line) {
            (Some(name), Some(line)) => write!(f, "{name} (line {line}): ")?,
            (Some(name), None) => write!(f, "{name}: ")?,
            (None, Some(line)) => write!(f, "line {line}: ")?,
            (None, None) => {}
        }
        f.write_str(&self.written)
    }
}

impl core::fmt::Display for Condition {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        self.reason.fmt(f)
    }
}

impl GenomMap {
    /// The services a client of the layer may request, as `(module, service)`: all but
    /// those whose requests a component of the model sends, and tasks' machines.
    pub fn requestable(&self) -> impl Iterator<Item = (&str, &str)> + '_ {
        self.modules.iter().flat_map(|m| {
            m.services
                .iter()
                .filter(|s| !s.owned_by_model && s.request.is_some())
                .map(move |s| (m.name.as_str(), s.name.as_str()))
        })
    }

    pub fn module(&self, name: &str) -> Option<&ModuleMap> {
        self.modules.iter().find(|m| m.name == name)
    }

    pub fn service(&self, module: &str, service: &str) -> Option<&ServiceMap> {
        self.module(module)?
            .services
            .iter()
            .find(|s| s.name == service)
    }

    /// The codel the engine binds as `(module, service, state)`.
    pub fn codel(&self, module: &str, service: &str, state: &str) -> Option<&CodelMap> {
        self.service(module, service)?
            .codels
            .iter()
            .find(|c| c.state == state)
    }
}

impl ServiceMap {
    /// Its codels, then its codels at a request (its `validate`, then a function's): the
    /// order in which the engine numbers a module's codels, and a module object's codels
    /// are numbered.
    pub fn every_codel(&self) -> impl Iterator<Item = &CodelMap> {
        self.codels
            .iter()
            .chain(self.validate.as_ref())
            .chain(self.function.as_ref())
    }
}

impl CodelMap {
    /// The module transition that writes `value(k)` into the `k`-th field of
    /// [`CodelMap::ids`]; `None` if a value is outside its field's range.
    pub fn ids_transition(&self, mut value: impl FnMut(usize) -> i64) -> Option<u32> {
        let mut t = self.ids_transitions.start;
        for (k, f) in self.ids.iter().enumerate() {
            let v = value(k);
            if v < f.lo || v > f.hi {
                return None;
            }
            t += (v - f.lo) as u32 * f.stride;
        }
        Some(t)
    }

    /// The interaction its conditions gate: an async codel's start, or its run.
    pub fn gated(&self) -> u32 {
        self.apart.map_or(self.run, |a| a.start)
    }

    /// The yield a transition of the activity's atom takes.
    pub fn yield_of(&self, transition: u32) -> Option<&YieldMap> {
        self.yields
            .iter()
            .find(|y| y.transitions.contains(&transition))
    }
}
