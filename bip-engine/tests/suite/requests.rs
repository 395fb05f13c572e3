//! Requests and replies: refusals with the model's reasons, starts held by a constraint,
//! and the outcome of each activity (ether, exception, interrupted, bad transition).

use crate::common;

use bip_engine::*;
use bip_model::genom::Reason;
use common::*;

fn replies(e: &mut Engine) -> Vec<(Ticket, Reply)> {
    e.events()
        .filter_map(|ev| match ev {
            Event::Reply { ticket, reply, .. } => Some((ticket, reply)),
            _ => None,
        })
        .collect()
}

fn rover() -> EngineBuilder {
    Engine::builder(load("rover.ron"))
        .default_codels(DefaultCodels::FirstYield)
        .record(10_000)
}

#[test]
fn a_request_before_its_after_is_refused_with_the_reason() {
    let mut e = rover().build().expect("builds");
    let t = e.request("rflex", "TrackSpeed", ()).expect("queued");
    e.run_until(Until::Quiescent).expect("runs");
    let got = replies(&mut e);
    let [(ticket, Reply::Refused(Refusal::Conditions(r)))] = got.as_slice() else {
        panic!("{got:?}");
    };
    assert_eq!(*ticket, t);
    let s = e
        .inspect()
        .service_id("rflex", "TrackSpeed")
        .expect("service");
    let map = e.inspect().system().genom.as_ref().expect("layer");
    let refusals = map
        .service("rflex", "TrackSpeed")
        .expect("service")
        .refusals
        .clone();
    let why: Vec<&Reason> = r.iter().map(|k| &refusals[k].reason).collect();
    assert_eq!(
        why,
        [&Reason::After {
            service: "rflex.Init".into()
        }]
    );
    assert!(e
        .inspect()
        .refusal_texts(s, *r)
        .all(|t| t.contains("after rflex.Init")));
    // after Init the same request is accepted
    e.request("rflex", "Init", ()).expect("queued");
    let t2 = e.request("rflex", "TrackSpeed", ()).expect("queued");
    e.run_until(Until::Quiescent).expect("runs");
    assert!(replies(&mut e).contains(&(t2, Reply::Accepted)));
    // a second request while it is active: refused, already requested
    let t3 = e.request("rflex", "TrackSpeed", ()).expect("queued");
    e.run_until(Until::Ticks(2)).expect("runs");
    let got = replies(&mut e);
    let refused = got
        .iter()
        .find_map(|(t, r)| match r {
            Reply::Refused(Refusal::Conditions(r)) if *t == t3 => Some(*r),
            _ => None,
        })
        .expect("refused");
    assert_eq!(
        refused
            .iter()
            .map(|k| &refusals[k].reason)
            .collect::<Vec<_>>(),
        [&Reason::AlreadyRequested]
    );
    states_of(e.inspect().system(), &e.record());
}

#[test]
fn unknown_and_model_owned_services_are_errors_not_replies() {
    let mut e = rover().build().expect("builds");
    assert!(matches!(
        e.request("rflex", "Fly", ()),
        Err(RequestError::UnknownService(..))
    ));
    let mut sat = Engine::builder(load("satellite.ron"))
        .default_codels(DefaultCodels::FirstYield)
        .build()
        .expect("builds");
    assert!(matches!(
        sat.request("acs", "Point", ()),
        Err(RequestError::OwnedByModel(..))
    ));
    // the sequencer sends those requests itself, as steps of the model
    sat.run_until(Until::Ticks(30)).expect("runs");
    assert!(
        sat.inspect().stats().codels > 10,
        "{:?}",
        sat.inspect().stats()
    );
}

#[test]
fn an_exclusive_start_is_held_with_the_constraint_then_runs_when_it_is_free() {
    let mut e = rover().build().expect("builds");
    e.request("rflex", "Init", ()).expect("queued");
    let drive = e.request("rflex", "TrackSpeed", ()).expect("queued");
    e.run_until(Until::Ticks(3)).expect("runs");
    let talk = e.request("antenna", "Communicate", ()).expect("queued");
    e.run_until(Until::Ticks(4)).expect("runs");
    let events: Vec<Event> = e.events().collect();
    assert!(events.iter().any(|ev| matches!(ev,
        Event::Reply {
            ticket,
            service,
            reply: Reply::Accepted
        } if *ticket == talk && service.to_string() == "antenna.Communicate")));
    let start = e
        .inspect()
        .codel_id("antenna", "Communicate", "start")
        .expect("codel");
    let held = events
        .iter()
        .find_map(|ev| match ev {
            Event::Held {
                codel,
                ticket,
                reasons,
            } if codel.id == start => Some((*ticket, *reasons)),
            _ => None,
        })
        .expect("the start is held");
    assert_eq!(held.0, Some(talk));
    let texts: Vec<String> = e.inspect().hold_texts(start, held.1).collect();
    assert!(texts.iter().any(|t| t.contains("Exclusive")), "{texts:?}");
    let active = |e: &Engine, comp: &str| {
        let c = e
            .inspect()
            .system()
            .component_index(comp)
            .expect("component");
        e.inspect().system().location_name(e.inspect().state(), c) != "ether"
    };
    assert!(active(&e, "rflex_TrackSpeed") && !active(&e, "antenna_Communicate"));
    // stopping the motion frees the antenna: TrackSpeed is interrupted, Communicate runs
    e.request("rflex", "Stop", ()).expect("queued");
    e.run_until(Until::Ticks(4)).expect("runs");
    let got = replies(&mut e);
    // by the client's request of rflex.Stop, which interrupts TrackSpeed
    assert!(
        got.iter().any(|(t, r)| *t == drive
            && matches!(r, Reply::Done { outcome: Outcome::Interrupted { by: Some(s) }, .. }
                if s.to_string() == "rflex.Stop")),
        "{got:?}"
    );
    assert!(!active(&e, "rflex_TrackSpeed") && active(&e, "antenna_Communicate"));
    let states = states_of(e.inspect().system(), &e.record());
    assert_invariants(e.inspect().system(), &states);
}

const BLOCKED: f64 = 1.0;
const LOST: f64 = 2.0;
const ARRIVE: f64 = 3.0;
const WANDER: f64 = 4.0;

#[test]
fn replies_carry_the_outcome_ether_exception_interrupted_and_bad_transition() {
    let mut e = rover()
        // the goal (a `Float`, rover.ron's type of GoTo's arguments) says what happens
        .codel(("ndd", "GoTo", "move"), |ctx| match ctx.args::<f64>() {
            Some(&BLOCKED) => Next::Throw("e_blocked"),
            Some(&LOST) => Next::Yield("nowhere"),
            Some(&ARRIVE) => Next::ETHER,
            _ => Next::Yield("pause::move"),
        })
        .build()
        .expect("builds");
    // navigation needs the laser and a fresh pose
    e.request("sick", "Scan", ()).expect("queued");
    e.request("pom", "Track", ()).expect("queued");
    e.run_until(Until::Ticks(4)).expect("runs");
    let mut outcome_of = |args: f64| {
        let t = e.request("ndd", "GoTo", args).expect("queued");
        e.run_until(Until::Ticks(4)).expect("runs");
        let got = replies(&mut e);
        assert!(got.contains(&(t, Reply::Accepted)), "{args}: {got:?}");
        got.into_iter().find_map(|(k, r)| match r {
            Reply::Done { outcome, .. } if k == t => Some(outcome),
            _ => None,
        })
    };
    assert_eq!(outcome_of(ARRIVE), Some(Outcome::Ether));
    assert_eq!(
        outcome_of(BLOCKED),
        Some(Outcome::Exception("e_blocked".into()))
    );
    let lost = outcome_of(LOST);
    assert!(
        matches!(
            &lost,
            Some(Outcome::Fault(Fault {
                kind: FaultKind::BadTransition("nowhere"),
                ..
            }))
        ),
        "{lost:?}"
    );
    // a goal that never arrives is replaced by the next one: interrupted
    let first = e.request("ndd", "GoTo", WANDER).expect("queued");
    e.run_until(Until::Ticks(3)).expect("runs");
    let second = e.request("ndd", "GoTo", ARRIVE).expect("queued");
    e.run_until(Until::Ticks(5)).expect("runs");
    let got = replies(&mut e);
    // replaced by the next request of the same service
    assert!(
        got.iter().any(|(t, r)| *t == first
            && matches!(r, Reply::Done { outcome: Outcome::Interrupted { by: Some(s) }, .. }
                if s.to_string() == "ndd.GoTo")),
        "{got:?}"
    );
    assert!(
        got.contains(&(second, Reply::done(Outcome::Ether))),
        "{got:?}"
    );
    let states = states_of(e.inspect().system(), &e.record());
    assert_invariants(e.inspect().system(), &states);
}

#[test]
fn a_function_is_done_when_accepted_and_a_codel_may_read_its_request_arguments() {
    let seen = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let log = seen.clone();
    let mut e = Engine::builder(load_text(IDS_MODEL))
        .codel(("m", "S", "start"), move |ctx| {
            log.lock()
                .expect("lock")
                .push(*ctx.args::<u32>().unwrap_or(&0));
            Next::Yield("pause::main")
        })
        .codel(("m", "S", "main"), |_| Next::ETHER)
        .build()
        .expect("builds");
    let init = e.request("m", "Init", ()).expect("queued");
    e.run_until(Until::Quiescent).expect("runs");
    assert_eq!(
        replies(&mut e),
        [(init, Reply::Accepted), (init, Reply::done(Outcome::Ether))]
    );
    let t = e.request("m", "S", 42u32).expect("queued");
    e.run_until(Until::Ticks(6)).expect("runs");
    assert_eq!(*seen.lock().expect("lock"), [42]);
    assert!(replies(&mut e).contains(&(t, Reply::done(Outcome::Ether))));
}

#[test]
fn unbound_codels_are_a_build_error_unless_defaults_are_asked_for() {
    let err = Engine::builder(load("rover.ron")).build().err();
    assert!(matches!(err, Some(BuildError::Unbound(..))), "{err:?}");
    let err = Engine::builder(load("rover.ron"))
        .codel(("rflex", "TrackSpeed", "fly"), |_| Next::ETHER)
        .build()
        .err();
    assert!(matches!(err, Some(BuildError::UnknownCodel(..))), "{err:?}");
    let err = Engine::builder(load("rover.ron"))
        .codel(("rflex", "TrackSpeed", "track"), |_| Next::ETHER)
        .codel(("rflex", "TrackSpeed", "track"), |_| Next::ETHER)
        .default_codels(DefaultCodels::FirstYield)
        .build()
        .err();
    assert!(matches!(err, Some(BuildError::BoundTwice(..))), "{err:?}");
    let err = Engine::builder(load("philosophers.ron"))
        .codel(("a", "B", "c"), |_| Next::ETHER)
        .build()
        .err();
    assert!(matches!(err, Some(BuildError::NoGenomLayer)), "{err:?}");
}

#[test]
fn a_core_model_runs_its_own_steps() {
    // no GenoM layer: the engine takes the model's progress steps by itself (the
    // asymmetric philosophers never deadlock)
    let mut e = Engine::builder(load("philosophers-asymmetric.ron"))
        .policy(Policy::Seeded(3))
        .record(100)
        .build()
        .expect("builds");
    e.run_until(Until::Steps(60)).expect("runs");
    assert_eq!(e.inspect().stats().steps, 60);
    states_of(e.inspect().system(), &e.record());
}

#[test]
fn a_function_named_by_a_constraint_is_refused_with_the_constraint() {
    // `Requires` on a function gates its request: refused while the laser is off
    let mut e = Engine::builder(load_text(
        r#"System(
        name: "gated",
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
        constraints: [Requires(name: "scan_first", service: "m.Snapshot", active: ["m.Scan"])],
    )"#,
    ))
    .default_codels(DefaultCodels::FirstYield)
    .record(1000)
    .build()
    .expect("builds");
    let s = e.inspect().service_id("m", "Snapshot").expect("service");
    let early = e.request("m", "Snapshot", ()).expect("queued");
    e.run_until(Until::Quiescent).expect("runs");
    let got = replies(&mut e);
    let [(t, Reply::Refused(Refusal::Conditions(r)))] = got.as_slice() else {
        panic!("{got:?}");
    };
    assert_eq!(*t, early);
    let refusals = &e
        .inspect()
        .system()
        .genom
        .as_ref()
        .expect("layer")
        .service("m", "Snapshot")
        .expect("service")
        .refusals;
    let why: Vec<&Reason> = r.iter().map(|k| &refusals[k].reason).collect();
    let [Reason::Constraint(c)] = why.as_slice() else {
        panic!("{why:?}");
    };
    assert_eq!((c.index, c.kind.as_str()), (0, "Requires"));
    // the refusal speaks of the constraint as written, not of its expanded guard
    let texts: Vec<String> = e.inspect().refusal_texts(s, *r).collect();
    assert_eq!(
        texts,
        [r#"scan_first (line 15): Requires(service: "m.Snapshot", active: ["m.Scan"])"#]
    );
    // once the scan runs, the same request is accepted and done
    e.request("m", "Scan", ()).expect("queued");
    e.run_until(Until::Ticks(2)).expect("runs");
    let later = e.request("m", "Snapshot", ()).expect("queued");
    e.run_until(Until::Ticks(1)).expect("runs");
    let got = replies(&mut e);
    assert!(got.contains(&(later, Reply::Accepted)), "{got:?}");
    assert!(
        got.contains(&(later, Reply::done(Outcome::Ether))),
        "{got:?}"
    );
    states_of(e.inspect().system(), &e.record());
}

/// A task's machine starts with the engine and runs its codels with no request; a request
/// for it is an error, not a reply.
#[test]
fn a_task_machine_runs_unrequested_and_cannot_be_requested() {
    let mut e = Engine::builder(load("tests/task-machine.ron"))
        .default_codels(DefaultCodels::FirstYield)
        .build()
        .expect("builds");
    assert!(matches!(
        e.request("flight", "main", ()),
        Err(RequestError::TaskMachine(..))
    ));
    e.run_until(Until::Ticks(6)).expect("runs");
    // start at the first boundary (tick 2), init (its first yield, `pause::init`) at the
    // second (tick 4); the codels after tick 6 are past `Ticks(6)`
    let s = e.inspect();
    assert_eq!(s.stats().requests_accepted, 0);
    assert_eq!(s.stats().codels, 2, "{:?}", s.stats());
    let machine = s.system().component_index("flight_main").expect("machine");
    assert_eq!(s.system().location_name(s.state(), machine), "init");
}

#[test]
fn a_pending_request_interrupts_what_is_requested_after_it() {
    // robots/tests/interrupts.ron: `Open` interrupts `Grasp`, which holds until interrupted
    let mut e = Engine::builder(load("tests/interrupts.ron"))
        .default_codels(DefaultCodels::FirstYield)
        .record(1_000)
        .build()
        .expect("builds");
    let open = e.request("gripper", "Open", ()).expect("queued");
    let grasp = e.request("gripper", "Grasp", ()).expect("queued");
    e.run_until(Until::Ticks(6)).expect("runs");
    let got = replies(&mut e);
    // `Grasp` is accepted while `Open` waits for its period, and interrupted by it
    assert!(got.contains(&(grasp, Reply::Accepted)), "{got:?}");
    assert!(
        got.iter().any(|(t, r)| *t == grasp
            && matches!(r, Reply::Done { outcome: Outcome::Interrupted { by: Some(s) }, .. }
                if s.to_string() == "gripper.Open")),
        "{got:?}"
    );
    assert!(!got.contains(&(grasp, Reply::Started)), "{got:?}");
    // `Open` is not starved: it runs and ends
    assert!(got.contains(&(open, Reply::Started)), "{got:?}");
    assert!(
        got.contains(&(open, Reply::done(Outcome::Ether))),
        "{got:?}"
    );
    // every recorded state keeps the model's invariants (`Open` waits only for a stop)
    let states = states_of(e.inspect().system(), &e.record());
    assert_invariants(e.inspect().system(), &states);
    // the recording replays through an engine, the interrupts as a step of the model
    let r = bip_engine::replay::replay(load("tests/interrupts.ron"), &e.record()).expect("builds");
    assert!(r.refused.is_none(), "{:?}", r.refused);
    assert_eq!(r.steps.len(), e.record().steps.len());
    assert!(r.steps.iter().any(|s| s.stepped == Stepped::Other));
}
