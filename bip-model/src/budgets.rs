//! The system's time budgets outside a GenoM layer (docs/model.md, "Time budgets"): the
//! CPUs tasks run on, and the components whose atom stands for a periodic task. The step
//! relation never reads them; the scheduling analysis does.

#[allow(unused_imports)]
use crate::prelude::*;

/// The CPUs and the components that are periodic tasks.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Budgets {
    /// The CPUs' names, as declared; empty if the model declares none, and then every
    /// task is on one CPU.
    pub cpus: Vec<String>,
    /// One per component whose atom declares a `task`, in component order.
    pub tasks: Vec<ComponentTask>,
}

/// A component standing for a periodic task: released every `period_us`, it does at most
/// `wcet_us` of work per period.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ComponentTask {
    /// Index into the system's components.
    pub component: u32,
    pub period_us: u64,
    /// The worst-case work of one period.
    pub wcet_us: u64,
    /// Index into [`Budgets::cpus`] (0 if the model declares none).
    pub cpu: u32,
    /// Larger is more urgent; `None` on every task of its CPU: rate-monotonic.
    pub priority: Option<i64>,
    /// How long after its release a period's work must be done; `None`: the period.
    pub deadline_us: Option<u64>,
}
