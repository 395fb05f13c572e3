//! Async codels (docs/engine.md, "Async codels"): the engine runs one on a thread of its
//! own; its task's other activity goes on meanwhile; its return and outcome are the
//! model's steps, and its writes take effect at its outcome (or not at all when an
//! interrupt drops it). The recordings replay against the model.

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use bip_engine::{Engine, Event, Next, Outcome, Reply, Ticket};

use super::common::{load_text, states_of};

const MODEL: &str = r#"System(name: "apart", tick_ms: 1,
    modules: [(name: "m",
        ids: [(name: "frames", ty: Int(0, 3))],
        tasks: [(name: "t", period: 1)],
        ports: [(name: "image")],
        services: [
            (name: "Grab", kind: Activity, task: "t", codels: [
                (state: "start", yields: ["grab"]),
                (state: "grab", yields: ["ether"], async: true, writes: ["frames", "image"])]),
            (name: "Tune", kind: Activity, task: "t", codels: [
                (state: "start", yields: ["pause::start"])]),
            (name: "Halt", kind: Function, interrupts: ["Grab"]),
        ])])"#;

/// An engine whose `Grab.grab` tells `started` when it runs, then blocks until `release`
/// says; it writes `frames` and `image`. `Tune.start` counts its runs.
fn engine(started: Sender<()>, release: Receiver<()>, tunes: Arc<AtomicU32>) -> Engine {
    let release = Mutex::new(release);
    Engine::builder(load_text(MODEL))
        .codel(("m", "Grab", "start"), |_| Next::Yield("grab"))
        .codel(("m", "Grab", "grab"), move |ctx| {
            let _ = started.send(());
            let _ = release.lock().expect("lock").recv();
            ctx.set("frames", 2);
            ctx.write_port("image", 7i64);
            Next::ETHER
        })
        .codel(("m", "Tune", "start"), move |_| {
            tunes.fetch_add(1, Ordering::SeqCst);
            Next::Yield("pause::start")
        })
        .record(100_000)
        .build()
        .expect("builds")
}

/// The outcome of the request `ticket`, once one of `events` ends it.
fn end_of(events: &[Event], ticket: Ticket) -> Option<Outcome> {
    events.iter().find_map(|e| match e {
        Event::Reply {
            ticket: t,
            reply: Reply::Done { outcome, .. },
            ..
        } if *t == ticket => Some(outcome.clone()),
        _ => None,
    })
}

/// Steps until `ticket` ends (the async codel's thread returns in its own time).
fn step_until_done(e: &mut Engine, events: &mut Vec<Event>, ticket: Ticket) -> Outcome {
    for _ in 0..20_000 {
        e.step().expect("steps");
        events.extend(e.events());
        if let Some(o) = end_of(events, ticket) {
            return o;
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    panic!("the request never ended: {events:?}");
}

/// The names of the recorded steps.
fn step_names(e: &Engine) -> Vec<String> {
    e.record().steps.into_iter().map(|s| s.step).collect()
}

/// The recording is a run of the model, and the engine replays it.
fn assert_replays(e: &Engine) {
    let system = load_text(MODEL);
    let trace = e.record();
    assert_eq!(states_of(&system, &trace).len(), trace.steps.len() + 1);
    let replay = bip_engine::replay::replay(system, &trace).expect("builds");
    assert!(
        replay.refused.is_none(),
        "refused: {:?}",
        replay.refused.map(|r| r.step)
    );
    assert_eq!(replay.steps.len(), trace.steps.len());
}

#[test]
fn an_async_codel_blocks_apart_while_its_task_runs_its_other_activity() {
    let (started_tx, started) = channel();
    let (release, release_rx) = channel();
    let tunes = Arc::new(AtomicU32::new(0));
    let mut e = engine(started_tx, release_rx, tunes.clone());
    let grab = e.request("m", "Grab", ()).expect("sent");
    e.request("m", "Tune", ()).expect("sent");
    let mut events = Vec::new();
    // the grab starts and blocks; its task goes on running Tune, period after period
    for _ in 0..200 {
        e.step().expect("steps");
        events.extend(e.events());
    }
    started
        .recv_timeout(Duration::from_secs(10))
        .expect("the grab started");
    let before = tunes.load(Ordering::SeqCst);
    assert!(
        before >= 10,
        "Tune ran {before} times while the grab was blocked"
    );
    assert_eq!(end_of(&events, grab), None);
    // running apart is progress, not a codel held
    assert!(
        !events.iter().any(|e| matches!(e, Event::Held { .. })),
        "{events:?}"
    );
    // nothing of the grab's writes shows while it runs
    assert_eq!(e.inspect().ids("m", "frames"), Some(0));
    assert_eq!(e.inspect().port::<i64>("m", "image"), None);
    let names = step_names(&e);
    assert!(names.iter().any(|n| n.ends_with("grab_start")), "{names:?}");
    assert!(
        !names.iter().any(|n| n.ends_with("grab_return")),
        "{names:?}"
    );
    // released: its return, then its outcome, commit its writes
    release.send(()).expect("released");
    assert_eq!(step_until_done(&mut e, &mut events, grab), Outcome::Ether);
    assert_eq!(e.inspect().ids("m", "frames"), Some(2));
    assert_eq!(e.inspect().port::<i64>("m", "image"), Some(&7));
    let names = step_names(&e);
    let at = |suffix: &str| names.iter().position(|n| n.ends_with(suffix));
    let (Some(start), Some(ret), Some(outcome)) =
        (at("grab_start"), at("grab_return"), at("m_Grab_grab"))
    else {
        panic!("steps missing: {names:?}");
    };
    assert!(start < ret && ret < outcome, "{names:?}");
    // Tune's codels were committed between the start and the return
    assert!(
        names[start..ret].iter().any(|n| n.contains("Tune")),
        "{names:?}"
    );
    assert_replays(&e);
}

#[test]
fn an_interrupt_during_the_async_run_drops_its_outcome() {
    let (started_tx, started) = channel();
    let (release, release_rx) = channel();
    let mut e = engine(started_tx, release_rx, Arc::new(AtomicU32::new(0)));
    let grab = e.request("m", "Grab", ()).expect("sent");
    let mut events = Vec::new();
    for _ in 0..20 {
        e.step().expect("steps");
        events.extend(e.events());
    }
    started
        .recv_timeout(Duration::from_secs(10))
        .expect("the grab started");
    e.request("m", "Halt", ()).expect("sent");
    for _ in 0..20 {
        e.step().expect("steps");
        events.extend(e.events());
    }
    release.send(()).expect("released");
    let outcome = step_until_done(&mut e, &mut events, grab);
    assert!(
        matches!(outcome, Outcome::Interrupted { .. }),
        "{outcome:?}"
    );
    // the interrupt ended the request at once; the codel returns in its own time, and
    // its outcome, with its writes, is dropped
    let mut names = step_names(&e);
    for _ in 0..20_000 {
        if names.iter().any(|n| n.ends_with("grab_return")) {
            break;
        }
        e.step().expect("steps");
        std::thread::sleep(Duration::from_micros(200));
        names = step_names(&e);
    }
    for _ in 0..20 {
        e.step().expect("steps");
    }
    let names = step_names(&e);
    assert!(
        names.iter().any(|n| n.ends_with("grab_return")),
        "{names:?}"
    );
    assert!(!names.iter().any(|n| n == "m_Grab_grab"), "{names:?}");
    assert_eq!(e.inspect().ids("m", "frames"), Some(0));
    assert_eq!(e.inspect().port::<i64>("m", "image"), None);
    assert_replays(&e);
}

#[test]
fn dropping_the_engine_does_not_wait_for_a_codel_that_never_returns() {
    let (started_tx, started) = channel();
    // held to the end: the grab never returns while the engine lives
    let (release, release_rx) = channel();
    let mut e = engine(started_tx, release_rx, Arc::new(AtomicU32::new(0)));
    e.request("m", "Grab", ()).expect("sent");
    for _ in 0..20 {
        e.step().expect("steps");
    }
    started
        .recv_timeout(Duration::from_secs(10))
        .expect("the grab started");
    let (dropped_tx, dropped) = channel();
    std::thread::spawn(move || {
        drop(e);
        let _ = dropped_tx.send(());
    });
    dropped
        .recv_timeout(Duration::from_secs(10))
        .expect("the engine was dropped while its codel ran");
    // the codel's thread, left detached, ends when its codel returns
    drop(release);
}

/// Module `m` of MODEL as a module object numbers its codels and outcomes.
const MODULE: &[bip_engine::CodelSignature] = &[
    bip_engine::CodelSignature {
        service: "Grab",
        codel: "start",
        yields: &["grab"],
        throws: &[],
    },
    bip_engine::CodelSignature {
        service: "Grab",
        codel: "grab",
        yields: &["ether"],
        throws: &[],
    },
    bip_engine::CodelSignature {
        service: "Tune",
        codel: "start",
        yields: &["pause::start"],
        throws: &[],
    },
];

#[test]
fn a_codel_bound_apart_is_taken_from_its_module_object_and_an_unknown_one_is_refused() {
    // the object answers 0 for its codels; the one bound apart answers its own
    let builder =
        || Engine::builder(load_text(MODEL)).module("m", MODULE, |_, _| Next::Declared(0));
    let mut hosted = builder()
        .apart("m", 1, |ctx| {
            ctx.set("frames", 3);
            Next::Declared(0)
        })
        .hosted(&["m"])
        .expect("hosted");
    let mut ids = vec![0];
    let mut output = None;
    let end = hosted[0].run(
        1,
        bip_engine::HostedRun {
            ids: &mut ids,
            args: None,
            output: &mut output,
            now_us: 0,
            tick: 0,
        },
    );
    assert_eq!(end.next, Ok(Next::Declared(0)));
    assert_eq!(ids, [3], "the closure bound apart ran, not the object");
    let refused = builder()
        .apart("m", 3, |_| Next::ETHER)
        .build()
        .err()
        .map(|e| e.to_string());
    assert_eq!(
        refused.as_deref(),
        Some("codel 3 of module `m` was bound apart, but `m` is bound to no module object with such a codel")
    );
}
