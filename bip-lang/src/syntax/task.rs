//! An atom that stands for a periodic task (docs/model.md, "Atoms that stand for
//! periodic tasks"): a
//! PECOS-style design of plain periodic tasks, without GenoM modules.

use crate::source::{ConstExpr, Text};

/// Every component of the atom is a task: released every `period`, it does at most
/// `wcet` of work per period, on `cpu`, at `priority`, done within `deadline`.
#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct AtomTaskDef {
    /// A duration (`"10ms"`, or microseconds): a core atom has no tick to count in.
    pub period: ConstExpr,
    /// The worst-case work of one period, a duration.
    pub wcet: ConstExpr,
    /// Larger is more urgent; given on every task of a CPU or on none (rate-monotonic).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub priority: Option<ConstExpr>,
    /// One of the model's `cpus`; by default the first.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cpu: Option<Text>,
    /// How long after its release a period's work must be done; by default the period.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deadline: Option<ConstExpr>,
}
