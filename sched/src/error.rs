//! What can be wrong with a task set, in its tasks' names.

/// A task set the analysis cannot take.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SchedError {
    #[error("task `{task}`: {what}")]
    Task { task: String, what: String },
    #[error("CPU `{cpu}`: some of its tasks give a priority and `{task}` does not (give every task on a CPU a priority, or none for rate-monotonic)")]
    MixedPriorities { cpu: String, task: String },
    #[error(
        "the schedule over {horizon} µs holds more than {limit} jobs to draw; draw a shorter span"
    )]
    TooLong { horizon: u64, limit: u64 },
}
