//! Faults: a codel that panics, returns a state outside its `yields`, throws what it does
//! not declare, writes ids it does not declare or out of their range, or writes a port it
//! may not, takes its activity's error path and is reported; the engine goes on and its
//! state stays a model state. A codel that runs longer than its task's period is reported
//! as an overrun.

use crate::common;

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

use bip_engine::*;
use common::*;

/// Runs the `main` codel of IDS_MODEL once with `body`, then once more normally; returns
/// the engine and the events.
fn run_main(
    body: impl FnMut(&mut Ctx<'_>) -> Next + Send + 'static,
    clock: Option<VirtualClock>,
) -> (Engine, Vec<Event>) {
    let mut b = Engine::builder(load_text(IDS_MODEL))
        .codel(("m", "S", "start"), |_| Next::Yield("pause::main"))
        .codel(("m", "S", "main"), body)
        .record(1000);
    if let Some(c) = clock {
        b = b.clock(c);
    }
    let mut e = b.build().expect("builds");
    e.request("m", "Init", ()).expect("queued");
    e.request("m", "S", ()).expect("queued");
    e.run_until(Until::Ticks(12)).expect("runs");
    let events = e.events().collect();
    (e, events)
}

fn faults(events: &[Event]) -> Vec<FaultKind> {
    events
        .iter()
        .filter_map(|e| match e {
            Event::Fault(f) => Some(f.kind.clone()),
            _ => None,
        })
        .collect()
}

fn done(events: &[Event]) -> Vec<Outcome> {
    events
        .iter()
        .filter_map(|e| match e {
            Event::Reply {
                reply: Reply::Done { outcome, .. },
                ..
            } => Some(outcome.clone()),
            _ => None,
        })
        .collect()
}

/// The activity ended on its error path, the trace is a path of the model, the ids kept
/// their values, and the engine still serves a new request to completion.
fn assert_error_path_and_recovery(mut e: Engine, events: &[Event]) {
    let outcomes = done(events);
    assert!(
        matches!(outcomes.last(), Some(Outcome::Fault(_))),
        "{outcomes:?}"
    );
    let sys = e.inspect().system().clone();
    let c = sys.component_index("m_S").expect("activity");
    assert_eq!(sys.location_name(e.inspect().state(), c), "ether");
    let trace = e.record();
    let states = states_of(&sys, &trace);
    assert_invariants(&sys, &states);
    assert!(
        trace.steps.iter().any(|s| s.step == "m_S_main_fail"),
        "the error path is a step of the model"
    );
    assert_eq!(
        e.inspect().ids("m", "speed"),
        Some(1),
        "errors write no ids"
    );
    assert_eq!(e.inspect().ids("m", "on"), Some(0));
    // the engine goes on
    let t = e.request("m", "S", ()).expect("queued");
    e.run_until(Until::Ticks(4)).expect("runs");
    let service = e_service(&e);
    assert!(e.events().any(|ev| matches!(ev,
        Event::Reply {
            ticket,
            service: s,
            reply: Reply::Accepted
        } if ticket == t && s.id == service)));
}

fn e_service(e: &Engine) -> ServiceId {
    e.inspect().service_id("m", "S").expect("service")
}

#[test]
fn a_codel_that_panics_takes_the_error_path() {
    silence_injected_panics();
    let (e, events) = run_main(|_| panic!("injected: wheel encoder unplugged"), None);
    let f = faults(&events);
    assert!(
        matches!(&f[..], [FaultKind::Panic(m), ..] if m.contains("wheel encoder")),
        "{f:?}"
    );
    assert_error_path_and_recovery(e, &events);
}

#[test]
fn a_yield_outside_the_declared_yields_is_a_bad_transition() {
    let (e, events) = run_main(|_| Next::Yield("pause::start"), None);
    assert_eq!(faults(&events)[0], FaultKind::BadTransition("pause::start"));
    assert_error_path_and_recovery(e, &events);
}

#[test]
fn a_yield_is_told_by_its_text_not_by_where_the_text_is() {
    // after a declared yield, an undeclared one that starts at the same address (a longer
    // text) and one of the same length (another text) are still bad transitions
    let long: &'static str = "pause::mainX";
    let short: &'static str = &long[..11];
    let same_length: &'static str = "pause::xxxx";
    let runs = Arc::new(AtomicU32::new(0));
    let r = runs.clone();
    let (mut e, events) = run_main(
        move |_| match r.fetch_add(1, Ordering::SeqCst) {
            0 => Next::Yield(short),
            1 => Next::Yield(long),
            2 => Next::Yield(same_length),
            _ => Next::Yield(short),
        },
        None,
    );
    assert_eq!(runs.load(Ordering::SeqCst), 2);
    assert_eq!(faults(&events), [FaultKind::BadTransition("pause::mainX")]);
    e.request("m", "S", ()).expect("queued");
    e.run_until(Until::Ticks(12)).expect("runs");
    let events: Vec<Event> = e.events().collect();
    assert_eq!(faults(&events), [FaultKind::BadTransition("pause::xxxx")]);
    e.request("m", "S", ()).expect("queued");
    e.run_until(Until::Ticks(6)).expect("runs");
    let events: Vec<Event> = e.events().collect();
    assert!(faults(&events).is_empty(), "{events:?}");
}

#[test]
fn an_undeclared_exception_is_a_fault_and_a_declared_one_an_outcome() {
    let (e, events) = run_main(|_| Next::Throw("e_other"), None);
    assert_eq!(
        faults(&events)[0],
        FaultKind::UndeclaredException("e_other")
    );
    assert_error_path_and_recovery(e, &events);
    let (_, events) = run_main(|_| Next::Throw("e_bad"), None);
    assert!(faults(&events).is_empty());
    assert_eq!(
        done(&events).last(),
        Some(&Outcome::Exception("e_bad".into()))
    );
}

/// `Next::Declared(k)` numbers `main`'s outcomes as the model declares them: `pause::main`,
/// `ether`, then `e_bad`; past them is a fault.
#[test]
fn a_declared_outcome_is_numbered_yields_then_exceptions() {
    let (_, events) = run_main(|_| Next::Declared(1), None);
    assert!(faults(&events).is_empty(), "{events:?}");
    assert_eq!(done(&events).last(), Some(&Outcome::Ether));
    let (_, events) = run_main(|_| Next::Declared(2), None);
    assert!(faults(&events).is_empty(), "{events:?}");
    assert_eq!(
        done(&events).last(),
        Some(&Outcome::Exception("e_bad".into()))
    );
    let (e, events) = run_main(|_| Next::Declared(3), None);
    assert_eq!(faults(&events)[0], FaultKind::UndeclaredOutcome(3));
    assert_error_path_and_recovery(e, &events);
    // `pause::main` loops: the codel runs again, and ends the second time
    let runs = Arc::new(AtomicU32::new(0));
    let r = runs.clone();
    let (_, events) = run_main(
        move |_| Next::Declared(u16::from(r.fetch_add(1, Ordering::SeqCst) > 0)),
        None,
    );
    assert!(runs.load(Ordering::SeqCst) >= 2);
    assert_eq!(done(&events).last(), Some(&Outcome::Ether));
}

#[test]
fn ids_left_out_of_range_are_a_fault_and_are_not_written() {
    let (e, events) = run_main(
        |ctx| {
            ctx.set("speed", 7);
            Next::Yield("pause::main")
        },
        None,
    );
    assert_eq!(
        faults(&events)[0],
        FaultKind::IdsOutOfRange {
            field: "speed".into(),
            value: 7
        }
    );
    assert_error_path_and_recovery(e, &events);
}

#[test]
fn writing_an_undeclared_ids_field_or_port_is_a_fault() {
    let (e, events) = run_main(
        |ctx| {
            ctx.set("altitude", 1);
            Next::ETHER
        },
        None,
    );
    assert_eq!(
        faults(&events)[0],
        FaultKind::UndeclaredIdsWrite("altitude".into())
    );
    assert_error_path_and_recovery(e, &events);
    let (e, events) = run_main(
        |ctx| {
            ctx.write_port("scan", 1.0f64);
            Next::ETHER
        },
        None,
    );
    assert_eq!(faults(&events)[0], FaultKind::PortWrite("scan".into()));
    assert_error_path_and_recovery(e, &events);
}

#[test]
fn ids_in_range_are_written_by_the_codels_step_and_ports_keep_their_data() {
    let runs = Arc::new(AtomicU32::new(0));
    let n = runs.clone();
    let (e, events) = run_main(
        move |ctx| {
            let k = n.fetch_add(1, Ordering::SeqCst);
            ctx.set("speed", i64::from(k % 4));
            ctx.set_bool("on", true);
            *ctx.port_mut::<Vec<u32>>("pose").expect("declared") = vec![k];
            if k == 2 {
                Next::ETHER
            } else {
                Next::Yield("pause::main")
            }
        },
        None,
    );
    assert!(faults(&events).is_empty(), "{events:?}");
    assert_eq!(done(&events).last(), Some(&Outcome::Ether));
    assert_eq!(e.inspect().ids("m", "speed"), Some(2));
    assert_eq!(e.inspect().ids("m", "on"), Some(1));
    assert_eq!(e.inspect().port::<Vec<u32>>("m", "pose"), Some(&vec![2]));
    // each write is the module pick of the codel's step: the recorded trace shows it
    let trace = e.record();
    let steps: Vec<_> = trace
        .steps
        .iter()
        .filter(|s| s.step == "m_S_main")
        .collect();
    assert_eq!(steps.len(), 3);
    assert!(steps[1]
        .state
        .iter()
        .any(|(k, v)| k == "m.speed" && *v == bip_model::TraceValue::Int(1)));
    states_of(e.inspect().system(), &trace);
}

#[test]
fn a_codel_longer_than_its_period_is_an_overrun() {
    let clock = VirtualClock::new();
    let during = clock.clone();
    // the period is 2 ticks of 10 ms: 20 ms
    let (e, events) = run_main(
        move |_| {
            during.advance(25_000);
            Next::Yield("pause::main")
        },
        Some(clock),
    );
    let overruns: Vec<(u64, u64)> = events
        .iter()
        .filter_map(|ev| match ev {
            Event::Overrun {
                took_us, period_us, ..
            } => Some((*took_us, *period_us)),
            _ => None,
        })
        .collect();
    assert!(!overruns.is_empty());
    assert!(overruns.iter().all(|&(t, p)| t == 25_000 && p == 20_000));
    assert!(faults(&events).is_empty(), "an overrun is not a fault");
    // the ticks it delayed are fired afterwards: none is dropped
    assert!(e.inspect().stats().ticks >= 12);
    let states = states_of(e.inspect().system(), &e.record());
    assert_invariants(e.inspect().system(), &states);
}
