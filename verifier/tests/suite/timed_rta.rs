//! Exploration against response-time analysis on the one case where the analysis is
//! exact: one preemptive fixed-priority core, each task's job one codel. The analysis
//! bounds every response (the exploration never finds a larger one, and never a miss
//! where the analysis finds none); with synchronous releases and every codel taking its
//! WCET at most (the analysis' critical instant is then a run of the model), the worst
//! responses are equal, and so are the verdicts.

use bip_lang::load_str;
use bip_random_systems::timed::{Codel, Cpu, Policy, Preemption, Task, TaskSet, Yield};
use bip_sched::rta::response_time;
use bip_sched::{show_micros, ResponseTime};
use bip_verifier::{verify, Method, Options, PropertyResult};
use proptest::prelude::*;

/// A task: its period in ticks of 1 ms, its codel's WCET in ms, whether its BCET is its
/// WCET (else 0), and its delay in ticks (taken modulo the period).
type Drawn = (u64, u64, bool, u64);

fn task_set(drawn: &[Drawn], synchronous: bool) -> TaskSet {
    let tasks = drawn
        .iter()
        .enumerate()
        .map(|(i, &(period, wcet, full, delay))| Task {
            module: 0,
            period_ticks: period,
            delay_ticks: if synchronous { 0 } else { delay % period },
            cpu: 0,
            core: None,
            // the first drawn is the most urgent
            priority: (drawn.len() - i) as i64,
            deadline_us: None,
            codels: vec![Codel {
                bcet_us: full.then_some(wcet * 1000),
                wcet_us: Some(wcet * 1000),
                yields: vec![Yield::Pause(0)],
                uses: Vec::new(),
            }],
        })
        .collect();
    TaskSet {
        tick_ms: 1,
        unit_us: None,
        cpus: vec![Cpu {
            cores: 1,
            policy: Policy::FixedPriority,
            preemption: Preemption::Preemptive,
        }],
        tasks,
    }
}

/// Each task's response by the analysis, in µs (`None`: its jobs queue without bound).
fn analysis(drawn: &[Drawn]) -> Vec<Option<u64>> {
    let us = |(period, wcet, _, _): Drawn| (wcet * 1000, period * 1000);
    (0..drawn.len())
        .map(|i| {
            let higher: Vec<(u64, u64)> = drawn[..i].iter().map(|&d| us(d)).collect();
            let (demand, period) = us(drawn[i]);
            match response_time(demand, period, &higher).response {
                ResponseTime::Exact(r) => Some(r),
                _ => None,
            }
        })
        .collect()
}

fn result<'a>(results: &'a [PropertyResult], name: &str) -> &'a PropertyResult {
    results
        .iter()
        .find(|p| p.name.starts_with(name))
        .unwrap_or_else(|| panic!("no result `{name}`"))
}

fn check(drawn: Vec<Drawn>, synchronous: bool) -> Result<(), TestCaseError> {
    let set = task_set(&drawn, synchronous);
    let text = set.to_ron();
    let system = load_str("rta.ron", &text)
        .map_err(|e| TestCaseError::fail(format!("{}\n{text}", e.summary())))?;
    let report = verify(&system, Method::Explicit, &Options::default(), &|_| {})
        .map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
    let rta = analysis(&drawn);
    let meets = |i: usize, r: &Option<u64>| r.is_some_and(|r| r <= drawn[i].0 * 1000);
    let all_meet = rta.iter().enumerate().all(|(i, r)| meets(i, r));
    let tight = synchronous && drawn.iter().all(|d| d.2);
    let mut explored_all_meet = true;
    for (i, r) in rta.iter().enumerate() {
        let (module, name) = set.tasks[i].names(i);
        let deadline = result(&report.properties, &format!("{module}.{name} meets its"));
        explored_all_meet &= deadline.verdict.holds();
        // the analysis is sound: no miss where it finds none
        if meets(i, r) {
            prop_assert!(
                deadline.verdict.holds(),
                "{}: {:?}\n{text}",
                deadline.name,
                rta
            );
        }
    }
    if tight {
        prop_assert_eq!(
            explored_all_meet,
            all_meet,
            "verdicts differ: {:?}\n{}",
            rta,
            text
        );
    }
    if !explored_all_meet {
        return Ok(());
    }
    for (i, r) in rta.iter().enumerate() {
        let (module, name) = set.tasks[i].names(i);
        let worst = result(
            &report.properties,
            &format!("{module}.{name} worst response"),
        );
        let note = worst.note.clone().unwrap_or_default();
        let bound = r.expect("every task meets its deadline, so the analysis is bounded");
        if tight {
            prop_assert_eq!(&note, &show_micros(bound), "{}\n{}", worst.name, text);
        } else {
            // every duration here is whole milliseconds
            let within = (0..=bound).step_by(1000).any(|us| note == show_micros(us));
            prop_assert!(
                within,
                "{}: {note} is above the analysis' {}\n{text}",
                worst.name,
                show_micros(bound)
            );
        }
    }
    Ok(())
}

fn drawn() -> impl Strategy<Value = Vec<Drawn>> {
    prop::collection::vec(
        (
            prop::sample::select(vec![2u64, 3, 4, 6, 12]),
            1u64..4,
            any::<bool>(),
            0u64..12,
        )
            .prop_map(|(p, w, full, d)| (p, w.min(p), full, d)),
        1..4,
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn the_exact_worst_response_is_within_the_analysis(drawn in drawn(), synchronous in any::<bool>()) {
        check(drawn, synchronous)?;
    }
}
