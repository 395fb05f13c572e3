//! Each `Replies` property's worst response (the longest wait for the reply) on random
//! small timed layers, against the bounded search as oracle: a finite worst W means that
//! the reply always comes within W time units and not always within W − 1; an unbounded
//! one, that no bound holds. The run that waits longest replays in the model, and the
//! wait along it, as the step relation's watch counts it, is W.

use bip_lang::load_str;
use bip_model::{PropertyKind, ResponseWatch, System};
use bip_verifier::{verify, CheckKind, Method, Options, PropertyResult, PropertyVerdict, Report};
use proptest::prelude::*;

/// A random timed layer: one module, its tasks on one CPU, activities on them whose
/// codels take random times, some pausing, some interrupting one another, and a
/// `Replies` without bound for each service.
fn layer() -> impl Strategy<Value = String> {
    let task = (2u32..=4, 0u32..=1);
    let codel = (0usize..4, 0usize..4, 0usize..3);
    let service = (
        0usize..2,
        prop::collection::vec(codel, 1..=2),
        any::<bool>(),
    );
    (
        1usize..=2,
        prop::collection::vec(task, 1..=2),
        prop::collection::vec(service, 1..=2),
    )
        .prop_map(|(cores, tasks, services)| {
            const TIMES: [&str; 4] = ["", "500us", "1ms", "2ms"];
            let mut s = format!(
                "System(name: \"w\", tick_ms: 1, time: Exact,\n  cpus: [(name: \"main\", cores: {cores}, policy: FixedPriority, preemption: Job)],\n  modules: [(name: \"m\", tasks: [\n"
            );
            for (i, (period, delay)) in tasks.iter().enumerate() {
                s += &format!(
                    "    (name: \"t{i}\", period: {period}, delay: {}, priority: {}),\n",
                    delay % period,
                    10 - i
                );
            }
            s += "  ], services: [\n";
            for (i, (task, codels, interrupts)) in services.iter().enumerate() {
                let task = task % tasks.len();
                let name = |k: usize| if k == 0 { "start".to_string() } else { format!("c{k}") };
                s += &format!("    (name: \"S{i}\", kind: Activity, task: \"t{task}\"");
                if *interrupts {
                    s += &format!(", interrupts: [\"S{i}\"]");
                }
                s += ", codels: [\n";
                for (k, (bcet, wcet, next)) in codels.iter().enumerate() {
                    let last = k + 1 == codels.len();
                    let then = if last { "ether".to_string() } else { name(k + 1) };
                    // every codel is reached: each but the last yields to the next
                    let yields = match (next, last) {
                        (2, _) => format!("\"pause::{}\", \"{then}\"", name(k)),
                        (1, false) => format!("\"{then}\", \"ether\""),
                        _ => format!("\"{then}\""),
                    };
                    let (b, w) = (bcet.min(wcet), bcet.max(wcet));
                    s += &format!("      (state: \"{}\", yields: [{yields}]", name(k));
                    if *w > 0 {
                        if *b > 0 {
                            s += &format!(", bcet: \"{}\"", TIMES[*b]);
                        }
                        s += &format!(", wcet: \"{}\"", TIMES[*w]);
                    }
                    s += "),\n";
                }
                s += "    ]),\n";
            }
            s += "  ])],\n  properties: [";
            for i in 0..services.len() {
                s += &format!("Replies(service: \"m.S{i}\"), ");
            }
            s += "],\n)\n";
            s
        })
}

fn explored(system: &System) -> Report {
    let options = Options {
        jobs: 1,
        ..Options::default()
    };
    verify(system, Method::Explicit, &options, &|_| {}).expect("the run completes")
}

/// The property's worst wait: `Some(units)`, or `None` where it is unbounded.
fn figure(system: &System, row: &PropertyResult, text: &str) -> Result<Option<u64>, TestCaseError> {
    let unit_us = system
        .genom
        .as_ref()
        .and_then(|g| g.time_unit_us)
        .expect("a timed layer has a unit");
    match &row.verdict {
        PropertyVerdict::Holds { .. } => {
            let us = row
                .worst_us
                .ok_or_else(|| TestCaseError::fail(format!("{}: no figure\n{text}", row.name)))?;
            prop_assert_eq!(us % unit_us, 0);
            Ok(Some(us / unit_us))
        }
        PropertyVerdict::Fails { reason, .. } if reason.starts_with("unbounded") => Ok(None),
        other => Err(TestCaseError::fail(format!(
            "{}: {other:?}\n{text}",
            row.name
        ))),
    }
}

/// The indices of the system's response properties (its `Replies`; the deadlines are
/// invariants).
fn responses(system: &System) -> Vec<usize> {
    (0..system.properties.len())
        .filter(|&p| matches!(system.properties[p].kind, PropertyKind::Response { .. }))
        .collect()
}

/// The system with bound `within[k]` on its `k`-th response property.
fn bounded(system: &System, within: &[u64]) -> System {
    let mut out = system.clone();
    for (p, &k) in responses(system).into_iter().zip(within) {
        if let PropertyKind::Response { within, .. } = &mut out.properties[p].kind {
            *within = Some(k);
        }
    }
    out
}

/// The verdicts of the system's properties (its `Replies`), in order.
fn verdicts(system: &System) -> Vec<(String, bool, bool)> {
    explored(system)
        .properties
        .iter()
        .filter(|p| p.kind == CheckKind::Response)
        .map(|p| (p.name.clone(), p.verdict.holds(), p.verdict.fails()))
        .collect()
}

/// The longest wait along the witness of property `p`'s worst response, as the step
/// relation's watch counts it, and whether the wait is answered at its end.
fn wait_along(system: &System, p: usize, row: &PropertyResult) -> (u64, bool) {
    let trace = row.verdict.trace().expect("a finite worst has its run");
    let path = trace.replay(system).expect("the run replays in the model");
    let spec = system.properties[p]
        .kind
        .response_spec()
        .expect("a response property");
    let init = system.initial_state();
    let mut watch = ResponseWatch::start(system, spec, &init, "").expect("in range");
    let mut longest = 0;
    let mut before = init;
    for (step, after) in path {
        let waited = watch.waiting;
        let units = system
            .time_advance(&before, step.as_step())
            .expect("it fired");
        let late = watch
            .observe(system, spec, &before, step.as_step(), &after, "")
            .expect("in range");
        assert!(!late, "no bound is set");
        // a tick that answers counts too, though the answer clears the count
        if let Some(c) = waited {
            longest = longest.max(c + units);
        }
        before = after;
    }
    (longest, watch.waiting.is_none())
}

fn check(text: &str) -> Result<(), TestCaseError> {
    let system = load_str("w.ron", text)
        .map_err(|e| TestCaseError::fail(format!("{}\n{text}", e.summary())))?;
    let report = explored(&system);
    let replies = responses(&system).len();
    let mut worst = Vec::new();
    for p in responses(&system) {
        let name = format!("{} worst response", system.properties[p].name);
        let row = report
            .properties
            .iter()
            .find(|r| r.name == name && r.kind == CheckKind::WorstResponse)
            .ok_or_else(|| TestCaseError::fail(format!("no row `{name}`\n{text}")))?;
        let w = figure(&system, row, text)?;
        if let (Some(w), Some(_)) = (w, row.verdict.trace()) {
            let (along, answered) = wait_along(&system, p, row);
            prop_assert_eq!(along, w, "{}: the wait along its run\n{}", name, text);
            prop_assert!(answered, "{}: its run ends with the answer\n{}", name, text);
        }
        worst.push(w);
    }
    prop_assert_eq!(worst.len(), replies);
    // an unbounded wait fails every bound: 0, and one past the longest finite wait here
    let beyond = worst.iter().flatten().max().copied().unwrap_or(0) + 20;
    let at =
        |unbounded: u64| -> Vec<u64> { worst.iter().map(|w| w.unwrap_or(unbounded)).collect() };
    let holds_at_worst = verdicts(&bounded(&system, &at(beyond)));
    let below: Vec<u64> = worst
        .iter()
        .map(|w| w.map_or(0, |w| w.saturating_sub(1)))
        .collect();
    let below_worst = verdicts(&bounded(&system, &below));
    for p in 0..replies {
        let (name, holds, fails) = &holds_at_worst[p];
        match worst[p] {
            Some(w) => {
                prop_assert!(
                    *holds,
                    "{name}: the worst {w} as a bound does not hold\n{text}"
                );
                if w > 0 {
                    prop_assert!(below_worst[p].2, "{name}: {} holds too\n{text}", w - 1);
                }
            }
            None => {
                prop_assert!(*fails, "{name}: unbounded, but {beyond} holds\n{text}");
                prop_assert!(below_worst[p].2, "{name}: unbounded, but 0 holds\n{text}");
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn a_replies_worst_response_is_its_tightest_bound(text in layer()) {
        check(&text)?;
    }
}

/// `robots/tests/timed.ron`'s `Log` (task `log`, period 8 ms, 1 to 2 ms on a core it never
/// waits for): a request just after the release waits for the next one, 8 ms later, and
/// its reply comes 10 ms after it at worst (the bound `suite::schedulability` checks).
#[test]
fn a_services_worst_response_is_known() {
    let text = include_str!("../../../robots/tests/timed.ron").replacen(
        "    ],\n)",
        "    ],\n    properties: [Replies(service: \"nav.Log\")],\n)",
        1,
    );
    let system = load_str("timed.ron", &text).expect("the model loads");
    let report = explored(&system);
    let row = report
        .property("Replies(nav.Log) worst response")
        .expect("the row");
    assert_eq!(row.kind, CheckKind::WorstResponse);
    assert_eq!(
        (row.worst_us, row.note.as_deref()),
        (Some(10_000), Some("10 ms"))
    );
    assert_eq!(
        wait_along(&system, 0, row),
        (20, true),
        "in units of 500 µs"
    );
}

/// In a model without a GenoM layer the figure is in time units, and the tick that brings
/// the response counts: `suite::advance`'s clock triggers with the tick into `k == 1`, and
/// its ticks from 1 and 2 stand for 2 and 3 units, the second bringing `k == 3`.
#[test]
fn the_answering_tick_counts_in_time_units() {
    let system = super::advance::stepper(
        "c.k + 1",
        r#"LeadsTo(name: "three", from: "c.k == 1", to: "c.k == 3")"#,
    );
    let report = explored(&system);
    let row = report.property("three worst response").expect("the row");
    assert!(row.verdict.holds(), "{:?}", row.verdict);
    assert_eq!(
        (row.worst_us, row.note.as_deref()),
        (None, Some("5 time units"))
    );
    let p = responses(&system)[0];
    assert_eq!(wait_along(&system, p, row), (5, true));
    // the bounded search agrees
    let verdict = |k: u64| verdicts(&bounded(&system, &[k]))[0].clone();
    assert_eq!(verdict(5), ("three".to_string(), true, false));
    assert_eq!(verdict(4), ("three".to_string(), false, true));
}
