//! Timed models on the engine (docs/engine.md, "Codel times"): every run, whatever the
//! seed and the codel times, is a path of the timed model (the step relation replays it,
//! and so does the engine), its codels finish when the chosen time says (their WCET,
//! their BCET, or in between), and the engine reports a deadline miss exactly when a
//! deadline invariant fails, naming its task. Bound codels take the time their clock
//! measures, in whole units, within their BCET and WCET.

use crate::common;
use crate::simulate::streamed;

use bip_engine::replay::{replay, End};
use bip_engine::simulate::{BudgetEventKind, SimulationEnd, SimulationOptions};
use bip_engine::{CodelTime, DefaultCodels, Engine, Event, Next, Until, VirtualClock};
use bip_model::{Label, System};
use common::*;
use proptest::prelude::*;

/// One task, a 500 µs codel each 10 ms period after a start codel that takes no time: a
/// model the verifier proves free of misses (the untimed engine's simulated CPUs once
/// called it late).
const ONE: &str = r#"System(name: "one", tick_ms: 1, time: Exact,
    cpus: [(name: "main", preemption: Job)],
    modules: [(name: "m", tasks: [(name: "t", period: 10, codels: [
        (state: "start", yields: ["pause::work"]),
        (state: "work", yields: ["pause::work"], wcet: "500us")])])])"#;

/// A task whose codel may take 1 to 3 ms with a deadline of 2 ms: late at its WCET, on
/// time at its BCET.
const LATE: &str = r#"System(name: "late", tick_ms: 1, time: Exact,
    cpus: [(name: "main", preemption: Job)],
    modules: [(name: "m", tasks: [(name: "t", period: 4, deadline: "2ms", codels: [
        (state: "start", yields: ["pause::work"]),
        (state: "work", yields: ["pause::work"], bcet: "1ms", wcet: "3ms")])])])"#;

/// Two tasks sharing one core by EDF, activities that clients request, interrupt and
/// stop, a codel that may throw, and a function whose codel and validation run at its
/// request, in zero time.
const EDF: &str = r#"System(name: "edf", tick_ms: 1, time: Exact,
    cpus: [(name: "c", cores: 1, policy: Edf, preemption: Job)],
    modules: [(name: "m",
        tasks: [(name: "a", period: 5), (name: "b", period: 10, delay: 1)],
        services: [
            (name: "A", kind: Activity, task: "a", interrupts: ["A"], codels: [
                (state: "start", yields: ["run"], wcet: "1ms"),
                (state: "run", yields: ["pause::run", "ether"], throws: ["e_x"],
                 bcet: "1ms", wcet: "2ms")]),
            (name: "B", kind: Activity, task: "b", codels: [
                (state: "start", yields: ["ether"], wcet: "3ms")]),
            (name: "Stop", kind: Function, interrupts: ["A"], validate: (throws: ["e_no"]),
             codels: [(state: "start", yields: ["ether"], throws: ["e_x"])]),
        ])])"#;

fn model(k: usize) -> System {
    match k {
        0 => load("tests/timed.ron"),
        1 => load_text(ONE),
        2 => load_text(LATE),
        _ => load_text(EDF),
    }
}

/// Per interaction that finishes a timed codel (its run or error path): the slot of its
/// task's `x`, and its BCET and WCET in units.
fn finishes(system: &System) -> Vec<Option<(usize, i64, i64)>> {
    let mut out = vec![None; system.interactions.len()];
    let genom = system.genom.as_ref().expect("a GenoM layer");
    let unit = genom.time_unit_us.expect("a timed model");
    for m in &genom.modules {
        for s in &m.services {
            // (a function runs no codel on a task)
            let Some(task) = s.task.and_then(|k| m.tasks[k].timed) else {
                continue;
            };
            for c in &s.codels {
                let wcet = (c.wcet_us.unwrap_or(0) / unit) as i64;
                let bcet = (c.bcet_us.unwrap_or(0) / unit) as i64;
                let at = (task.elapsed_slot as usize, bcet, wcet);
                out[c.run as usize] = Some(at);
                out[c.fail as usize] = Some(at);
            }
        }
    }
    out
}

/// Replays `trace` with the step relation: each step's label and the state it leaves.
fn path_of(system: &System, trace: &bip_model::Trace) -> Vec<(Label, bip_model::State)> {
    let path = trace
        .replay(system)
        .unwrap_or_else(|e| panic!("the run is not a path of the timed model: {e}"));
    let mut before = system.initial_state();
    let mut out = Vec::new();
    for (step, after) in path {
        out.push((step.label, before));
        before = after;
    }
    out
}

/// How long each timed codel finished in `path` had run: `x` before its finish.
fn ran_units(system: &System, path: &[(Label, bip_model::State)]) -> Vec<(u32, i64, i64, i64)> {
    let finish = finishes(system);
    path.iter()
        .filter_map(|(label, before)| {
            let Label::Interaction(i) = *label else {
                return None;
            };
            let (x, bcet, wcet) = finish[i as usize]?;
            Some((i, before.slots()[x], bcet, wcet))
        })
        .collect()
}

/// Simulates model `k` with `codel_time` and checks the run (see the module's
/// documentation); returns how it ended and the tasks reported late.
fn check_run(k: usize, seed: u64, codel_time: CodelTime) -> (SimulationEnd, Vec<String>) {
    let system = model(k);
    let options = SimulationOptions {
        steps: 1500,
        seed,
        codel_time,
    };
    let (sim, trace) = streamed(system.clone(), options);
    // a path of the timed model, by the step relation
    let path = path_of(&system, &trace);
    let ran = ran_units(&system, &path);
    // a run cut short by a miss finishes a few; the others, many
    let cut = matches!(sim.end, SimulationEnd::Violation(_));
    assert!(
        ran.len() > if cut { 0 } else { 20 },
        "{} codels finished",
        ran.len()
    );
    for (inter, ran, bcet, wcet) in ran {
        let expected = match codel_time {
            CodelTime::Wcet => ran == wcet,
            CodelTime::Zero => ran == bcet,
            CodelTime::Random(_) => (bcet..=wcet).contains(&ran),
        };
        assert!(
            expected,
            "{} finished after {ran} units ([{bcet}, {wcet}], {codel_time:?})",
            system.interactions[inter as usize].name
        );
    }
    // and through the engine
    let replayed = replay(system.clone(), &trace).expect("builds");
    assert!(replayed.refused.is_none(), "{:?}", replayed.refused);
    let late: Vec<String> = sim
        .budget_events
        .iter()
        .filter_map(|e| match &e.kind {
            BudgetEventKind::DeadlineMissed { task, .. } => Some(task.clone()),
            _ => None,
        })
        .collect();
    match &sim.end {
        SimulationEnd::Completed => {
            assert_eq!(replayed.end, Some(End::Recording));
            assert_eq!(sim.stats.deadlines_missed, 0);
        }
        SimulationEnd::Violation(p) => {
            assert_eq!(
                replayed.end,
                Some(End::Violation {
                    property: p.clone()
                })
            );
            // the deadline invariant that failed is the task reported late
            assert_eq!(late.len(), 1, "{late:?}");
            assert!(p.starts_with(&format!("{} meets its", late[0])), "{p}");
        }
        other => panic!("{other:?}"),
    }
    (sim.end, late)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Every run of the engine on a timed model replays in the timed semantics, its
    /// codels finishing when the codel time says.
    #[test]
    fn every_run_of_a_timed_model_replays(seed in any::<u64>(), k in 0usize..4, time in 0u8..3) {
        let codel_time = match time {
            0 => CodelTime::Zero,
            1 => CodelTime::Wcet,
            _ => CodelTime::Random(seed),
        };
        check_run(k, seed, codel_time);
    }
}

/// Models the verifier proves free of misses (robots/tests/timed.ron, `ONE`, `EDF`: see
/// the root's tests, which verify them) never see one, at any codel time.
#[test]
fn no_miss_where_the_verifier_proves_none() {
    for k in [0, 1, 3] {
        for seed in 0..4 {
            for time in [CodelTime::Zero, CodelTime::Wcet, CodelTime::Random(seed)] {
                let (end, late) = check_run(k, seed, time);
                assert_eq!(end, SimulationEnd::Completed, "model {k}, {time:?}");
                assert!(late.is_empty());
            }
        }
    }
}

/// `LATE` misses at its WCET: the run ends on its deadline invariant, the engine names the
/// task; at its BCET it never does.
#[test]
fn a_miss_at_the_wcet_is_reported_for_its_task() {
    let (end, late) = check_run(2, 1, CodelTime::Wcet);
    assert_eq!(
        end,
        SimulationEnd::Violation("m.t meets its 2 ms deadline".into())
    );
    assert_eq!(late, ["m.t"]);
    let (end, late) = check_run(2, 1, CodelTime::Zero);
    assert_eq!(end, SimulationEnd::Completed);
    assert!(late.is_empty());
}

/// A bound codel takes the time its clock measures, rounded up to whole units (its finish
/// comes after its return), at least its BCET; one that runs past its WCET is reported
/// and finishes at its WCET in the model.
#[test]
fn a_bound_codel_takes_the_time_it_took() {
    let run = |took_us: u64| {
        let clock = VirtualClock::new();
        let slow = clock.clone();
        let system = load_text(LATE);
        let mut e = Engine::builder(system)
            .clock(clock)
            .codel(("m", "t", "work"), move |_| {
                slow.advance(took_us);
                Next::Yield("pause::work")
            })
            .default_codels(DefaultCodels::FirstYield)
            .record(1000)
            .build()
            .expect("builds");
        e.run_until(Until::Ticks(12)).expect("runs");
        let system = e.inspect().system().clone();
        let path = path_of(&system, &e.record());
        let ran: Vec<i64> = ran_units(&system, &path)
            .into_iter()
            .map(|(_, ran, _, _)| ran)
            .collect();
        let over = e
            .events()
            .filter(|ev| matches!(ev, Event::WcetExceeded { .. }))
            .count();
        (ran, over)
    };
    // 1.5 ms: 2 units of 1 ms; 0.2 ms: its BCET, 1 unit; 5 ms: past its WCET of 3
    let (ran, over) = run(1500);
    assert!(ran.len() > 1 && ran[1..].iter().all(|&x| x == 2), "{ran:?}");
    assert_eq!(over, 0);
    let (ran, _) = run(200);
    assert!(ran.len() > 1 && ran[1..].iter().all(|&x| x == 1), "{ran:?}");
    let (ran, over) = run(5000);
    assert!(ran.len() > 1 && ran[1..].iter().all(|&x| x == 3), "{ran:?}");
    assert_eq!(over, ran.len() - 1);
}

/// `EDF`'s `Stop` runs its validation and its codel at the request, in zero time: across
/// runs each of their outcomes is taken, while codels of its module run on their core,
/// and every run replays (`check_run`).
#[test]
fn codels_at_the_request_run_in_a_timed_run() {
    let system = model(3);
    let running = |s: &bip_model::State| {
        let task = system.component_index("m_a_task").expect("task a");
        let codel = system.atom_of(task).var_index("codel").expect("codel");
        system.value(s, task, codel) != 0
    };
    let mut taken = std::collections::BTreeMap::<String, usize>::new();
    let mut while_running = 0;
    for seed in 0..8 {
        let options = SimulationOptions {
            steps: 1500,
            seed,
            codel_time: CodelTime::Random(seed),
        };
        let (_, trace) = streamed(system.clone(), options);
        for (label, before) in path_of(&system, &trace) {
            let Label::Interaction(i) = label else {
                continue;
            };
            let name = &system.interactions[i as usize].name;
            if name.starts_with("m_Stop_") {
                *taken.entry(name.clone()).or_default() += 1;
                while_running += usize::from(running(&before));
            }
        }
        check_run(3, seed, CodelTime::Random(seed));
    }
    for outcome in [
        "m_Stop_request",
        "m_Stop_start_fail",
        "m_Stop_validate_fail",
    ] {
        assert!(
            taken.get(outcome).is_some_and(|&n| n > 0),
            "{outcome}: {taken:?}"
        );
    }
    assert!(while_running > 0, "{taken:?}");
}
