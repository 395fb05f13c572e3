//! Time budgets at run time (docs/model.md, "Time budgets"): how long each codel takes,
//! against its WCET, and how long each task's work of a period takes from its release,
//! against its deadline.

#[allow(unused_imports)]
use crate::prelude::*;

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
