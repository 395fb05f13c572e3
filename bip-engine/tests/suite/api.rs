//! The embedding API without its traps (issue 20): what a new user of the engine tries
//! first works as it reads. Each test is one trap that a fresh controller met.

use crate::common;

use bip_engine::{
    CodelSignature, DefaultCodels, Engine, EngineBuilder, Event, FaultKind, ModuleTypes, Next,
    Outcome, RealClock, Reply, RequestError, ServiceTypes, Stepped, Typed, Until,
};
use common::*;

/// `step()` alone, on the default (virtual) clock, lets time pass: codels run and ticks
/// come, where it used to answer `Idle` forever.
#[test]
fn step_in_a_loop_runs_the_model_on_a_virtual_clock() {
    let mut e = Engine::builder(load("rover.ron"))
        .default_codels(DefaultCodels::FirstYield)
        .build()
        .expect("builds");
    e.request("rflex", "Init", ()).expect("queued");
    e.request("rflex", "TrackSpeed", ()).expect("queued");
    let mut idle = 0;
    for _ in 0..300 {
        if let Stepped::Idle { next_tick_us } = e.step().expect("steps") {
            idle += 1;
            // the clock is already at the next tick: the next step fires it
            assert_eq!(next_tick_us, Some(e.inspect().now_us()));
        }
    }
    let stats = e.inspect().stats();
    assert!(stats.ticks >= 20 && stats.codels >= 20, "{stats:?}");
    assert!(idle >= 20, "{idle} idle steps");
    assert_eq!(e.inspect().now_us(), stats.ticks * e.inspect().tick_us());
}

/// On a real clock `step` never blocks: an idle step says when the next tick is due, and
/// the time is the wall clock's.
#[test]
fn step_on_a_real_clock_does_not_move_time() {
    let mut e = Engine::builder(load("rover.ron"))
        .default_codels(DefaultCodels::FirstYield)
        .clock(RealClock::new())
        .tick_us(10_000_000)
        .build()
        .expect("builds");
    let started = std::time::Instant::now();
    let mut first_idle = None;
    for _ in 0..50 {
        if let Stepped::Idle { next_tick_us } = e.step().expect("steps") {
            first_idle = first_idle.or(next_tick_us);
        }
    }
    // a tick after the engine was built, by the wall clock
    let next = first_idle.expect("idle");
    assert!((10_000_000..11_000_000).contains(&next), "{next}");
    assert!(started.elapsed() < std::time::Duration::from_secs(5));
    assert!(e.inspect().now_us() < 10_000_000);
    assert_eq!(e.inspect().stats().ticks, 0);
}

/// Events name what they are about, so a loop over them reads the names from the event
/// while the engine is borrowed, and each prints as one line in the model's terms.
#[test]
fn events_carry_their_names_and_read_in_the_models_terms() {
    let mut e = Engine::builder(load("rover.ron"))
        .default_codels(DefaultCodels::FirstYield)
        .codel(("ndd", "GoTo", "move"), |_| Next::Yield("pause::nowhere"))
        .build()
        .expect("builds");
    e.request("rflex", "TrackSpeed", ()).expect("queued");
    e.request("rflex", "Init", ()).expect("queued");
    e.request("rflex", "TrackSpeed", ()).expect("queued");
    e.run_until(Until::Ticks(3)).expect("runs");
    e.request("antenna", "Communicate", ()).expect("queued");
    e.request("sick", "Scan", ()).expect("queued");
    e.request("pom", "Track", ()).expect("queued");
    e.run_until(Until::Ticks(3)).expect("runs");
    e.request("ndd", "GoTo", ()).expect("queued");
    e.run_until(Until::Ticks(3)).expect("runs");
    let mut lines = Vec::new();
    let mut names = Vec::new();
    for event in e.events() {
        lines.push(event.to_string());
        match &event {
            Event::Reply { service, .. } => {
                names.push(format!("{}.{}", service.module, service.name))
            }
            Event::Held { codel, .. } | Event::Overrun { codel, .. } => {
                names.push(codel.to_string())
            }
            Event::Fault(f) => names.push(f.codel.to_string()),
            _ => {}
        }
    }
    let has = |want: &str| lines.iter().any(|l| l.contains(want));
    assert!(
        has("#1 rflex.TrackSpeed: refused: after rflex.Init"),
        "{lines:#?}"
    );
    assert!(has("#2 rflex.Init: accepted"), "{lines:#?}");
    assert!(has("#2 rflex.Init: done: ether"), "{lines:#?}");
    assert!(has("#3 rflex.TrackSpeed: started"), "{lines:#?}");
    assert!(
        has("antenna.Communicate.start held: mast_still (line "),
        "{lines:#?}"
    );
    assert!(
        has("fault: codel ndd.GoTo.move returned `pause::nowhere`, which it does not yield"),
        "{lines:#?}"
    );
    assert!(
        names.contains(&"antenna.Communicate".to_string()),
        "{names:?}"
    );
}

/// A reply tells a client's interrupt (with the service that interrupted), the model's
/// own abort rule, and a fault apart.
#[test]
fn interrupted_aborted_and_faulted_are_told_apart() {
    let outcomes = |e: &mut Engine| -> Vec<(String, Outcome)> {
        e.events()
            .filter_map(|ev| match ev {
                Event::Reply {
                    service,
                    reply: Reply::Done { outcome, .. },
                    ..
                } => Some((service.to_string(), outcome)),
                _ => None,
            })
            .collect()
    };
    // ndd.GoTo without the laser: the rover's `abort_blind_navigation` aborts it
    let mut e = Engine::builder(load("rover.ron"))
        .default_codels(DefaultCodels::FirstYield)
        .build()
        .expect("builds");
    e.request("ndd", "GoTo", ()).expect("queued");
    e.run_until(Until::Ticks(3)).expect("runs");
    let got = outcomes(&mut e);
    assert!(
        got.contains(&("ndd.GoTo".to_string(), Outcome::Aborted)),
        "{got:?}"
    );
    // rflex.Stop interrupts TrackSpeed: the client's request, named
    e.request("rflex", "Init", ()).expect("queued");
    e.request("rflex", "TrackSpeed", ()).expect("queued");
    e.run_until(Until::Ticks(3)).expect("runs");
    e.request("rflex", "Stop", ()).expect("queued");
    e.run_until(Until::Ticks(3)).expect("runs");
    let got = outcomes(&mut e);
    let by = got.iter().find_map(|(s, o)| match o {
        Outcome::Interrupted { by } if s == "rflex.TrackSpeed" => Some(by.clone()),
        _ => None,
    });
    assert_eq!(
        by.flatten().map(|s| s.to_string()).as_deref(),
        Some("rflex.Stop"),
        "{got:?}"
    );
    // a codel that panics: a fault, naming the codel
    let mut e = Engine::builder(load_text(IDS_MODEL))
        .default_codels(DefaultCodels::FirstYield)
        .codel(("m", "S", "main"), |_| panic!("injected"))
        .build()
        .expect("builds");
    silence_injected_panics();
    e.request("m", "Init", ()).expect("queued");
    e.request("m", "S", ()).expect("queued");
    e.run_until(Until::Ticks(6)).expect("runs");
    let got = outcomes(&mut e);
    let fault = got.iter().find_map(|(_, o)| match o {
        Outcome::Fault(f) => Some(f.clone()),
        _ => None,
    });
    let fault = fault.expect("a fault");
    assert!(matches!(fault.kind, FaultKind::Panic(_)), "{fault:?}");
    assert_eq!(fault.to_string(), "codel m.S.main panicked: injected");
}

/// A reply carries the service's output, on the engine's thread and on a task's; the
/// activity's start is reported between its acceptance and its end.
#[test]
fn replies_carry_outputs_and_the_start_is_reported() {
    for threads in [false, true] {
        let mut e = Engine::builder(load_text(IDS_MODEL))
            .codel(("m", "S", "start"), |ctx| {
                ctx.set_output(String::from("half way"));
                Next::Yield("pause::main")
            })
            .codel(("m", "S", "main"), |ctx| {
                let speed = ctx.get("speed").unwrap_or(0);
                ctx.set_output(speed * 10);
                Next::ETHER
            })
            .threads(threads)
            .build()
            .expect("builds");
        e.request("m", "Init", ()).expect("queued");
        let t = e.request("m", "S", ()).expect("queued");
        e.run_until(Until::Ticks(6)).expect("runs");
        let replies: Vec<Reply> = e
            .events()
            .filter_map(|ev| match ev {
                Event::Reply { ticket, reply, .. } if ticket == t => Some(reply),
                _ => None,
            })
            .collect();
        assert!(
            matches!(
                replies.as_slice(),
                [
                    Reply::Accepted,
                    Reply::Started,
                    Reply::Done {
                        outcome: Outcome::Ether,
                        ..
                    }
                ]
            ),
            "{replies:?}"
        );
        let Reply::Done {
            output: Some(output),
            ..
        } = &replies[2]
        else {
            panic!("no output: {replies:?}")
        };
        assert_eq!(output.get::<i64>(), Some(&10), "threads: {threads}");
        assert_eq!(output.get::<String>(), None);
        assert_eq!(replies[2].to_string(), "done: ether, with an output");
    }
}

/// One dependency suffices: the model is loaded and its types are named through
/// bip-engine, and a load error's `Debug` (what `main` prints) is its summary.
#[test]
fn bip_engine_alone_loads_a_model_and_names_its_types() {
    let path = format!("{}/../robots/rover.ron", env!("CARGO_MANIFEST_DIR"));
    let system: bip_engine::System = bip_engine::load_file(&path).expect("loads");
    let trace: bip_engine::Trace = Engine::builder(system.clone())
        .default_codels(DefaultCodels::FirstYield)
        .record(100)
        .build()
        .expect("builds")
        .record();
    assert!(trace.steps.is_empty());
    let _: &[bip_engine::bip_model::Property] = &system.properties;
    let err = bip_engine::load_str("bad.ron", "System(name: 3)").expect_err("bad");
    let debug = format!("{err:?}");
    assert!(debug.starts_with("bad.ron:1:"), "{debug}");
}

/// The engine's errors print their message as their `Debug` too, so that `?` out of
/// `main` says it in the model's terms rather than as a struct.
#[test]
fn the_engines_errors_debug_as_their_message() {
    let Err(build) = Engine::builder(load("rover.ron")).build() else {
        panic!("built with its codels unbound")
    };
    assert_eq!(format!("{build:?}"), build.to_string());
    assert!(build.to_string().starts_with("codel ("), "{build}");
    let mut e = Engine::builder(load("rover.ron"))
        .default_codels(DefaultCodels::FirstYield)
        .build()
        .expect("builds");
    let request = e.request("rflex", "Warp", ()).expect_err("no such service");
    assert_eq!(
        format!("{request:?}"),
        "the model has no service rflex.Warp"
    );
}

/// rover.ron declares `rflex.TrackSpeed`'s arguments a `Float`: an `f32` is refused when
/// it is sent (it used to reach the codel as `None`, and the rover drove at speed 0), as
/// are arguments to a function, and an `Int` outside its range.
#[test]
fn request_arguments_are_checked_against_the_declared_type() {
    let mut e = Engine::builder(load("rover.ron"))
        .default_codels(DefaultCodels::FirstYield)
        .build()
        .expect("builds");
    let err = e
        .request("rflex", "TrackSpeed", 0.5f32)
        .expect_err("an f32 for a Float");
    assert_eq!(
        err.to_string(),
        "rflex.TrackSpeed takes arguments of type Float (a Rust `f64`), not a `f32`"
    );
    e.request("rflex", "TrackSpeed", 0.5f64).expect("an f64");
    e.request("rflex", "TrackSpeed", ()).expect("no arguments");
    let err = e.request("rflex", "Init", 1.0).expect_err("a function");
    assert!(
        matches!(&err, RequestError::NoArguments { service, given: "f64" } if service == "rflex.Init"),
        "{err}"
    );
    let err = e
        .request("antenna", "Communicate", 20i64)
        .expect_err("out of Int(1, 10)");
    assert_eq!(
        err.to_string(),
        "antenna.Communicate takes arguments of type Int(1, 10); 20 is outside it"
    );
    e.request("antenna", "Communicate", 3i64).expect("in range");
    // from another thread too
    let h = e.handle();
    let err = h
        .request("ndd", "GoTo", "far away")
        .err()
        .expect("a &str for a Float");
    assert!(
        matches!(err, RequestError::WrongArguments { given: "&str", .. }),
        "{err}"
    );
}

/// The rover's `odo` is a record `Odometry`: a codel that writes it with another type, or
/// reads it as another type, or gives GoTo (a `Float` output) an `f32`, is faulty, and
/// the fault names the port or service and both types.
#[test]
fn port_data_and_outputs_of_another_type_are_faults() {
    #[derive(Clone, Default)]
    struct Odometry {
        x: f64,
    }
    // the faults of a run with these requests, sent in phases six ticks apart
    let fault_of = |b: EngineBuilder, phases: &[&[(&str, &str)]]| -> Vec<String> {
        let mut e = b
            .default_codels(DefaultCodels::FirstYield)
            .build()
            .expect("builds");
        for requests in phases {
            for (m, s) in *requests {
                e.request(m, s, ()).expect("queued");
            }
            e.run_until(Until::Ticks(6)).expect("runs");
        }
        e.events()
            .filter_map(|ev| match ev {
                Event::Fault(f) => Some(f.to_string()),
                _ => None,
            })
            .collect()
    };
    let drive: &[&[(&str, &str)]] = &[&[("rflex", "Init"), ("rflex", "TrackSpeed")]];
    let wrong_write =
        Engine::builder(load("rover.ron")).codel(("rflex", "TrackSpeed", "track"), |ctx| {
            ctx.write_port("odo", 1.5f32);
            Next::Yield("pause::track")
        });
    let got = fault_of(wrong_write, drive);
    assert!(
        got.first().is_some_and(|f| f
            == "codel rflex.TrackSpeed.track wrote port `rflex.odo` with a `f32`, where the model has Record Odometry (a Rust `Odometry`)"),
        "{got:?}"
    );
    let good_write =
        Engine::builder(load("rover.ron")).codel(("rflex", "TrackSpeed", "track"), |ctx| {
            if let Some(odo) = ctx.port_mut::<Odometry>("odo") {
                odo.x += 1.0;
            }
            Next::Yield("pause::track")
        });
    assert_eq!(fault_of(good_write, drive), Vec::<String>::new());
    // pom reads the odometry as an f64
    let wrong_read = Engine::builder(load("rover.ron"))
        .codel(("rflex", "TrackSpeed", "track"), |ctx| {
            ctx.write_port("odo", Odometry { x: 1.0 });
            Next::Yield("pause::track")
        })
        .codel(("pom", "Track", "fuse"), |ctx| {
            let x = ctx.port::<f64>("rflex", "odo").copied().unwrap_or(0.0);
            ctx.write_port("pose", x);
            Next::Yield("pause::fuse")
        });
    let got = fault_of(
        wrong_read,
        &[&[("rflex", "Init"), ("rflex", "TrackSpeed"), ("pom", "Track")]],
    );
    assert!(
        got.first().is_some_and(|f| f
            == "codel pom.Track.fuse read port `rflex.odo` with a `f64`, where the model has Record Odometry (a Rust `Odometry`)"),
        "{got:?}"
    );
    let misspelt = Engine::builder(load("rover.ron")).codel(("pom", "Track", "fuse"), |ctx| {
        let _ = ctx.port::<Odometry>("rflex", "odometry");
        Next::Yield("pause::fuse")
    });
    let got = fault_of(misspelt, &[&[("pom", "Track")]]);
    assert!(
        got.first().is_some_and(
            |f| f.ends_with("read port `rflex.odometry`, which the model does not have")
        ),
        "{got:?}"
    );
    // an output of another type
    let wrong_output = Engine::builder(load("rover.ron")).codel(("ndd", "GoTo", "start"), |ctx| {
        ctx.set_output(1.0f32);
        Next::Yield("pause::move")
    });
    let got = fault_of(
        wrong_output,
        &[&[("sick", "Scan"), ("pom", "Track")], &[("ndd", "GoTo")]],
    );
    assert!(
        got.iter().any(|f| f
            == "codel ndd.GoTo.start gave ndd.GoTo an output with a `f32`, where the model has Float (a Rust `f64`)"),
        "{got:?}"
    );
}

#[path = "../../examples/minimal.rs"]
mod minimal;

/// The minimal example, a newcomer's first copy, runs and its run is a path of the model.
#[test]
fn the_minimal_example_runs() {
    minimal::main().unwrap_or_else(|e| panic!("the minimal example fails: {e}"));
}

/// One object serves all the codels of a module, called with each codel's index in the
/// GenoM map's order, its state kept between them, on the engine's thread and on a
/// task's; a panic is a fault like a closure's, and the object goes on serving.
#[test]
fn a_module_object_serves_all_its_codels_by_index() {
    for threads in [false, true] {
        let calls = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        let seen = calls.clone();
        let mut runs = 0;
        let mut e = Engine::builder(load_text(IDS_MODEL))
            .module("m", IDS_MODULE, move |codel, ctx| {
                seen.lock()
                    .expect("lock")
                    .push((codel, ctx.state().to_string()));
                runs += 1;
                match codel {
                    0 => Next::Yield("pause::main"),
                    _ if runs == 2 => panic!("the second run panics"),
                    _ => Next::ETHER,
                }
            })
            .threads(threads)
            .build()
            .expect("builds");
        e.request("m", "Init", ()).expect("queued");
        let first = e.request("m", "S", ()).expect("queued");
        e.run_until(Until::Ticks(6)).expect("runs");
        let second = e.request("m", "S", ()).expect("queued");
        e.run_until(Until::Ticks(6)).expect("runs");
        let ends: Vec<(bip_engine::Ticket, Outcome)> = e
            .events()
            .filter_map(|ev| match ev {
                Event::Reply {
                    ticket,
                    reply: Reply::Done { outcome, .. },
                    ..
                } => Some((ticket, outcome)),
                _ => None,
            })
            .collect();
        assert!(
            matches!(ends.as_slice(), [_, (a, Outcome::Fault(_)), (b, Outcome::Ether)] if *a == first && *b == second),
            "threads: {threads}: {ends:?}"
        );
        let calls = calls.lock().expect("lock").clone();
        assert_eq!(
            calls,
            [
                (0, "start".to_string()),
                (1, "main".to_string()),
                (0, "start".to_string()),
                (1, "main".to_string())
            ],
            "threads: {threads}"
        );
    }
}

#[test]
fn a_module_object_is_bound_to_a_module_with_codels_and_only_once() {
    let err = Engine::builder(load_text(IDS_MODEL))
        .module("n", IDS_MODULE, |_, _| Next::ETHER)
        .build()
        .err();
    assert!(
        matches!(&err, Some(bip_engine::BuildError::UnknownModule(m)) if m == "n"),
        "{err:?}"
    );
    let err = Engine::builder(load_text(IDS_MODEL))
        .codel(("m", "S", "main"), |_| Next::ETHER)
        .module("m", IDS_MODULE, |_, _| Next::ETHER)
        .build()
        .err();
    assert!(
        matches!(err, Some(bip_engine::BuildError::BoundTwice(..))),
        "{err:?}"
    );
}

/// Module `m` of IDS_MODEL as a module object numbers its codels and outcomes.
const IDS_MODULE: &[CodelSignature] = &[
    CodelSignature {
        service: "S",
        codel: "start",
        yields: &["pause::main"],
        throws: &[],
    },
    CodelSignature {
        service: "S",
        codel: "main",
        yields: &["pause::main", "ether"],
        throws: &["e_bad"],
    },
];

/// A module object made for another version of the model (bindings not regenerated) is
/// refused when the engine is built, with the first difference, rather than having its
/// codels and outcomes called by the wrong numbers.
#[test]
fn a_module_object_made_for_another_model_is_refused() {
    let build = |signature: Vec<CodelSignature>| {
        Engine::builder(load_text(IDS_MODEL))
            .module("m", signature.leak(), |_, _| Next::ETHER)
            .build()
            .err()
            .map(|e| e.to_string())
    };
    assert_eq!(build(IDS_MODULE.to_vec()), None);
    let reordered = vec![
        CodelSignature {
            yields: &["ether", "pause::main"],
            ..IDS_MODULE[1]
        },
        IDS_MODULE[0],
    ];
    let stale = [
        (IDS_MODULE[..1].to_vec(), "they have 1 codels, the model 2"),
        (
            reordered,
            "their codel 0 is `S.main`, the model's is `S.start`",
        ),
        (
            vec![
                IDS_MODULE[0],
                CodelSignature {
                    yields: &["ether", "pause::main"],
                    ..IDS_MODULE[1]
                },
            ],
            "codel `S.main` yields [\"ether\", \"pause::main\"] in them, [\"pause::main\", \"ether\"] in the model",
        ),
        (
            vec![
                IDS_MODULE[0],
                CodelSignature {
                    throws: &[],
                    ..IDS_MODULE[1]
                },
            ],
            "codel `S.main` throws [] in them, [\"e_bad\"] in the model",
        ),
        (
            vec![IDS_MODULE[0], IDS_MODULE[1], IDS_MODULE[1]],
            "they have 3 codels, the model 2",
        ),
    ];
    for (signature, difference) in stale {
        assert_eq!(
            build(signature),
            Some(format!(
                "module `m` was bound for another model: {difference}; regenerate its bindings from this model"
            ))
        );
    }
}

/// Module `m` of IDS_MODEL's data types, as typed code assumes them.
const IDS_TYPES: ModuleTypes = ModuleTypes {
    ids: &[
        Typed {
            name: "speed",
            ty: "Int(0, 3)",
        },
        Typed {
            name: "on",
            ty: "Bool",
        },
    ],
    ports: &[Typed {
        name: "pose",
        ty: "",
    }],
    services: &[
        ServiceTypes {
            name: "Init",
            args: "",
            output: "",
        },
        ServiceTypes {
            name: "S",
            args: "",
            output: "",
        },
        ServiceTypes {
            name: "Stop",
            args: "",
            output: "",
        },
    ],
};

/// Typed code made for other data types than the model's (bindings generated before a
/// type changed) is refused when the engine is built, with the first difference, rather
/// than faulting at run time when a codel reads or writes.
#[test]
fn types_assumed_for_another_model_are_refused() {
    let build = |module: &str, types: ModuleTypes| {
        Engine::builder(load_text(IDS_MODEL))
            .default_codels(DefaultCodels::FirstYield)
            .typed_as(module, Box::leak(Box::new(types)))
            .build()
            .err()
            .map(|e| e.to_string())
    };
    assert_eq!(build("m", IDS_TYPES), None);
    let wider = [Typed {
        name: "speed",
        ty: "Int(0, 4)",
    }];
    let mut args = IDS_TYPES.services.to_vec();
    args[1].args = "Float";
    let stale = [
        (
            ModuleTypes {
                ids: Box::leak(Box::new([wider[0], IDS_TYPES.ids[1]])),
                ..IDS_TYPES
            },
            "ids field `speed` is Int(0, 4) in them, Int(0, 3) in the model",
        ),
        (
            ModuleTypes {
                ports: &[],
                ..IDS_TYPES
            },
            "their ports are [], the model's [pose]",
        ),
        (
            ModuleTypes {
                services: args.leak(),
                ..IDS_TYPES
            },
            "service `S` is Float in them, untyped in the model (arguments)",
        ),
    ];
    for (types, difference) in stale {
        assert_eq!(
            build("m", types),
            Some(format!(
                "module `m` was bound for another model: {difference}; regenerate its bindings from this model"
            ))
        );
    }
    assert_eq!(
        build("n", IDS_TYPES),
        Some("the model has no module `n`".to_string())
    );
}

/// A model whose initial state has a range error (a guard divides by zero) is built: the
/// engine is stopped from the start, says by what, and its first step says so, as a step
/// into such a state stops it (the verifier reports the same error, `RangeErrors`).
#[test]
fn a_range_error_in_the_initial_state_stops_the_engine_before_its_first_step() {
    let system = bip_engine::load_str(
        "initial.ron",
        r#"System(
            name: "initial",
            atoms: { "A": Atom(locations: ["l0"], initial: "l0", ports: ["p"],
                vars: [(name: "x", ty: Int(0, 3), init: 0)],
                transitions: [(from: "l0", port: "p", to: "l0", guard: "1 / x > 0")]) },
            components: [(name: "a", atom: "A")],
            connectors: [(name: "p", ports: ["a.p"])],
        )"#,
    )
    .expect("loads");
    let mut e = Engine::builder(system).build().expect("builds, stopped");
    let stopped = e.inspect().stopped().expect("stopped").to_string();
    assert!(stopped.contains("division by zero"), "{stopped}");
    let err = e.step().expect_err("stopped");
    assert!(
        err.to_string().contains("stopped after a range error"),
        "{err}"
    );
    assert_eq!(e.inspect().stats().steps, 0);
}
