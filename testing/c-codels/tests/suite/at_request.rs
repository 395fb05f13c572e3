//! C codels at a request (docs/genom.md, "Codels at the request"): `SetGain`'s
//! validation refuses a negative gain with its exception; its C function codel gives the
//! gain it replaces as the output and writes the ids, throws above 100, and an event of
//! no component is a fault; every run replays against the model.

use bip_engine::{Engine, Event, FaultKind, Outcome, Refusal, Reply, Until};

use crate::{engine, system, Counter};

/// Sends `SetGain(g)` for each gain in turn (each served before the next), and returns
/// each one's replies, with the module object.
fn set_gains(gains: &[f64]) -> (Vec<Vec<Reply>>, Counter) {
    let system = system();
    let (mut engine, counter) = engine(&system, 3);
    let mut out = Vec::new();
    for &g in gains {
        let t = engine.request("counter", "SetGain", g).expect("a request");
        engine.run_until(Until::Quiescent).expect("runs");
        out.push(replies(&mut engine, t));
    }
    engine
        .record()
        .replay(&system)
        .expect("a path of the model");
    (out, counter)
}

fn replies(engine: &mut Engine, ticket: bip_engine::Ticket) -> Vec<Reply> {
    engine
        .events()
        .filter_map(|ev| match ev {
            Event::Reply {
                ticket: t, reply, ..
            } if t == ticket => Some(reply),
            _ => None,
        })
        .collect()
}

#[test]
fn a_function_codel_gives_its_output_and_writes_the_ids() {
    let (got, counter) = set_gains(&[0.5, 2.0]);
    let outputs: Vec<Option<f64>> = got
        .iter()
        .map(|r| match r.as_slice() {
            [Reply::Accepted, Reply::Done {
                outcome: Outcome::Ether,
                output: Some(o),
            }] => o.get::<f64>().copied(),
            other => panic!("{other:?}"),
        })
        .collect();
    // the ids' gain starts at 0; each call gives back the one it replaces
    assert_eq!(outputs, [Some(0.0), Some(0.5)]);
    assert_eq!(counter.lock().unwrap().state.ids.gain, 2.0);
}

#[test]
fn a_validation_refuses_with_its_exception_and_nothing_runs() {
    let (got, counter) = set_gains(&[1.5, -3.0]);
    let [Reply::Refused(Refusal::Validation(Outcome::Exception(e)))] = got[1].as_slice() else {
        panic!("{:?}", got[1])
    };
    assert_eq!(&**e, "e_limit");
    // the refused request did not run the function
    assert_eq!(counter.lock().unwrap().state.ids.gain, 1.5);
}

#[test]
fn a_function_codels_exception_or_stray_event_is_its_failed_reply() {
    let (got, counter) = set_gains(&[7.0, 500.0, 42.0]);
    let ends: Vec<&Outcome> = got
        .iter()
        .map(|r| match r.as_slice() {
            [Reply::Accepted, Reply::Done { outcome, .. }] => outcome,
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(ends[0], &Outcome::Ether);
    assert!(
        matches!(ends[1], Outcome::Exception(e) if &**e == "e_limit"),
        "{:?}",
        ends[1]
    );
    let Outcome::Fault(f) = ends[2] else {
        panic!("{:?}", ends[2])
    };
    assert!(
        matches!(f.kind, FaultKind::UndeclaredOutcome(_)),
        "{:?}",
        f.kind
    );
    // neither failure wrote the ids: the step that took it is the error path
    assert_eq!(counter.lock().unwrap().state.ids.gain, 7.0);
}
