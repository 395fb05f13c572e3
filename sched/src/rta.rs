//! Exact response-time analysis of one task under fixed-priority preemptive scheduling
//! on one CPU.
//!
//! A task's worst response follows its release at the same instant as every task of
//! higher priority (the critical instant), with each releasing as often as it may. Its
//! q-th job of the busy period that starts there (q = 0, 1, ...) completes at the least
//! fixed point of
//!
//! ```text
//! w = (q + 1) C_i + Σ_{j ∈ hp(i)} ⌈w / T_j⌉ C_j
//! ```
//!
//! and responds in `w − q T_i`; the busy period ends with the first job that completes
//! before the task's next release (`w ≤ (q + 1) T_i`). With deadlines at most the period
//! that is the first job, and this is Joseph and Pandya's test; beyond the period it is
//! Lehoczky's. The fixed point exists exactly when the utilisation of the task and those
//! above it is at most 1: above 1 the jobs queue without end.

use crate::task::Micros;

/// A task's worst-case response time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ResponseTime {
    Exact(Micros),
    /// The task and those above it ask more than the CPU gives: its jobs queue without
    /// bound.
    Unbounded,
    /// The iteration reached [`MAX_ITERATIONS`] (or the limits of the integers) before
    /// its fixed point: the response is at least this.
    AtLeast(Micros),
}

/// Fixed-point steps allowed for one task (all jobs of its busy period together).
pub const MAX_ITERATIONS: u64 = 10_000_000;

/// What the fixed point found for one task, and what it cost.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Found {
    pub response: ResponseTime,
    /// Steps of the fixed-point iteration.
    pub iterations: u64,
    /// Jobs of the busy period examined.
    pub jobs: u64,
}

/// The worst response of a task of work `demand` every `period`, under the tasks
/// `higher` (each `(demand, period)`) of higher priority on its CPU.
pub fn response_time(demand: Micros, period: Micros, higher: &[(Micros, Micros)]) -> Found {
    if demand == 0 {
        // Nothing to wait for: done at its release, whatever runs above it.
        return Found {
            response: ResponseTime::Exact(0),
            iterations: 0,
            jobs: 1,
        };
    }
    let mut all = higher.to_vec();
    all.push((demand, period));
    if utilisation_exceeds_one(&all) {
        return Found {
            response: ResponseTime::Unbounded,
            iterations: 0,
            jobs: 0,
        };
    }
    let interference = |w: u128| -> u128 {
        higher
            .iter()
            .map(|&(c, t)| w.div_ceil(u128::from(t)) * u128::from(c))
            .sum()
    };
    let (c, t) = (u128::from(demand), u128::from(period));
    let mut worst: u128 = 0;
    let mut iterations = 0;
    let mut q: u128 = 0;
    loop {
        let own = (q + 1) * c;
        let mut w = own + higher.iter().map(|&(c, _)| u128::from(c)).sum::<u128>();
        loop {
            let next = own + interference(w);
            iterations += 1;
            if next == w {
                break;
            }
            w = next;
            if iterations >= MAX_ITERATIONS || w > u128::from(Micros::MAX) {
                let response = w.saturating_sub(q * t).max(worst);
                return Found {
                    response: ResponseTime::AtLeast(saturate(response)),
                    iterations,
                    jobs: (q + 1) as u64,
                };
            }
        }
        worst = worst.max(w - q * t);
        if w <= (q + 1) * t {
            return Found {
                response: ResponseTime::Exact(saturate(worst)),
                iterations,
                jobs: (q + 1) as u64,
            };
        }
        q += 1;
    }
}

fn saturate(x: u128) -> Micros {
    Micros::try_from(x).unwrap_or(Micros::MAX)
}

/// Whether Σ C/T > 1, exactly: over the periods' least common multiple L, whether
/// Σ C·(L/T) > L. Should L not fit in 128 bits, compared in floating point, where only
/// a utilisation within 10⁻¹² of 1 could be misjudged, and then the iteration's bound
/// still stops the analysis.
pub fn utilisation_exceeds_one(tasks: &[(Micros, Micros)]) -> bool {
    let lcm = tasks.iter().try_fold(1u128, |l, &(_, t)| {
        let t = u128::from(t);
        (l / gcd(l, t)).checked_mul(t)
    });
    match lcm {
        Some(l) => {
            let work = tasks.iter().try_fold(0u128, |sum, &(c, t)| {
                sum.checked_add(u128::from(c).checked_mul(l / u128::from(t))?)
            });
            work.is_none_or(|w| w > l)
        }
        None => utilisation(tasks) > 1.0,
    }
}

/// Σ C/T.
pub fn utilisation(tasks: &[(Micros, Micros)]) -> f64 {
    tasks.iter().map(|&(c, t)| c as f64 / t as f64).sum()
}

fn gcd(mut a: u128, mut b: u128) -> u128 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    fn exact(r: Micros) -> ResponseTime {
        ResponseTime::Exact(r)
    }

    /// Buttazzo, "Hard Real-Time Computing Systems", the response-time example:
    /// (C, T) = (1, 4), (2, 6), (3, 10), rate-monotonic; R = 1, 3, 10.
    #[test]
    fn a_textbook_set() {
        assert_eq!(response_time(1, 4, &[]).response, exact(1));
        assert_eq!(response_time(2, 6, &[(1, 4)]).response, exact(3));
        let third = response_time(3, 10, &[(1, 4), (2, 6)]);
        assert_eq!(third.response, exact(10));
        // w = 6, 7, 9, 10, 10: four steps to the fixed point.
        assert_eq!(third.iterations, 4);
    }

    /// Burns and Wellings' example: (C, T) = (3, 7), (3, 12), (5, 20); R = 3, 6, 20,
    /// the last through w = 11, 14, 17, 20, 20.
    #[test]
    fn several_iterations() {
        assert_eq!(response_time(3, 7, &[]).response, exact(3));
        assert_eq!(response_time(3, 12, &[(3, 7)]).response, exact(6));
        let low = response_time(5, 20, &[(3, 7), (3, 12)]);
        assert_eq!(low.response, exact(20));
        assert_eq!(low.iterations, 4);
    }

    /// A set that misses: (C, T) = (2, 5), (4, 7); U = 0.97 ≤ 1 yet task 2 needs 8 > 7.
    #[test]
    fn a_miss() {
        assert_eq!(response_time(4, 7, &[(2, 5)]).response, exact(8));
    }

    /// Lehoczky's deadline-beyond-period example: (C, T) = (26, 70), (62, 100), U = 0.991.
    /// The second task's jobs of the busy period respond in 114, 102, 116, 104, 118, 106
    /// and 94: the worst is the fifth, and the busy period ends with the seventh
    /// (694 ≤ 700).
    #[test]
    fn the_worst_job_is_not_always_the_first() {
        let found = response_time(62, 100, &[(26, 70)]);
        assert_eq!(found.response, exact(118));
        assert_eq!(found.jobs, 7);
    }

    #[test]
    fn overload_is_unbounded() {
        assert_eq!(
            response_time(3, 5, &[(3, 5)]).response,
            ResponseTime::Unbounded
        );
        assert!(!utilisation_exceeds_one(&[(1, 2), (1, 3), (1, 6)]));
        assert!(utilisation_exceeds_one(&[(1, 2), (1, 3), (2, 11)]));
    }
}
