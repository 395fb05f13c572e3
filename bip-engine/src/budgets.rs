//! Time budgets at run time (docs/model.md, "Time budgets"): how long each codel takes,
//! against its WCET, and how long each task's work of a period takes from its release,
//! against its deadline. In a simulation, codels without a body take a time
//! ([`CodelTime`]): in a timed model, their time in the model (`engine/timed.rs`); in an
//! untimed one, work on CPUs scheduled as the analysis assumes ([`SimulatedCpus`], for
//! models whose preemptive CPUs cannot be timed yet).

#[allow(unused_imports)]
use crate::prelude::*;

use alloc::collections::VecDeque;

/// Buckets of [`CodelTimes::histogram`]: bucket `k` counts runs of `[2^(k-1), 2^k)` µs
/// (bucket 0: under 1 µs), the last one everything longer.
pub const BUCKETS: usize = 24;

/// How long one codel's runs took, by the engine's clock.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CodelTimes {
    pub runs: u64,
    pub total_us: u64,
    pub max_us: u64,
    /// Runs by duration, in powers of two of microseconds (see [`BUCKETS`]).
    pub histogram: [u64; BUCKETS],
    /// Runs that took longer than the codel's WCET.
    pub over_wcet: u64,
}

impl Default for CodelTimes {
    fn default() -> Self {
        CodelTimes {
            runs: 0,
            total_us: 0,
            max_us: 0,
            histogram: [0; BUCKETS],
            over_wcet: 0,
        }
    }
}

impl CodelTimes {
    pub(crate) fn record(&mut self, took_us: u64) {
        self.runs += 1;
        self.total_us = self.total_us.saturating_add(took_us);
        self.max_us = self.max_us.max(took_us);
        let bucket = (u64::BITS - took_us.leading_zeros()) as usize;
        self.histogram[bucket.min(BUCKETS - 1)] += 1;
    }

    /// Mean duration of a run, in microseconds.
    pub fn mean_us(&self) -> f64 {
        if self.runs == 0 {
            0.0
        } else {
            self.total_us as f64 / self.runs as f64
        }
    }
}

/// A task's period as the engine lives it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TaskClock {
    /// Every this many ticks (the first release at tick `period_ticks`).
    pub period_ticks: u64,
    /// Ticks until the next release (a count down, not a division per tick).
    pub until_release: u64,
    pub deadline_us: u64,
    /// When the current period began.
    pub released_us: u64,
    /// A miss of the current period was reported.
    pub missed: bool,
}

impl TaskClock {
    /// A task released every `period_ticks` ticks, from `now_us`.
    pub fn new(period_ticks: u64, deadline_us: u64, now_us: u64) -> TaskClock {
        let period_ticks = period_ticks.max(1);
        TaskClock {
            period_ticks,
            until_release: period_ticks,
            deadline_us,
            released_us: now_us,
            missed: false,
        }
    }

    /// A tick at time `now_us`: starts a period if the task is released.
    #[inline]
    pub fn tick(&mut self, now_us: u64) {
        self.until_release -= 1;
        if self.until_release == 0 {
            self.until_release = self.period_ticks;
            self.released_us = now_us;
            self.missed = false;
        }
    }

    /// A codel of the task ended at `end_us`: `Some(elapsed)` the first time in a period
    /// that its work ends past the deadline.
    #[inline]
    pub fn ended(&mut self, end_us: u64) -> Option<u64> {
        let elapsed = end_us.saturating_sub(self.released_us);
        if elapsed > self.deadline_us && !self.missed {
            self.missed = true;
            Some(elapsed)
        } else {
            None
        }
    }
}

/// How long a codel without a body (a default codel of a simulation) takes: in a timed
/// model, when its finish comes after its start (docs/engine.md, "Codel times"); in an
/// untimed one, its work on the simulated CPUs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CodelTime {
    /// As early as the model allows: its BCET in a timed model, no time in an untimed
    /// one (the engine's measures and checks see instants).
    #[default]
    Zero,
    /// Its WCET (no time without one): the worst case, the work the scheduling analysis
    /// assumes.
    Wcet,
    /// Drawn from this seed at its start: a whole number of units in [BCET, WCET] in a
    /// timed model, uniformly from 0 to its WCET in an untimed one.
    Random(u64),
}

/// A task as the simulated CPUs schedule it.
#[derive(Clone, Debug)]
pub(crate) struct SimulatedTask {
    pub cpu: u32,
    pub priority: Option<i64>,
    pub period_ticks: u64,
    pub deadline_us: u64,
}

/// One period's work of a task, as far as it has run.
#[derive(Clone, Copy, Debug)]
struct Job {
    release_us: u64,
    remaining_us: u64,
    /// The codel that last added work, which a miss names.
    codel: u32,
    missed: bool,
}

/// A period's work that ended (or is still running) past the task's deadline.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Miss {
    pub codel: u32,
    /// From the release to the end of the work, or to now if it has not ended.
    pub elapsed_us: u64,
    pub deadline_us: u64,
}

/// The most jobs a task keeps waiting: past it (a CPU that never catches up, already
/// reported), new work joins the last job, so that a long run takes bounded memory.
const MAX_BACKLOG: usize = 1024;

/// The CPUs as the scheduling analysis sees them (docs/sched.md): each runs its tasks'
/// work by fixed priorities, preemptively, a task's periods one after the other. The
/// codels' simulated times are the work; the model's releases stay on the tick, so a
/// period's work may end after the next tick, as on a real CPU, and a miss shows when it
/// ends past the deadline, or when the deadline passes before it ends.
#[derive(Clone, Debug)]
pub(crate) struct SimulatedCpus {
    tasks: Vec<SimulatedTask>,
    jobs: Vec<VecDeque<Job>>,
    /// Per CPU, its tasks most urgent first (priorities, else rate-monotonic; ties in
    /// declaration order, as `bip sched`).
    order: Vec<Vec<usize>>,
    /// Per CPU, how far its schedule has run.
    time_us: Vec<u64>,
}

impl SimulatedCpus {
    pub fn new(tasks: Vec<SimulatedTask>) -> SimulatedCpus {
        let cpus = tasks.iter().map(|t| t.cpu as usize + 1).max().unwrap_or(0);
        let order = (0..cpus)
            .map(|cpu| {
                let mut on: Vec<usize> = (0..tasks.len())
                    .filter(|&i| tasks[i].cpu as usize == cpu)
                    .collect();
                let given = on.iter().all(|&i| tasks[i].priority.is_some());
                on.sort_by_key(|&i| {
                    let t = &tasks[i];
                    let rank = if given {
                        -i128::from(t.priority.unwrap_or(0))
                    } else {
                        i128::from(t.period_ticks)
                    };
                    (rank, i)
                });
                on
            })
            .collect();
        SimulatedCpus {
            jobs: vec![VecDeque::new(); tasks.len()],
            tasks,
            order,
            time_us: vec![0; cpus],
        }
    }

    /// Codel `codel` of `task` ran `us` of work in the period released at `release_us`.
    pub fn work(&mut self, task: usize, codel: u32, release_us: u64, us: u64) {
        let jobs = &mut self.jobs[task];
        let full = jobs.len() >= MAX_BACKLOG;
        match jobs.back_mut() {
            Some(j) if j.release_us == release_us || full => {
                j.remaining_us = j.remaining_us.saturating_add(us);
                j.codel = codel;
            }
            _ => jobs.push_back(Job {
                release_us,
                remaining_us: us,
                codel,
                missed: false,
            }),
        }
    }

    /// Runs every CPU up to `to_us`, giving each miss to `missed`.
    pub fn run_until(&mut self, to_us: u64, mut missed: impl FnMut(Miss)) {
        for cpu in 0..self.order.len() {
            let mut t = self.time_us[cpu].max(self.earliest_release(cpu));
            while t < to_us {
                let Some(&task) = self.order[cpu].iter().find(|&&k| {
                    self.jobs[k]
                        .front()
                        .is_some_and(|j| j.release_us <= t && j.remaining_us > 0)
                }) else {
                    // idle until the next release, or the end
                    t = self.next_release(cpu, t).unwrap_or(to_us).min(to_us);
                    continue;
                };
                // it runs until it ends, a more urgent task is released, or the end
                let deadline_us = self.tasks[task].deadline_us;
                let until = self.next_release(cpu, t).unwrap_or(to_us).min(to_us);
                let job = self.jobs[task].front_mut().expect("found above");
                let ran = job.remaining_us.min(until - t);
                t += ran;
                job.remaining_us -= ran;
                if job.remaining_us == 0 {
                    let elapsed_us = t - job.release_us;
                    if elapsed_us > deadline_us && !job.missed {
                        missed(Miss {
                            codel: job.codel,
                            elapsed_us,
                            deadline_us,
                        });
                    }
                    self.jobs[task].pop_front();
                } else if ran == 0 {
                    t = until;
                }
            }
            self.time_us[cpu] = to_us;
            for &k in &self.order[cpu] {
                let deadline_us = self.tasks[k].deadline_us;
                for j in self.jobs[k].iter_mut() {
                    let elapsed_us = to_us.saturating_sub(j.release_us);
                    if elapsed_us > deadline_us && !j.missed {
                        j.missed = true;
                        missed(Miss {
                            codel: j.codel,
                            elapsed_us,
                            deadline_us,
                        });
                    }
                }
            }
        }
    }

    fn earliest_release(&self, cpu: usize) -> u64 {
        self.order[cpu]
            .iter()
            .filter_map(|&k| self.jobs[k].front().map(|j| j.release_us))
            .min()
            .unwrap_or(0)
    }

    /// The first release after `t` of a job waiting on `cpu`.
    fn next_release(&self, cpu: usize, t: u64) -> Option<u64> {
        self.order[cpu]
            .iter()
            .flat_map(|&k| self.jobs[k].iter().map(|j| j.release_us))
            .filter(|&r| r > t)
            .min()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_fall_in_their_power_of_two() {
        let mut t = CodelTimes::default();
        for us in [0, 1, 2, 3, 4, 1000, u64::MAX] {
            t.record(us);
        }
        assert_eq!(t.runs, 7);
        assert_eq!(t.max_us, u64::MAX);
        assert_eq!(t.histogram[0], 1); // 0
        assert_eq!(t.histogram[1], 1); // 1
        assert_eq!(t.histogram[2], 2); // 2, 3
        assert_eq!(t.histogram[3], 1); // 4
        assert_eq!(t.histogram[10], 1); // 1000 in [512, 1024)
        assert_eq!(t.histogram[BUCKETS - 1], 1);
    }

    #[test]
    fn one_miss_per_period() {
        let mut task = TaskClock::new(2, 150, 0);
        task.tick(100); // not a release
        assert_eq!(task.ended(140), None);
        assert_eq!(task.ended(160), Some(160));
        assert_eq!(task.ended(170), None);
        task.tick(200);
        assert_eq!(task.ended(300), None);
        assert_eq!(task.ended(351), Some(151));
    }
}
