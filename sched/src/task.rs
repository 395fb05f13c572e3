//! What the analysis is given: periodic tasks on CPUs, each with its worst-case work per
//! period, and how their priorities are decided.

use crate::error::SchedError;

/// Time in microseconds.
pub type Micros = u64;

/// A time for people: in seconds from 1 s, in milliseconds from 1 ms (up to three
/// decimals, as needed), else in microseconds.
pub fn show_micros(us: Micros) -> String {
    let decimal = |x: f64| {
        let s = format!("{x:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    };
    if us >= 1_000_000 {
        format!("{} s", decimal(us as f64 / 1e6))
    } else if us >= 1000 {
        format!("{} ms", decimal(us as f64 / 1e3))
    } else {
        format!("{us} µs")
    }
}

/// A periodic task: released every `period`, it must finish `demand` of work (its worst
/// case per period) within `deadline` of its release, on its CPU, preempted by every task
/// of higher priority there.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Task {
    pub name: String,
    /// Index into [`TaskSet::cpus`].
    pub cpu: usize,
    pub period: Micros,
    /// C_i: the worst-case execution time of one period's work.
    pub demand: Micros,
    /// D_i: relative to the release; may exceed the period (then several jobs of the task
    /// can be pending at once, each after the one before).
    pub deadline: Micros,
    /// Larger is more urgent (as POSIX and GenoM priorities); `None` on every task of a
    /// CPU: rate-monotonic.
    pub priority: Option<i64>,
}

/// Tasks and the CPUs they run on.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TaskSet {
    pub cpus: Vec<String>,
    pub tasks: Vec<Task>,
}

/// How priorities are decided when they are not all given, or to propose new ones.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Assignment {
    /// The tasks' own priorities; on a CPU where no task gives one, rate-monotonic.
    Given,
    /// Shorter period, higher priority (optimal among fixed priorities when deadlines
    /// equal periods).
    RateMonotonic,
    /// Shorter deadline, higher priority (optimal when deadlines are at most periods).
    DeadlineMonotonic,
}

impl TaskSet {
    /// Checks what the analysis relies on: positive periods and deadlines, a CPU that
    /// exists, and per CPU either every task's priority or none. (A demand above the
    /// period is a verdict, not an error: the task's jobs queue without bound.)
    pub fn validate(&self) -> Result<(), SchedError> {
        for task in &self.tasks {
            let bad = |what: String| SchedError::Task {
                task: task.name.clone(),
                what,
            };
            if task.period == 0 {
                return Err(bad("its period is zero".into()));
            }
            if task.deadline == 0 {
                return Err(bad("its deadline is zero".into()));
            }
            if task.cpu >= self.cpus.len() {
                return Err(bad(format!(
                    "it runs on CPU #{} of {}",
                    task.cpu,
                    self.cpus.len()
                )));
            }
        }
        for (cpu, name) in self.cpus.iter().enumerate() {
            let on_cpu: Vec<&Task> = self.tasks.iter().filter(|t| t.cpu == cpu).collect();
            let some_given = on_cpu.iter().any(|t| t.priority.is_some());
            if let Some(missing) = on_cpu.iter().find(|t| t.priority.is_none()) {
                if some_given {
                    return Err(SchedError::MixedPriorities {
                        cpu: name.clone(),
                        task: missing.name.clone(),
                    });
                }
            }
        }
        Ok(())
    }

    /// The tasks of `cpu`, most urgent first: by priority (or period, or deadline, as
    /// `assignment` says), ties broken by declaration order.
    pub fn by_priority(&self, cpu: usize, assignment: Assignment) -> Vec<usize> {
        let mut order: Vec<usize> = (0..self.tasks.len())
            .filter(|&i| self.tasks[i].cpu == cpu)
            .collect();
        let given = order.iter().all(|&i| self.tasks[i].priority.is_some());
        let key = |i: &usize| -> (i128, usize) {
            let t = &self.tasks[*i];
            let rank = match (assignment, given) {
                (Assignment::Given, true) => -i128::from(t.priority.unwrap_or(0)),
                (Assignment::DeadlineMonotonic, _) => i128::from(t.deadline),
                _ => i128::from(t.period),
            };
            (rank, *i)
        };
        order.sort_by_key(key);
        order
    }
}
