//! Time budgets at run time: a codel that runs past its WCET, a task whose period's work
//! ends past its deadline, and the codels' run times, on a virtual clock that the codel
//! itself moves (a slow computation acted out); default codels that take their WCETs on
//! CPUs scheduled as the analysis assumes, missing a deadline exactly when it says.

use bip_engine::{CodelTime, DefaultCodels, Engine, Event, Next, Until, VirtualClock};
use bip_lang::load_str;
use bip_sched::{analyse, Assignment, ResponseTime, Task, TaskSet};

use crate::common::IDS_MODEL;

/// The ids model with a WCET on `main` (period: 2 ticks of 10 ms) and a deadline.
fn budgeted(deadline: &str) -> String {
    IDS_MODEL
        .replace(
            r#"(name: "t", period: 2)"#,
            &format!(r#"(name: "t", period: 2{deadline})"#),
        )
        .replace(
            r#"throws: ["e_bad"],"#,
            r#"throws: ["e_bad"], wcet: "3ms","#,
        )
}

/// Runs `m.S` for 12 ticks with `main` taking `took` µs on the virtual clock.
fn run(model: &str, took: impl Fn(u64) -> u64 + Send + 'static) -> (Engine, Vec<Event>) {
    let clock = VirtualClock::new();
    let during = clock.clone();
    let mut runs = 0;
    let mut e = Engine::builder(load_str("budgets.ron", model).expect("loads"))
        .codel(("m", "S", "start"), |_| Next::Yield("pause::main"))
        .codel(("m", "S", "main"), move |_| {
            runs += 1;
            during.advance(took(runs));
            Next::Yield("pause::main")
        })
        .clock(clock)
        .build()
        .expect("builds");
    e.request("m", "Init", ()).expect("queued");
    e.request("m", "S", ()).expect("queued");
    e.run_until(Until::Ticks(12)).expect("runs");
    let events = e.events().collect();
    (e, events)
}

#[test]
fn a_codel_past_its_wcet_is_reported_and_its_result_kept() {
    // every third run takes 4 ms, past its 3 ms
    let (e, events) = run(&budgeted(""), |k| if k % 3 == 0 { 4000 } else { 1000 });
    let over: Vec<(u64, u64)> = events
        .iter()
        .filter_map(|ev| match ev {
            Event::WcetExceeded {
                took_us, wcet_us, ..
            } => Some((*took_us, *wcet_us)),
            _ => None,
        })
        .collect();
    let main = e.inspect().codel_id("m", "S", "main").expect("main");
    let times = e.inspect().codel_times(main);
    assert!(times.runs >= 4, "{times:?}");
    assert_eq!(over.len() as u64, times.runs / 3);
    assert!(over.iter().all(|&o| o == (4000, 3000)), "{over:?}");
    assert_eq!(e.inspect().stats().wcet_exceeded, times.over_wcet);
    assert_eq!(times.over_wcet, times.runs / 3);
    assert_eq!(times.max_us, 4000);
    assert_eq!(
        times.total_us,
        4000 * (times.runs / 3) + 1000 * (times.runs - times.runs / 3)
    );
    // 1000 µs is in [512, 1024), bucket 10; 4000 µs in [2048, 4096), bucket 12
    assert_eq!(times.histogram[10], times.runs - times.runs / 3);
    assert_eq!(times.histogram[12], times.runs / 3);
    // no deadline was missed: 4 ms is well within the 20 ms period
    assert_eq!(e.inspect().stats().deadlines_missed, 0);
    // the run went on: the activity kept running its codel
    assert!(events.iter().all(|ev| !matches!(ev, Event::Fault(_))));
}

#[test]
fn a_period_past_its_deadline_is_reported_once_per_period() {
    // the task's deadline is 5 ms; every run of `main` takes 2 ms, the fourth 6 ms
    let (e, events) = run(&budgeted(r#", deadline: "5ms""#), |k| {
        if k == 4 {
            6000
        } else {
            2000
        }
    });
    let missed: Vec<(u64, u64)> = events
        .iter()
        .filter_map(|ev| match ev {
            Event::DeadlineMissed {
                elapsed_us,
                deadline_us,
                ..
            } => Some((*elapsed_us, *deadline_us)),
            _ => None,
        })
        .collect();
    assert_eq!(missed.len(), 1, "{missed:?}");
    let (elapsed, deadline) = missed[0];
    assert_eq!(deadline, 5000);
    assert!(elapsed >= 6000, "{elapsed}");
    assert_eq!(e.inspect().stats().deadlines_missed, 1);
    // 6 ms is past the 3 ms WCET too
    assert_eq!(e.inspect().stats().wcet_exceeded, 1);
}

/// Two activities that run every period of their tasks once started (their first yield): `fast` (every
/// tick of 10 ms, 4 ms a period) above `slow` (every 2 ticks, `work` a period, deadline
/// 18 ms), on one CPU, rate-monotonic.
fn two_tasks(work: &str) -> String {
    format!(
        r#"System(name: "two", tick_ms: 10,
    modules: [(name: "m",
        tasks: [(name: "fast", period: 1), (name: "slow", period: 2, deadline: "18ms")],
        services: [
            (name: "F", kind: Activity, task: "fast", codels: [
                (state: "start", yields: ["pause::main"], wcet: "4ms"),
                (state: "main", yields: ["pause::main", "ether"], wcet: "4ms")]),
            (name: "S", kind: Activity, task: "slow", codels: [
                (state: "start", yields: ["pause::main"], wcet: "{work}"),
                (state: "main", yields: ["pause::main", "ether"], wcet: "{work}")]),
        ])],
)"#
    )
}

/// Runs `two_tasks(work)` for 20 ticks with the codels taking their WCETs: the deadline
/// misses, as `(elapsed, deadline)`.
fn simulated_misses(work: &str) -> Vec<(u64, u64)> {
    let model = load_str("two.ron", &two_tasks(work)).expect("loads");
    let mut e = Engine::builder(model)
        .default_codels(DefaultCodels::FirstYield)
        .codel_time(CodelTime::Wcet)
        .build()
        .expect("builds");
    e.request("m", "F", ()).expect("queued");
    e.request("m", "S", ()).expect("queued");
    e.run_until(Until::Ticks(20)).expect("runs");
    let stats = e.inspect().stats();
    let misses: Vec<(u64, u64)> = e
        .events()
        .filter_map(|ev| match ev {
            Event::DeadlineMissed {
                elapsed_us,
                deadline_us,
                ..
            } => Some((elapsed_us, deadline_us)),
            _ => None,
        })
        .collect();
    assert_eq!(stats.deadlines_missed, misses.len() as u64);
    assert_eq!(stats.wcet_exceeded, 0, "a run takes its WCET, never more");
    misses
}

/// The analysis of the same tasks (bip-sched's response-time analysis).
fn analysed_response(work_us: u64) -> ResponseTime {
    let task = |name: &str, period, demand, deadline| Task {
        name: name.into(),
        cpu: 0,
        period,
        demand,
        deadline,
        priority: None,
    };
    let set = TaskSet {
        cpus: vec!["cpu".into()],
        tasks: vec![
            task("m.fast", 10_000, 4000, 10_000),
            task("m.slow", 20_000, work_us, 18_000),
        ],
    };
    analyse(&set, Assignment::Given).expect("analyses").tasks[1].response
}

/// With codels taking their WCETs, the CPU's schedule is the analysis' worst case: both
/// tasks are released together every 20 ms. With 10 ms of slow work the analysis gives
/// 10 + 2·4 = 18 ms, its deadline, and the run misses nothing; with 11 ms it gives
/// 11 + 2·4 = 19 ms, and the run misses the deadline by the same 1 ms in every period.
#[test]
fn simulated_codel_times_miss_a_deadline_exactly_when_the_analysis_does() {
    assert_eq!(analysed_response(10_000), ResponseTime::Exact(18_000));
    assert_eq!(simulated_misses("10ms"), []);
    assert_eq!(analysed_response(11_000), ResponseTime::Exact(19_000));
    let misses = simulated_misses("11ms");
    // both activities start at the first release of `slow` (tick 2), then every period
    // of `slow` until tick 20 is judged: 9 of them
    assert_eq!(misses, vec![(19_000, 18_000); 9]);
}
