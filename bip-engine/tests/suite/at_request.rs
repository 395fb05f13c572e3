//! Codels at a request (docs/genom.md, "Codels at the request"): a function's codel runs
//! when its request is served, reads the arguments, writes ids and gives an output; its
//! exception or an undeclared return is the request's failed reply; a `validate` codel
//! refuses a request with its exception, or passes it; the recording replays.

use bip_engine::replay::{replay, End};
use bip_engine::*;
use bip_lang::load_str;

const MODEL: &str = r#"System(name: "setter", tick_ms: 10,
    modules: [(name: "m",
        ids: [(name: "x", ty: Int(0, 3), init: 0)],
        tasks: [(name: "t", period: 2)], ports: [(name: "p", ty: Int(0, 3))],
        services: [
            (name: "Set", kind: Function, args: Int(0, 9), output: Int(0, 9),
             validate: (throws: ["too_big"]),
             codels: [(state: "start", yields: ["ether"], throws: ["busy"], writes: ["x", "p"])]),
            (name: "Run", kind: Activity, task: "t", after: ["Set"], args: Int(0, 9),
             validate: (throws: ["odd"]),
             codels: [(state: "start", yields: ["ether"])]),
        ])],
    properties: [DeadlockFree])"#;

fn system() -> bip_model::System {
    load_str("setter.ron", MODEL).expect("loads")
}

/// `Set(v)`: refused by its validation above 3, throws `busy` at 2, sets `x` and `p` to
/// `v` and gives `v + 1` otherwise; 3 returns a yield it does not declare. `Run(v)`:
/// refused when `v` is odd.
fn engine() -> Engine {
    Engine::builder(system())
        .codel(("m", "Set", "validate"), |ctx| match ctx.args::<i64>() {
            Some(&v) if v > 3 => Next::Throw("too_big"),
            _ => Next::Yield("ether"),
        })
        .codel(("m", "Set", "start"), |ctx| {
            let v = ctx.args::<i64>().copied().unwrap_or(0);
            match v {
                2 => Next::Throw("busy"),
                3 => Next::Yield("main"),
                _ => {
                    ctx.set("x", v);
                    ctx.write_port("p", v);
                    ctx.set_output(v + 1);
                    Next::Yield("ether")
                }
            }
        })
        .codel(("m", "Run", "validate"), |ctx| match ctx.args::<i64>() {
            Some(v) if v % 2 == 1 => Next::Throw("odd"),
            _ => Next::Yield("ether"),
        })
        .codel(("m", "Run", "start"), |_| Next::Yield("ether"))
        .record(1000)
        .build()
        .expect("builds")
}

fn replies(e: &mut Engine) -> Vec<Reply> {
    e.events()
        .filter_map(|ev| match ev {
            Event::Reply { reply, .. } => Some(reply),
            _ => None,
        })
        .collect()
}

fn serve(e: &mut Engine, service: &str, v: i64) -> Vec<Reply> {
    e.request("m", service, v).expect("queued");
    e.run_until(Until::Quiescent).expect("runs");
    replies(e)
}

#[test]
fn a_function_codel_runs_at_its_request_and_gives_its_output() {
    let mut e = engine();
    let got = serve(&mut e, "Set", 1);
    let [Reply::Accepted, Reply::Done {
        outcome: Outcome::Ether,
        output: Some(o),
    }] = got.as_slice()
    else {
        panic!("{got:?}")
    };
    assert_eq!(o.get::<i64>(), Some(&2));
    assert_eq!(e.inspect().ids("m", "x"), Some(1));
}

#[test]
fn a_function_codels_exception_or_undeclared_return_is_its_failed_reply() {
    let mut e = engine();
    serve(&mut e, "Set", 1);
    let got = serve(&mut e, "Set", 2);
    assert!(
        matches!(got.as_slice(), [Reply::Accepted, Reply::Done { outcome: Outcome::Exception(x), output: None }] if &**x == "busy"),
        "{got:?}"
    );
    let got = serve(&mut e, "Set", 3);
    assert!(
        matches!(got.as_slice(), [Reply::Accepted, Reply::Done { outcome: Outcome::Fault(f), .. }] if matches!(f.kind, FaultKind::BadTransition("main"))),
        "{got:?}"
    );
    // neither wrote its ids
    assert_eq!(e.inspect().ids("m", "x"), Some(1));
    let trace = e.record();
    let steps: Vec<&str> = trace.steps.iter().map(|s| s.step.as_str()).collect();
    assert_eq!(
        steps,
        ["m_Set_request", "m_Set_start_fail", "m_Set_start_fail"]
    );
}

#[test]
fn a_validation_refuses_a_request_with_its_exception_or_passes_it() {
    let mut e = engine();
    let got = serve(&mut e, "Set", 7);
    assert!(
        matches!(got.as_slice(), [Reply::Refused(Refusal::Validation(Outcome::Exception(x)))] if &**x == "too_big"),
        "{got:?}"
    );
    assert_eq!(
        e.inspect().ids("m", "x"),
        Some(0),
        "the function did not run"
    );
    // a refusal by the model comes first: `Run` waits for `Set`, and no validation runs
    let got = serve(&mut e, "Run", 1);
    assert!(
        matches!(got.as_slice(), [Reply::Refused(Refusal::Conditions(_))]),
        "{got:?}"
    );
    serve(&mut e, "Set", 0);
    let got = serve(&mut e, "Run", 1);
    assert!(
        matches!(got.as_slice(), [Reply::Refused(Refusal::Validation(Outcome::Exception(x)))] if &**x == "odd"),
        "{got:?}"
    );
    let got = serve(&mut e, "Run", 4);
    assert!(matches!(got.as_slice(), [Reply::Accepted]), "{got:?}");
    e.run_until(Until::Ticks(4)).expect("runs");
    let got = replies(&mut e);
    assert!(
        matches!(
            got.as_slice(),
            [
                Reply::Started,
                Reply::Done {
                    outcome: Outcome::Ether,
                    ..
                }
            ]
        ),
        "{got:?}"
    );
    let trace = e.record();
    let steps: Vec<&str> = trace.steps.iter().map(|s| s.step.as_str()).collect();
    assert_eq!(
        &steps[..4],
        [
            "m_Set_validate_fail",
            "m_Set_request",
            "m_Run_validate_fail",
            "m_Run_request"
        ]
    );
}

#[test]
fn a_recording_with_codels_at_requests_replays() {
    let mut e = engine();
    for (s, v) in [
        ("Set", 9),
        ("Set", 2),
        ("Set", 1),
        ("Run", 3),
        ("Run", 2),
        ("Set", 3),
    ] {
        serve(&mut e, s, v);
        e.run_until(Until::Ticks(2)).expect("runs");
    }
    let trace = e.record();
    // with default codels, each step is what the trace says
    let r = replay(system(), &trace).expect("builds");
    assert!(r.refused.is_none(), "{:?}", r.refused);
    assert_eq!(r.end, Some(End::Recording));
    assert_eq!(r.steps.len(), trace.steps.len());
    assert_eq!(r.engine.inspect().state(), e.inspect().state());
    let refusals = r
        .steps
        .iter()
        .filter(|s| {
            matches!(
                s.stepped,
                Stepped::Request {
                    accepted: false,
                    ..
                }
            )
        })
        .count();
    assert_eq!(refusals, 2, "Set(9) and Run(3)");
}

#[test]
fn default_codels_take_every_outcome_of_a_request() {
    let mut seen = std::collections::BTreeSet::new();
    for seed in 0..40 {
        let mut e = Engine::builder(system())
            .default_codels(DefaultCodels::Random(seed))
            .policy(Policy::Seeded(seed))
            .record(1000)
            .build()
            .expect("builds");
        for _ in 0..3 {
            serve(&mut e, "Set", 0);
        }
        for s in e.record().steps {
            seen.insert(s.step);
        }
    }
    let want = ["m_Set_request", "m_Set_start_fail", "m_Set_validate_fail"];
    assert!(want.iter().all(|w| seen.contains(*w)), "{seen:?}");
}

#[test]
fn a_codel_at_a_request_the_model_sends_is_refused() {
    let model = MODEL.replace(
        "properties: [DeadlockFree]",
        r#"atoms: {"Sup": Atom(locations: ["s"], initial: "s", ports: ["go"],
              transitions: [(from: "s", port: "go", to: "s")])},
           components: [(name: "sup", atom: "Sup")],
           connectors: [(name: "m_Set_request", ports: ["sup.go"])]"#,
    );
    let system = load_str("owned.ron", &model).expect("loads");
    let built = Engine::builder(system)
        .default_codels(DefaultCodels::FirstYield)
        .build();
    let Err(BuildError::AtRequest(m, s, c)) = built else {
        panic!("not refused")
    };
    assert_eq!(
        (m.as_str(), s.as_str(), c.as_str()),
        ("m", "Set", "validate")
    );
}
