//! Replaying traces through the engine: rover-deadlock's counterexample reaches the
//! deadlock (the navigation's start held by `Requires`), an engine's own recording replays
//! step by step, and a step the model does not allow is refused with the reason.

use crate::common;

use bip_engine::replay::{replay, End};
use bip_engine::*;
use bip_model::Verdict;
use common::*;

#[test]
fn rover_deadlocks_counterexample_reaches_the_deadlock_through_the_engine() {
    // what `bip verify robots/rover-deadlock.ron` prints and saves (tests/genom.rs at the
    // root checks it against the verifier's own trace)
    let text = r#"Trace(
        system: "rover_deadlock",
        verdict: Deadlock,
        steps: [(step: "ndd_GoTo_request", state: {"ndd_GoTo.req": true, "ndd_GoTo.paused": true})],
    )"#;
    let trace = bip_lang::trace_file::from_ron(text).expect("reads");
    let r = replay(load("rover-deadlock.ron"), &trace).expect("builds");
    assert!(r.refused.is_none());
    assert_eq!(r.steps.len(), 1);
    assert!(matches!(
        r.steps[0].stepped,
        Stepped::Request { accepted: true, .. }
    ));
    let Some(End::Deadlock { held }) = &r.end else {
        panic!("{:?}", r.end);
    };
    assert_eq!(held.len(), 1, "{held:?}");
    assert!(
        held[0].starts_with("ndd.GoTo codel `start` (waits for its period), held by")
            && held[0].contains("Requires"),
        "{held:?}"
    );
    // and the same trace on the fixed rover is not a deadlock: the safety rule aborts
    let r = replay(load("rover.ron"), &trace).expect("builds");
    assert!(
        matches!(r.end, Some(End::NotConfirmed { .. })),
        "{:?}",
        r.end
    );
}

#[test]
fn an_engine_recording_replays_step_by_step() {
    let mut e = Engine::builder(load("rover.ron"))
        .default_codels(DefaultCodels::Random(5))
        .policy(Policy::Seeded(5))
        .record(1000)
        .build()
        .expect("builds");
    for (m, s) in [
        ("rflex", "Init"),
        ("sick", "Scan"),
        ("pom", "Track"),
        ("ndd", "GoTo"),
        ("rflex", "TrackSpeed"),
    ] {
        e.request(m, s, ()).expect("queued");
        e.run_until(Until::Ticks(3)).expect("runs");
    }
    let trace = e.record();
    let r = replay(e.inspect().system().clone(), &trace).expect("builds");
    assert!(r.refused.is_none(), "{:?}", r.refused);
    assert_eq!(r.steps.len(), trace.steps.len());
    assert_eq!(r.end, Some(End::Recording));
    assert_eq!(r.engine.inspect().state(), e.inspect().state());
    // replayed codel steps ran as codels, requests as requests, ticks as ticks
    for (s, t) in r.steps.iter().zip(&trace.steps) {
        match s.stepped {
            Stepped::Tick => assert_eq!(t.step, "tick"),
            Stepped::Codel { .. } => assert!(t.step.starts_with(|c: char| c.is_lowercase())),
            Stepped::Request { accepted, .. } => {
                assert!(accepted && t.step.ends_with("_request"))
            }
            Stepped::Other => assert_eq!(t.step, "abort_blind_navigation"),
            other => panic!("{other:?} for {}", t.step),
        }
    }
}

#[test]
fn a_step_the_model_does_not_allow_is_refused_with_the_reason() {
    // the navigation's start needs the laser: without it, it is held by `Requires`
    let text = r#"Trace(
        system: "rover",
        verdict: None,
        steps: [
            (step: "ndd_GoTo_request", state: {"ndd_GoTo.req": true, "ndd_GoTo.paused": true}),
            (step: "tick", state: {"clock.n": 1, "ndd_GoTo.paused": false}),
            (step: "ndd_GoTo_start", state: {"ndd_GoTo": "move"}),
        ],
    )"#;
    let trace = bip_lang::trace_file::from_ron(text).expect("reads");
    let r = replay(load("rover-deadlock.ron"), &trace).expect("builds");
    let refused = r.refused.expect("refused");
    assert_eq!((refused.step, refused.name.as_str()), (3, "ndd_GoTo_start"));
    assert!(
        refused.reasons.iter().any(|x| x.contains("Requires")),
        "{refused:?}"
    );
    assert_eq!(r.steps.len(), 2);
    assert_eq!(trace.verdict, Verdict::None);
}
