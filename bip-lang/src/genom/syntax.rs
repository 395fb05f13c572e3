//! The GenoM layer of the file format (docs/model.md, "The GenoM layer"): modules and constraints, as
//! written. `genom::check` validates them; `genom::build` expands them into BIP core.

use crate::source::{ConstExpr, ConstValue, Span, Text};
use crate::syntax::VarDef;
pub use bip_model::genom::map::ServiceKind;

/// A GenoM3-style module: ids, execution tasks, out and in ports and services.
#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ModuleDef {
    pub name: Text,
    /// Free text for people; ignored by the tool.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub doc: Option<Text>,
    /// The module's internal data structure: bounded variables like an atom's.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ids: Vec<VarDef>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tasks: Vec<TaskDef>,
    /// Out ports (posters).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ports: Vec<PortDef>,
    /// In ports: what the module reads from another's out port, once the model's
    /// `connections` say which (docs/model.md, "Connections").
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub in_ports: Vec<PortDef>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub services: Vec<ServiceDef>,
}

/// An execution task: activities of the task are released every `period` ticks, or at
/// once without a period (an aperiodic task, docs/genom.md, "Aperiodic tasks").
#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct TaskDef {
    pub name: Text,
    /// In ticks; at least 1. Without one the task is aperiodic: it runs its codels as
    /// soon as they are ready, and `pause::` waits for an event of its module.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub period: Option<ConstExpr>,
    /// The offset of the task's period boundaries, in ticks, below the period: they fall
    /// on the ticks `delay + k * period` after the start (GenoM3's `delay`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delay: Option<ConstExpr>,
    /// Larger is more urgent; given on every task of a CPU or on none, which then takes
    /// rate-monotonic priorities (docs/model.md, "Time budgets").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub priority: Option<ConstExpr>,
    /// One of the model's `cpus`; by default the first.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cpu: Option<Text>,
    /// How long after its release a period's work must be done (a duration); by default
    /// the period.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deadline: Option<ConstExpr>,
    /// In a timed model, the core of its CPU the task is pinned to (from 0); absent: it
    /// runs on any free core of its CPU.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub core: Option<ConstExpr>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub doc: Option<Text>,
    /// The task's own state machine (GenoM3's permanent activity): codels like an
    /// activity's, started with the component, without any request (docs/genom.md,
    /// "Task machines").
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub codels: Vec<CodelDef>,
}

impl TaskDef {
    /// True if the task runs a state machine of its own.
    pub fn has_machine(&self) -> bool {
        !self.codels.is_empty()
    }
}

/// An out port (poster), or an in port. An out port's age is tracked when some expression
/// or constraint reads it (or an in port connected to it).
#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct PortDef {
    pub name: Text,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub doc: Option<Text>,
    /// The type of the port's data (docs/model.md, "Data types").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ty: Option<DataTypeDef>,
}

/// The type of a port's data, a service's arguments or its output, as written
/// (docs/model.md, "Data types"); bip-model's `DataType` once checked.
#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(rename = "DataType")]
pub enum DataTypeDef {
    Bool,
    /// `Int(lo, hi)`, both bounds included; bounds may be constant expressions.
    Int(ConstExpr, ConstExpr),
    Float,
    /// `Record(name: "Pose", fields: [(name: "x", ty: Float), ...])`.
    Record {
        name: Text,
        fields: Vec<FieldDef>,
    },
    /// `Rust("my_crate::nav::Pose")`: a Rust type, opaque to the model.
    Rust(Text),
}

/// A field of a record type.
#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct FieldDef {
    pub name: Text,
    pub ty: DataTypeDef,
}

#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ServiceDef {
    pub name: Text,
    pub kind: ServiceKind,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub doc: Option<Text>,
    /// The execution task of an activity.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub task: Option<Text>,
    /// Services of the same module that a request for this one interrupts.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub interrupts: Vec<Text>,
    /// Services of the same module that must have completed successfully once before a
    /// request for this one is accepted.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub after: Vec<Text>,
    /// Services of the same module that wait for this one: a request for any of them is
    /// accepted only once this one has completed successfully (each lists this one in its
    /// `after`, in effect).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub before: Vec<Text>,
    /// An activity's codel automaton; a function's or attribute's one codel (at state
    /// `start`, yielding `ether`), which runs when its request is accepted
    /// (docs/genom.md, "Codels at the request").
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub codels: Vec<CodelDef>,
    /// GenoM3's `validate` codel: it checks a request's arguments before the request is
    /// accepted, and refuses it with one of its exceptions.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub validate: Option<ValidateDef>,
    /// The type of a request's arguments (docs/model.md, "Data types").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub args: Option<DataTypeDef>,
    /// The type of the service's output.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output: Option<DataTypeDef>,
    /// Not written in a file: set by the expansion on the activity that stands for a
    /// task's machine (`genom::machines`).
    #[serde(skip)]
    pub machine: bool,
}

/// A service's `validate` codel: the exceptions with which it refuses a request.
#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ValidateDef {
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub throws: Vec<Text>,
}

/// One codel state of an activity: the codel it runs and where it may go next.
#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct CodelDef {
    pub state: Text,
    /// `"s"` (run `s` in the same cycle), `"pause::s"` (run `s` at the task's next period)
    /// or `"ether"` (the activity ends successfully).
    pub yields: Vec<Text>,
    /// Exceptions the codel may end with; the activity then ends with that error.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub throws: Vec<Text>,
    /// Out ports of the module the codel writes on every normal completion.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub writes: Vec<Text>,
    /// The module's ids members and ports (out or in) the codel reads or writes besides
    /// `writes`: GenoM3's codel parameters. In a timed model a codel holds a lock on each,
    /// and on each of `writes`, while it runs (docs/model.md, "Codel locks"); an untimed
    /// model's codels are instants and need none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub uses: Vec<Text>,
    /// Worst-case execution time of one run: `"2ms"`, `"150us"`, or microseconds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wcet: Option<ConstExpr>,
    /// Best-case execution time of one run, at most the WCET; by default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bcet: Option<ConstExpr>,
    /// GenoM3's `async` codel: it runs apart from its task, which goes on with its other
    /// activities meanwhile (docs/genom.md, "Async codels").
    #[serde(default, rename = "async", skip_serializing_if = "std::ops::Not::not")]
    pub asynchronous: bool,
}

/// A connection: module `m`'s in port `p` reads module `n`'s out port `q`
/// (`(port: "m.p", reads: "n.q")`, GenoM3's `connect_port` said in the model).
#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ConnectionDef {
    /// The in port, `"module.port"`.
    pub port: Text,
    /// The out port it reads, `"module.port"`.
    pub reads: Text,
}

/// A system-level constraint between services of (possibly different) modules. Services
/// are written `"module.Service"`, ports `"module.port"`. Every kind may have a `name`,
/// which reports show with the constraint as written.
#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
pub enum ConstraintDef {
    /// Never two of these activities active at once: a start is held back while another
    /// is active.
    Exclusive {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        name: Option<Text>,
        services: Vec<Text>,
    },
    /// The service runs only while every listed activity is active.
    Requires {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        name: Option<Text>,
        service: Text,
        active: Vec<Text>,
    },
    /// The service runs only while the port's age is at most `max_age` ticks.
    Fresh {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        name: Option<Text>,
        service: Text,
        port: Text,
        max_age: ConstExpr,
    },
    /// The service runs only while the expression holds.
    Guard {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        name: Option<Text>,
        service: Text,
        when: Text,
    },
    /// At most `max` of these activities active at once.
    AtMost {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        name: Option<Text>,
        max: ConstExpr,
        services: Vec<Text>,
    },
}

impl ConstraintDef {
    /// The constraint's kind as written.
    pub fn kind(&self) -> &'static str {
        match self {
            ConstraintDef::Exclusive { .. } => "Exclusive",
            ConstraintDef::Requires { .. } => "Requires",
            ConstraintDef::Fresh { .. } => "Fresh",
            ConstraintDef::Guard { .. } => "Guard",
            ConstraintDef::AtMost { .. } => "AtMost",
        }
    }

    /// The name given to the constraint, if any.
    pub fn name(&self) -> Option<&Text> {
        match self {
            ConstraintDef::Exclusive { name, .. }
            | ConstraintDef::Requires { name, .. }
            | ConstraintDef::Fresh { name, .. }
            | ConstraintDef::Guard { name, .. }
            | ConstraintDef::AtMost { name, .. } => name.as_ref(),
        }
    }

    /// Where the constraint is in the file: its first field.
    pub fn span(&self) -> Span {
        match self {
            ConstraintDef::Exclusive { name, services } => name
                .as_ref()
                .or(services.first())
                .map_or(Span::NONE, |t| t.span),
            ConstraintDef::AtMost { name, max, .. } => name.as_ref().map_or(max.span, |t| t.span),
            ConstraintDef::Requires { name, service, .. }
            | ConstraintDef::Fresh { name, service, .. }
            | ConstraintDef::Guard { name, service, .. } => name.as_ref().unwrap_or(service).span,
        }
    }

    /// The constraint as written, without its name:
    /// `Requires(service: "ndd.GoTo", active: ["sick.Scan"])`.
    pub fn written(&self) -> String {
        let s = |t: &Text| format!("{:?}", t.value);
        let list = |ts: &[Text]| {
            let items: Vec<String> = ts.iter().map(s).collect();
            format!("[{}]", items.join(", "))
        };
        let value = |c: &ConstExpr| match &c.value {
            ConstValue::Expr(e) => format!("{e:?}"),
            v => v.to_string(),
        };
        let fields = match self {
            ConstraintDef::Exclusive { services, .. } => format!("services: {}", list(services)),
            ConstraintDef::Requires {
                service, active, ..
            } => format!("service: {}, active: {}", s(service), list(active)),
            ConstraintDef::Fresh {
                service,
                port,
                max_age,
                ..
            } => format!(
                "service: {}, port: {}, max_age: {}",
                s(service),
                s(port),
                value(max_age)
            ),
            ConstraintDef::Guard { service, when, .. } => {
                format!("service: {}, when: {}", s(service), s(when))
            }
            ConstraintDef::AtMost { max, services, .. } => {
                format!("max: {}, services: {}", value(max), list(services))
            }
        };
        format!("{}({fields})", self.kind())
    }
}
