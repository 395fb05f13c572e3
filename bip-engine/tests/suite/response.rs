//! The run-time monitor of bounded response properties: on robots/served.ron (a server
//! that takes two ticks) `answered_in_one` is late after every request, as often as an
//! oracle that reads the run's trace counts, and `answered_in_two` never; on a GenoM
//! layer, `Replies(within)` names the request whose wait passed the bound, once.

use crate::common;

use bip_engine::simulate::{simulate_with, Hooks, SimulationOptions};
use bip_engine::{CodelTime, DefaultCodels, Engine, Event, Until};
use bip_model::{Trace, Verdict};
use common::*;

/// Per request in `trace`, the ticks until its reply (the ticks so far if the run ends
/// first), with whether it was answered.
fn ticks_to_reply(trace: &Trace) -> Vec<(u64, bool)> {
    let mut out = Vec::new();
    let mut waiting: Option<u64> = None;
    for s in &trace.steps {
        match s.step.as_str() {
            "request" => waiting = Some(0),
            "reply" => out.extend(waiting.take().map(|t| (t, true))),
            "tick" => {
                if let Some(w) = &mut waiting {
                    *w += 1;
                }
            }
            _ => {}
        }
    }
    out.extend(waiting.map(|t| (t, false)));
    out
}

#[test]
fn a_two_tick_server_is_late_for_a_bound_of_one_after_every_request() {
    let system = load("served.ron");
    let mut whole = Trace::new(&system, Verdict::None, Vec::new());
    let mut on_steps = |segment: &Trace| whole.steps.extend(segment.steps.iter().cloned());
    let options = SimulationOptions {
        steps: 60,
        seed: 1,
        codel_time: CodelTime::Zero,
    };
    let hooks = Hooks {
        stop: None,
        on_steps: Some(&mut on_steps),
    };
    let sim = simulate_with(system.clone(), options, hooks).expect("builds");
    assert_eq!(sim.responses_monitored, 2);
    // the oracle: late once two ticks passed since the request, answered or not
    let replies = ticks_to_reply(&whole);
    let late = replies.iter().filter(|(t, _)| *t >= 2).count();
    assert!(late >= 5, "{replies:?}");
    assert_eq!(sim.stats.responses_late, late as u64);
    assert_eq!(sim.late_responses.len(), late);
    for e in &sim.late_responses {
        assert_eq!(
            (e.property.as_str(), e.within, e.elapsed_ticks, e.ticket),
            ("answered_in_one", 1, 2, None)
        );
    }
}

#[test]
fn a_late_reply_names_its_request_once() {
    // the scan codel never yields `ether` with first yields: the request is never answered
    let mut e = Engine::builder(load_text(
        r#"System(
        name: "slow",
        tick_ms: 10,
        modules: [(
            name: "m",
            tasks: [(name: "t", period: 1)],
            services: [
                (name: "Scan", kind: Activity, task: "t", codels: [
                    (state: "start", yields: ["pause::scan"]),
                    (state: "scan", yields: ["pause::scan", "ether"]),
                ]),
                (name: "Snapshot", kind: Function),
            ],
        )],
        properties: [
            Replies(service: "m.Scan", within: 2),
            Replies(service: "m.Snapshot", within: 0),
        ],
    )"#,
    ))
    .default_codels(DefaultCodels::FirstYield)
    .build()
    .expect("builds");
    let snapshot = e.request("m", "Snapshot", ()).expect("queued");
    let scan = e.request("m", "Scan", ()).expect("queued");
    assert_ne!(snapshot, scan);
    e.run_until(Until::Steps(40)).expect("runs");
    let late: Vec<Event> = e
        .events()
        .filter(|e| matches!(e, Event::ResponseLate { .. }))
        .collect();
    let [Event::ResponseLate {
        property,
        within,
        elapsed_ticks,
        ticket,
    }] = late.as_slice()
    else {
        panic!("{late:?}");
    };
    assert_eq!(
        (&**property, *within, *elapsed_ticks, *ticket),
        ("Replies(m.Scan, within: 2)", 2, 3, Some(scan))
    );
    assert_eq!(e.inspect().stats().responses_late, 1);
    assert_eq!(
        late[0].to_string(),
        format!(
            "response late: Replies(m.Scan, within: 2): no response 3 ticks after its trigger, past its bound of 2 (request #{})",
            scan.0
        )
    );
}
