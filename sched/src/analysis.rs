//! The analysis of a whole task set: per CPU, the priority order, the utilisation beside
//! Liu and Layland's bound, and per task its worst response against its deadline.

use crate::error::SchedError;
use crate::rta::{response_time, utilisation, ResponseTime};
use crate::task::{Assignment, Micros, TaskSet};

/// The verdict on a task set, with the figures behind it.
#[derive(Clone, Debug, PartialEq)]
pub struct Analysis {
    pub assignment: Assignment,
    pub cpus: Vec<CpuAnalysis>,
    /// Per task, in the set's order.
    pub tasks: Vec<TaskAnalysis>,
}

/// One CPU's load.
#[derive(Clone, Debug, PartialEq)]
pub struct CpuAnalysis {
    /// Its tasks, most urgent first.
    pub order: Vec<usize>,
    /// Σ C/T of its tasks.
    pub utilisation: f64,
    /// n(2^{1/n} − 1) for its n tasks: below it, rate-monotonic priorities with
    /// deadlines equal to periods always meet their deadlines. A sufficient test only;
    /// the verdict is the response times'.
    pub liu_layland: f64,
}

/// One task's worst case.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TaskAnalysis {
    /// 0 for the most urgent task of its CPU.
    pub rank: usize,
    pub response: ResponseTime,
    pub iterations: u64,
}

impl TaskAnalysis {
    /// Deadline minus worst response when the response is known and within it.
    pub fn slack(&self, deadline: Micros) -> Option<Micros> {
        match self.response {
            ResponseTime::Exact(r) => deadline.checked_sub(r),
            _ => None,
        }
    }

    pub fn meets(&self, deadline: Micros) -> bool {
        self.slack(deadline).is_some()
    }
}

impl Analysis {
    pub fn schedulable(&self, set: &TaskSet) -> bool {
        self.misses(set).next().is_none()
    }

    /// The tasks whose worst response exceeds their deadline (or has no bound).
    pub fn misses<'a>(&'a self, set: &'a TaskSet) -> impl Iterator<Item = usize> + 'a {
        (0..self.tasks.len()).filter(|&i| !self.tasks[i].meets(set.tasks[i].deadline))
    }
}

/// Analyses `set` with priorities decided as `assignment` says.
pub fn analyse(set: &TaskSet, assignment: Assignment) -> Result<Analysis, SchedError> {
    set.validate()?;
    let mut tasks = vec![
        TaskAnalysis {
            rank: 0,
            response: ResponseTime::Unbounded,
            iterations: 0,
        };
        set.tasks.len()
    ];
    let mut cpus = Vec::with_capacity(set.cpus.len());
    for cpu in 0..set.cpus.len() {
        let order = set.by_priority(cpu, assignment);
        let mut higher: Vec<(Micros, Micros)> = Vec::with_capacity(order.len());
        for (rank, &i) in order.iter().enumerate() {
            let task = &set.tasks[i];
            let found = response_time(task.demand, task.period, &higher);
            tasks[i] = TaskAnalysis {
                rank,
                response: found.response,
                iterations: found.iterations,
            };
            higher.push((task.demand, task.period));
        }
        let n = order.len() as f64;
        let liu_layland = if order.is_empty() {
            1.0
        } else {
            n * (2f64.powf(1.0 / n) - 1.0)
        };
        cpus.push(CpuAnalysis {
            order,
            utilisation: utilisation(&higher),
            liu_layland,
        });
    }
    Ok(Analysis {
        assignment,
        cpus,
        tasks,
    })
}
