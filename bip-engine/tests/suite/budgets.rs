//! Time budgets at run time: a codel that runs past its WCET, a task whose period's work
//! ends past its deadline, and the codels' run times, on a virtual clock that the codel
//! itself moves (a slow computation acted out).

use bip_engine::{Engine, Event, Next, Until, VirtualClock};
use bip_lang::load_str;

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
