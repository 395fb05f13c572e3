//! Fixed-priority preemptive scheduling analysis, for `bip sched` and `bip verify`'s
//! `Schedulable` property.
//!
//! A task set ([`TaskSet`]) is periodic tasks on CPUs, each with its worst-case work per
//! period (its demand, which bip derives from the codels a task runs in a period and
//! their WCETs). [`analyse`] gives each task's exact worst-case response time
//! ([`rta`]: Joseph and Pandya's fixed point, Lehoczky's busy period when a deadline
//! exceeds the period) and each CPU's utilisation beside Liu and Layland's bound;
//! [`simulate`] runs the schedule from the critical instant over a span, and
//! [`schedule_svg`] draws it.
//!
//! Layers, lowest first: `error`, `task`; `rta`; `analysis`, `simulate`; `svg`.

mod analysis;
mod error;
pub mod rta;
mod simulate;
mod svg;
mod task;

pub use analysis::{analyse, Analysis, CpuAnalysis, TaskAnalysis};
pub use error::SchedError;
pub use rta::ResponseTime;
pub use simulate::{hyperperiod, simulate, Job, Run, Schedule, TaskSchedule};
pub use svg::schedule_svg;
pub use task::{show_micros, Assignment, Micros, Task, TaskSet};
