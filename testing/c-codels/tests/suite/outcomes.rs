//! Each outcome a C codel returns, read by the engine: a declared yield or exception moves
//! the model as declared; an undeclared exception, another codel's yield, an address of
//! no event, or `genom_ok` takes the activity's error path, reported as a fault. Every run
//! is a path of the model.

use bip_c_codels::hooks::{set_step_outcome, OUTCOME_LOCK};
use bip_engine::{Engine, Event, FaultKind, Outcome, Reply, Until};

use crate::{engine, system, Counter};

/// Runs `Count(n)` with `counter_count_step` returning outcome `mode`; its end, the
/// engine's faults, and the module's state.
fn count(n: i64, mode: i32) -> (Outcome, u64, Counter) {
    let _guard = OUTCOME_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    set_step_outcome(mode);
    let system = system();
    let (mut engine, counter) = engine(&system, 1);
    let ticket = engine.request("counter", "Count", n).expect("a request");
    engine.run_until(Until::Ticks(20)).expect("runs");
    let end = done(&mut engine, ticket).expect("Count ends");
    let faults = engine.inspect().stats().faults;
    engine
        .record()
        .replay(&system)
        .expect("a path of the model");
    set_step_outcome(0);
    (end, faults, counter)
}

fn done(engine: &mut Engine, ticket: bip_engine::Ticket) -> Option<Outcome> {
    engine.events().find_map(|ev| match ev {
        Event::Reply {
            ticket: t,
            reply: Reply::Done { outcome, .. },
            ..
        } if t == ticket => Some(outcome),
        _ => None,
    })
}

fn fault_kind(o: Outcome) -> FaultKind {
    match o {
        Outcome::Fault(f) => f.kind,
        other => panic!("not a fault: {other:?}"),
    }
}

#[test]
fn declared_yields_move_the_model_and_the_ids_are_read_back() {
    let (end, faults, counter) = count(3, 0);
    assert_eq!(end, Outcome::Ether);
    assert_eq!(faults, 0);
    // start set 0 and 0.25, then step ran three times (pause::step, pause::step, ether)
    let ids = counter.lock().unwrap().state.ids;
    assert_eq!((ids.count, ids.done, ids.gain), (3, true, 2.0));
}

#[test]
fn start_yielding_ether_ends_at_once() {
    let (end, faults, counter) = count(0, 0);
    assert_eq!(end, Outcome::Ether);
    assert_eq!(faults, 0);
    assert_eq!(counter.lock().unwrap().state.ids.count, 0);
}

#[test]
fn a_declared_exception_ends_the_activity_with_it_and_its_detail() {
    let (end, faults, counter) = count(3, 1);
    assert_eq!(end, Outcome::Exception("e_limit".into()));
    assert_eq!(faults, 0);
    let (_, detail) = counter.lock().unwrap().raised().last().expect("raised");
    // counter_e_limit_detail { int32_t at; }, at the count when thrown
    assert_eq!(detail, 0i32.to_ne_bytes());
}

#[test]
fn an_exception_the_codel_does_not_declare_takes_the_error_path() {
    let (end, faults, _) = count(3, 2);
    assert_eq!(fault_kind(end), FaultKind::UndeclaredException("e_stray"));
    assert_eq!(faults, 1);
}

#[test]
fn another_codels_yield_takes_the_error_path() {
    let (end, faults, _) = count(3, 3);
    assert_eq!(fault_kind(end), FaultKind::BadTransition("step"));
    assert_eq!(faults, 1);
}

#[test]
fn an_address_of_no_event_or_genom_ok_takes_the_error_path() {
    for mode in [4, 5] {
        let (end, faults, _) = count(3, mode);
        assert_eq!(fault_kind(end), FaultKind::UndeclaredOutcome(u16::MAX));
        assert_eq!(faults, 1);
    }
}

#[test]
fn a_codel_taking_an_ids_member_by_value_runs() {
    let _guard = OUTCOME_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let system = system();
    let (mut engine, _) = engine(&system, 2);
    let ticket = engine.request("counter", "Idle", ()).expect("a request");
    engine.run_until(Until::Ticks(5)).expect("runs");
    assert_eq!(done(&mut engine, ticket), Some(Outcome::Ether));
    engine
        .record()
        .replay(&system)
        .expect("a path of the model");
}

#[test]
fn codels_numbered_otherwise_than_the_model_do_not_bind() {
    let system = system();
    let builder =
        Engine::builder(system).module("counter", &bip_c_codels::counter::CODELS[..2], |_, _| {
            bip_engine::Next::ETHER
        });
    let err = builder.build().err().expect("refused").to_string();
    assert!(err.contains("they have 2 codels, the model 6"), "{err}");
}

#[test]
fn a_record_argument_is_its_mirror_passed_by_pointer() {
    use bip_c_codels::place as Place;
    let _guard = OUTCOME_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let system = system();
    let (mut engine, counter) = engine(&system, 3);
    // the engine checks the mirror by its name against `Record(name: "place", ..)`
    let err = engine
        .request("counter", "Go", 1.5f64)
        .expect_err("refused");
    assert!(err.to_string().contains("place"), "{err}");
    let to = Place { x: 1.5, y: -2.0 };
    let ticket = engine.request("counter", "Go", to).expect("a request");
    engine.run_until(Until::Ticks(5)).expect("runs");
    assert_eq!(done(&mut engine, ticket), Some(Outcome::Ether));
    let at = counter.lock().unwrap().state.ids.at;
    assert_eq!((at.x, at.y), (1.5, -2.0));
    engine
        .record()
        .replay(&system)
        .expect("a path of the model");
}
