//! The analysis against the schedule itself: on random task sets, the event-driven
//! schedule equals the oracle's, and each task's worst response over a hyperperiod from
//! the critical instant is the response-time analysis' figure whenever the jobs do not
//! queue without end; the priority rules and the checks of a task set.

use bip_sched::{
    analyse, hyperperiod, simulate, Assignment, ResponseTime, SchedError, Task, TaskSet,
};
use proptest::prelude::*;

use crate::oracle;

fn task(name: &str, cpu: usize, period: u64, demand: u64, deadline: u64) -> Task {
    Task {
        name: name.into(),
        cpu,
        period,
        demand,
        deadline,
        priority: None,
    }
}

fn set_of(tasks: Vec<Task>, cpus: usize) -> TaskSet {
    TaskSet {
        cpus: (0..cpus).map(|c| format!("cpu{c}")).collect(),
        tasks,
    }
}

fn task_sets() -> impl Strategy<Value = (TaskSet, Assignment)> {
    let one = (1usize..=2, 1u64..=12, 0u64..=12, 0u64..=24, 0i64..4);
    (
        proptest::collection::vec(one, 1..=5),
        prop_oneof![
            Just(Assignment::Given),
            Just(Assignment::RateMonotonic),
            Just(Assignment::DeadlineMonotonic),
        ],
        any::<bool>(),
    )
        .prop_map(|(raw, assignment, with_priorities)| {
            let tasks = raw
                .into_iter()
                .enumerate()
                .map(|(i, (cpu, period, demand, deadline, priority))| Task {
                    name: format!("t{i}"),
                    cpu: cpu - 1,
                    period,
                    demand,
                    deadline: deadline.max(1),
                    priority: with_priorities.then_some(priority),
                })
                .collect();
            (set_of(tasks, 2), assignment)
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn the_schedule_is_the_oracles((set, assignment) in task_sets()) {
        let horizon = hyperperiod(&set).unwrap();
        let schedule = simulate(&set, assignment, horizon, 100_000).unwrap();
        let expected = oracle::finish_times(&set, assignment, horizon);
        for (i, trace) in schedule.tasks.iter().enumerate() {
            let finish: Vec<u64> = trace.jobs.iter().map(|j| j.finish).collect();
            prop_assert_eq!(&finish, &expected[i], "task {}", i);
            for (k, job) in trace.jobs.iter().enumerate() {
                prop_assert_eq!(job.release, k as u64 * set.tasks[i].period);
            }
            let ran: u64 = trace.runs.iter().map(|r| r.end - r.start).sum();
            prop_assert_eq!(ran, set.tasks[i].demand * trace.jobs.len() as u64);
        }
    }

    #[test]
    fn the_analysis_is_the_worst_response_from_the_critical_instant(
        (set, assignment) in task_sets()
    ) {
        let analysis = analyse(&set, assignment).unwrap();
        let horizon = hyperperiod(&set).unwrap();
        let schedule = simulate(&set, assignment, horizon, 100_000).unwrap();
        for (i, found) in analysis.tasks.iter().enumerate() {
            let worst = schedule.tasks[i].worst_response().unwrap();
            match found.response {
                ResponseTime::Exact(r) => {
                    prop_assert_eq!(r, worst, "task {}", i);
                    let missed = schedule.tasks[i].jobs.iter().any(|j| j.missed());
                    prop_assert_eq!(found.meets(set.tasks[i].deadline), !missed);
                }
                // Over one hyperperiod the queue has only begun to grow; what the
                // schedule shows is a lower bound.
                ResponseTime::Unbounded => {
                    let cpu = set.tasks[i].cpu;
                    let order = &analysis.cpus[cpu].order;
                    let upto = &order[..=found.rank];
                    let u: f64 = upto
                        .iter()
                        .map(|&j| set.tasks[j].demand as f64 / set.tasks[j].period as f64)
                        .sum();
                    prop_assert!(u > 1.0);
                    prop_assert!(!found.meets(set.tasks[i].deadline));
                }
                ResponseTime::AtLeast(_) => prop_assert!(false, "bound reached on a small set"),
            }
        }
    }
}

/// Buttazzo's set: (C, T) = (1, 4), (2, 6), (3, 10) in microseconds; R = 1, 3, 10, all
/// within their periods; U = 0.883 above the bound for three tasks (0.780), so only the
/// exact analysis can tell.
#[test]
fn schedulable_above_the_liu_layland_bound() {
    let set = set_of(
        vec![
            task("a", 0, 4, 1, 4),
            task("b", 0, 6, 2, 6),
            task("c", 0, 10, 3, 10),
        ],
        1,
    );
    let analysis = analyse(&set, Assignment::Given).unwrap();
    let responses: Vec<_> = analysis.tasks.iter().map(|t| t.response).collect();
    assert_eq!(
        responses,
        [1, 3, 10].map(ResponseTime::Exact).to_vec(),
        "{analysis:?}"
    );
    assert!(analysis.schedulable(&set));
    let cpu = &analysis.cpus[0];
    assert!(cpu.utilisation > cpu.liu_layland);
    assert!((cpu.liu_layland - 0.7798).abs() < 1e-4);
}

/// Raise the last task's work by one: its first job responds in 11, and as it ends after
/// the next release the busy period goes on; the second responds in 12 > 10, a miss by 2.
#[test]
fn a_miss_and_by_how_much() {
    let set = set_of(
        vec![
            task("a", 0, 4, 1, 4),
            task("b", 0, 6, 2, 6),
            task("c", 0, 10, 4, 10),
        ],
        1,
    );
    let analysis = analyse(&set, Assignment::Given).unwrap();
    assert_eq!(analysis.tasks[2].response, ResponseTime::Exact(12));
    assert_eq!(analysis.misses(&set).collect::<Vec<_>>(), [2]);
    assert_eq!(analysis.tasks[2].slack(10), None);
}

#[test]
fn priorities_given_rate_and_deadline_monotonic() {
    let mut set = set_of(
        vec![
            task("slow", 0, 10, 1, 3),
            task("fast", 0, 5, 1, 5),
            task("twin", 0, 5, 1, 5),
            task("elsewhere", 1, 1, 1, 1),
        ],
        2,
    );
    // Rate-monotonic, ties by declaration order.
    assert_eq!(set.by_priority(0, Assignment::Given), [1, 2, 0]);
    assert_eq!(set.by_priority(0, Assignment::RateMonotonic), [1, 2, 0]);
    assert_eq!(set.by_priority(0, Assignment::DeadlineMonotonic), [0, 1, 2]);
    assert_eq!(set.by_priority(1, Assignment::Given), [3]);
    // Given priorities: larger is more urgent.
    for (t, p) in set.tasks.iter_mut().zip([7, 1, 1, 0]) {
        t.priority = Some(p);
    }
    assert_eq!(set.by_priority(0, Assignment::Given), [0, 1, 2]);
    assert_eq!(set.by_priority(0, Assignment::RateMonotonic), [1, 2, 0]);
}

#[test]
fn what_a_task_set_may_not_be() {
    let check = |tasks: Vec<Task>| set_of(tasks, 1).validate().unwrap_err().to_string();
    assert_eq!(
        check(vec![task("nav", 0, 0, 0, 1)]),
        "task `nav`: its period is zero"
    );
    assert_eq!(
        check(vec![task("nav", 1, 10, 1, 10)]),
        "task `nav`: it runs on CPU #1 of 1"
    );
    let mut mixed = vec![task("a", 0, 10, 1, 10), task("b", 0, 10, 1, 10)];
    mixed[0].priority = Some(3);
    // more work than its period is a verdict, not an error
    let over = set_of(vec![task("nav", 0, 10, 11, 10)], 1);
    assert_eq!(
        analyse(&over, Assignment::Given).unwrap().tasks[0].response,
        ResponseTime::Unbounded
    );
    assert!(matches!(
        set_of(mixed, 1).validate(),
        Err(SchedError::MixedPriorities { task, .. }) if task == "b"
    ));
}

#[test]
fn a_span_too_long_to_draw_is_refused() {
    let set = set_of(vec![task("a", 0, 1, 1, 1)], 1);
    assert_eq!(
        simulate(&set, Assignment::Given, 1_000_001, 1_000_000),
        Err(SchedError::TooLong {
            horizon: 1_000_001,
            limit: 1_000_000
        })
    );
}
