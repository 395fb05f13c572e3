//! The schedule itself: every task released at time 0 and then every period, each job
//! asking its task's whole demand, run by a fixed-priority preemptive CPU. Synchronous
//! release is the critical instant, so over a hyperperiod this schedule shows each
//! task's worst response, the one the analysis computes; it is what `bip sched --svg`
//! draws.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, VecDeque};

use crate::error::SchedError;
use crate::task::{Assignment, Micros, TaskSet};

/// What each task did over a span of releases.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Schedule {
    /// Jobs are released in `[0, horizon)`; the schedule goes on until they are done.
    pub horizon: Micros,
    /// When the last job finished.
    pub end: Micros,
    /// Per task, in the set's order.
    pub tasks: Vec<TaskSchedule>,
}

/// One task's jobs and the spans it ran.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TaskSchedule {
    pub jobs: Vec<Job>,
    /// Spans of running, in time order; a gap inside one job is a preemption.
    pub runs: Vec<Run>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Job {
    pub release: Micros,
    /// Absolute: release plus the task's deadline.
    pub deadline: Micros,
    pub finish: Micros,
}

impl Job {
    pub fn response(&self) -> Micros {
        self.finish - self.release
    }

    pub fn missed(&self) -> bool {
        self.finish > self.deadline
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Run {
    pub start: Micros,
    pub end: Micros,
    /// Index into the task's jobs.
    pub job: usize,
}

impl TaskSchedule {
    pub fn worst_response(&self) -> Option<Micros> {
        self.jobs.iter().map(Job::response).max()
    }
}

/// The least common multiple of the periods, if it fits.
pub fn hyperperiod(set: &TaskSet) -> Option<Micros> {
    set.tasks.iter().try_fold(1, |l: Micros, t| {
        let g = gcd(l, t.period);
        (l / g).checked_mul(t.period)
    })
}

fn gcd(mut a: Micros, mut b: Micros) -> Micros {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// Runs the schedule of jobs released in `[0, horizon)`, refusing to hold more than
/// `max_jobs` of them.
pub fn simulate(
    set: &TaskSet,
    assignment: Assignment,
    horizon: Micros,
    max_jobs: u64,
) -> Result<Schedule, SchedError> {
    set.validate()?;
    let jobs: u64 = set
        .tasks
        .iter()
        .map(|t| horizon.div_ceil(t.period))
        .fold(0u64, u64::saturating_add);
    if jobs > max_jobs {
        return Err(SchedError::TooLong {
            horizon,
            limit: max_jobs,
        });
    }
    let mut tasks = vec![TaskSchedule::default(); set.tasks.len()];
    let mut end = 0;
    for cpu in 0..set.cpus.len() {
        let order = set.by_priority(cpu, assignment);
        end = end.max(run_cpu(set, &order, horizon, &mut tasks));
    }
    Ok(Schedule {
        horizon,
        end,
        tasks,
    })
}

/// One CPU's tasks, most urgent first; returns when its last job finished.
fn run_cpu(set: &TaskSet, order: &[usize], horizon: Micros, out: &mut [TaskSchedule]) -> Micros {
    // Pending jobs per rank: (index in the task's jobs, work left).
    let mut pending: Vec<VecDeque<(usize, Micros)>> = vec![VecDeque::new(); order.len()];
    // Next release per rank.
    let mut releases: BinaryHeap<Reverse<(Micros, usize)>> = (0..order.len())
        .filter(|_| horizon > 0)
        .map(|rank| Reverse((0, rank)))
        .collect();
    let mut now: Micros = 0;
    loop {
        while let Some(&Reverse((at, rank))) = releases.peek() {
            if at > now {
                break;
            }
            releases.pop();
            let task = &set.tasks[order[rank]];
            let schedule = &mut out[order[rank]];
            // A job of no work is done when it is released.
            schedule.jobs.push(Job {
                release: at,
                deadline: at.saturating_add(task.deadline),
                finish: if task.demand == 0 { at } else { Micros::MAX },
            });
            if task.demand > 0 {
                pending[rank].push_back((schedule.jobs.len() - 1, task.demand));
            }
            if let Some(next) = at.checked_add(task.period).filter(|&n| n < horizon) {
                releases.push(Reverse((next, rank)));
            }
        }
        let next_release = releases.peek().map(|Reverse((at, _))| *at);
        let Some(rank) = pending.iter().position(|q| !q.is_empty()) else {
            match next_release {
                Some(at) => {
                    now = at;
                    continue;
                }
                None => return now,
            }
        };
        let task = order[rank];
        let (job, left) = pending[rank][0];
        let until = next_release.map_or(now + left, |at| at.min(now + left));
        if until > now {
            let runs = &mut out[task].runs;
            match runs.last_mut() {
                Some(last) if last.job == job && last.end == now => last.end = until,
                _ => runs.push(Run {
                    start: now,
                    end: until,
                    job,
                }),
            }
        }
        let left = left - (until - now);
        now = until;
        if left == 0 {
            pending[rank].pop_front();
            out[task].jobs[job].finish = now;
        } else {
            pending[rank][0].1 = left;
        }
    }
}
