//! The symbolic method on models whose answers are known: the examples (the explicit
//! method's verdicts, themselves checked against SPIN and brute force in
//! `known_answers.rs`), the deadlocking philosophers (a confirmed deadlock with a trace
//! that replays into a deadlock), and a deadlock-free model whose invariants are too weak
//! to prove it (a "possible deadlock", never "holds").

use bip_lang::load_str;
use bip_model::{Liveness, LivenessChecker, Steps, System, Verdict as TraceVerdict};
use bip_verifier::{verify, CheckKind, Method, Options, PropertyVerdict, Report, SymbolicOptions};

fn example(file: &str) -> (String, System) {
    let path = format!("{}/../robots/{file}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    let sys = load_str(file, &text).unwrap();
    (text, sys)
}

fn with_n(file: &str, n: u32) -> System {
    let (text, _) = example(file);
    let text = text.replace("\"N\": 5", &format!("\"N\": {n}"));
    load_str(file, &text).unwrap()
}

fn explicit(sys: &System) -> Report {
    verify(sys, Method::Explicit, &Options::default(), &|_| {}).unwrap()
}

fn symbolic(sys: &System, options: &Options) -> Report {
    verify(sys, Method::Symbolic, options, &|_| {}).unwrap()
}

fn symbolic_options() -> Options {
    Options {
        jobs: 1,
        symbolic: SymbolicOptions {
            solver_timeout: None,
            rlimit: Some(200_000_000),
            // the confirmation's memory budget counts this process's resident memory,
            // which the suite's other tests share: bound it by states alone
            confirm_memory: u64::MAX,
            ..SymbolicOptions::default()
        },
        ..Options::default()
    }
}

/// Without the explicit confirmation of deadlock candidates.
fn unconfirmed_options() -> Options {
    let mut options = symbolic_options();
    options.symbolic.confirm_states = 0;
    options
}

fn kind(v: &PropertyVerdict) -> &'static str {
    match v {
        PropertyVerdict::Holds { .. } => "holds",
        PropertyVerdict::Fails { .. } => "fails",
        PropertyVerdict::Inconclusive { .. } => "inconclusive",
    }
}

/// Every property is decided symbolically, with the explicit method's verdict.
fn same_verdicts(file: &str) {
    let (_, sys) = example(file);
    let e = explicit(&sys);
    let s = symbolic(&sys, &symbolic_options());
    assert_eq!(e.properties.len(), s.properties.len());
    for (e, s) in e.properties.iter().zip(&s.properties) {
        assert_eq!(e.name, s.name);
        assert!(
            !matches!(e.verdict, PropertyVerdict::Inconclusive { .. }),
            "{file} {}: the explicit method must decide",
            e.name
        );
        assert_eq!(
            kind(&e.verdict),
            kind(&s.verdict),
            "{file} {}: explicit {:?}, symbolic {:?}",
            e.name,
            e.verdict,
            s.verdict
        );
        // every symbolic trace is a run of the model
        if let Some(t) = s.verdict.trace() {
            t.replay(&sys).unwrap();
        }
    }
    // a proof of deadlock freedom comes from the symbolic method itself, not a fallback
    let dl = s.property("DeadlockFree").unwrap();
    if dl.verdict.holds() {
        assert_eq!(dl.method, Method::Symbolic, "{file}: {:?}", dl.note);
    }
}

#[test]
fn examples_get_the_explicit_verdicts() {
    for file in [
        "philosophers.ron",
        "philosophers-asymmetric.ron",
        "philosophers-atomic.ron",
        "pipeline.ron",
        "bench/buffers.ron",
        "bench/token-ring.ron",
    ] {
        same_verdicts(file);
    }
}

/// The GenoM example with a deadlock (robots/rover-deadlock.ron): the deadlock is found and
/// confirmed, and every invariant is proved as the explicit method finds it.
#[test]
fn genom_rover_with_a_deadlock() {
    let (_, sys) = example("rover-deadlock.ron");
    let e = explicit(&sys);
    let s = symbolic(&sys, &symbolic_options());
    for (e, s) in e.properties.iter().zip(&s.properties) {
        if s.kind == CheckKind::Reachable {
            // witnesses deeper than the bound may stay open; never a contradiction
            assert!(!(s.verdict.fails() && e.verdict.holds()), "{}", s.name);
            continue;
        }
        assert_eq!(
            kind(&e.verdict),
            kind(&s.verdict),
            "{}: {:?}",
            s.name,
            s.verdict
        );
    }
    let dl = s.property("DeadlockFree").unwrap();
    let trace = dl.verdict.trace().unwrap();
    assert_eq!(trace.verdict, TraceVerdict::Deadlock);
    trace.replay(&sys).unwrap();
}

/// Left fork then right fork: the candidate "all hungry" survives every invariant (it is
/// reachable) and is confirmed with a trace ending in a deadlock, by the one definition.
#[test]
fn deadlocking_philosophers_give_a_confirmed_deadlock() {
    for n in [5, 40] {
        let sys = with_n("philosophers.ron", n);
        let s = symbolic(&sys, &symbolic_options());
        let dl = s.property("DeadlockFree").unwrap();
        // confirmed by the bounded explicit search, or by the search towards the candidate
        let PropertyVerdict::Fails {
            trace: Some(trace), ..
        } = &dl.verdict
        else {
            panic!("N = {n}: {:?}", dl.verdict)
        };
        assert_eq!(trace.verdict, TraceVerdict::Deadlock);
        let path = trace.replay(&sys).unwrap();
        let last = path.last().unwrap().1.clone();
        let mut steps = Steps::new();
        sys.enabled_steps(&last, &mut steps).unwrap();
        assert_eq!(
            sys.liveness(&last, &steps, &mut LivenessChecker::default())
                .unwrap(),
            Liveness::Deadlock
        );
        // all hungry: at least one `left` per philosopher
        assert!(trace.steps.len() >= n as usize);
        // the deadlock-free variant of the same size is proved
        let sys = with_n("philosophers-asymmetric.ron", n);
        let s = symbolic(&sys, &symbolic_options());
        assert!(s.property("DeadlockFree").unwrap().verdict.holds());
    }
}

/// Two counters that move together stay equal, so the state where the first is at 100 and
/// the second at 30 is unreachable; it would be a deadlock (neither `step` nor `finish`
/// is enabled). No component invariant (each counter alone takes every value) and no trap
/// or semiflow (the counters have too many values for data-refined places) excludes it,
/// and it has a predecessor satisfying them all. With confirmation off, the symbolic method
/// must say "possible deadlock" and not "holds"; the explicit method proves the model
/// deadlock-free, so the symbolic answer is incomplete, not wrong.
const WEAK: &str = r#"System(
    name: "weak",
    atoms: {
        "Counter": Atom(
            locations: ["run", "done"],
            initial: "run",
            vars: [(name: "x", ty: Int(0, 100))],
            ports: ["tick", "end", "restart"],
            transitions: [
                (from: "run", port: "tick", to: "run", guard: "x < 100", action: "x = x + 1"),
                (from: "run", port: "end", to: "done", guard: "x == 100"),
                (from: "done", port: "restart", to: "run", action: "x = 0"),
            ],
        ),
    },
    components: [(name: "a", atom: "Counter"), (name: "b", atom: "Counter")],
    connectors: [
        (name: "step", ports: ["a.tick", "b.tick"]),
        (name: "finish", ports: ["a.end", "b.end"]),
        (name: "again", ports: ["a.restart", "b.restart"]),
    ],
    properties: [DeadlockFree],
)"#;

#[test]
fn too_weak_invariants_give_a_possible_deadlock_not_holds() {
    let sys = load_str("weak.ron", WEAK).unwrap();
    let e = explicit(&sys);
    assert!(e.property("DeadlockFree").unwrap().verdict.holds());
    let s = symbolic(&sys, &unconfirmed_options());
    let dl = s.property("DeadlockFree").unwrap();
    let PropertyVerdict::Inconclusive { reason } = &dl.verdict else {
        panic!("{:?}", dl.verdict)
    };
    assert!(reason.contains("possible deadlock"), "{reason}");
    // with confirmation on, the bounded explicit search settles it (all 102 states)
    let s = symbolic(&sys, &symbolic_options());
    let dl = s.property("DeadlockFree").unwrap();
    assert!(dl.verdict.holds(), "{:?}", dl.verdict);
    assert_eq!(dl.method, Method::Explicit);
    assert!(dl
        .note
        .as_deref()
        .unwrap_or("")
        .contains("102 reachable states"));
}

/// With a smaller bound each counter has few enough local states to get one place per
/// local state, and a semiflow over those places says the counters are equal: the same
/// model is then proved deadlock-free symbolically.
#[test]
fn data_refined_places_prove_what_locations_alone_cannot() {
    let sys = load_str("weak.ron", &WEAK.replace("100", "20")).unwrap();
    let s = symbolic(&sys, &unconfirmed_options());
    let dl = s.property("DeadlockFree").unwrap();
    assert!(dl.verdict.holds(), "{:?}", dl.verdict);
    assert_eq!(dl.method, Method::Symbolic);
}

/// Long chains of one operator (compiled flat or balanced, not as deep trees) mean the same
/// to both methods, also where a left-to-right sum overflows on the way.
#[test]
fn long_chains_get_the_explicit_verdicts() {
    let n = 10;
    let terms = |f: &dyn Fn(usize) -> String, op: &str| {
        (0..n).map(f).collect::<Vec<_>>().join(&format!(" {op} "))
    };
    let sum = terms(&|k| format!("p[{k}].x"), "+");
    let properties = [
        ("sum_bounded", format!("{sum} <= {n}")),
        ("sum_small", format!("{sum} <= {}", n - 1)),
        ("all_small", terms(&|k| format!("p[{k}].x <= 1"), "&&")),
        ("some_zero", terms(&|k| format!("p[{k}].x == 0"), "||")),
        (
            "near_max",
            format!("9223372036854775806 + {sum} - {n} < 0 || true"),
        ),
    ];
    let props: Vec<String> = properties
        .iter()
        .map(|(name, e)| format!(r#"Invariant(name: "{name}", expr: "{e}")"#))
        .collect();
    let text = format!(
        r#"System(
    name: "chains",
    atoms: {{
        "P": Atom(locations: ["s"], initial: "s", ports: ["go"],
            vars: [(name: "x", ty: Int(0, 1), init: 0)],
            transitions: [(from: "s", port: "go", to: "s", guard: "x == 0", action: "x = 1")]),
    }},
    components: [(name: "p", atom: "P", count: {n})],
    connectors: [(name: "c", forall: "i in 0..{n}", ports: ["p[i].go"])],
    properties: [{}],
)"#,
        props.join(", ")
    );
    let sys = load_str("chains.ron", &text).unwrap_or_else(|e| panic!("{}", e.summary()));
    let e = explicit(&sys);
    let s = symbolic(&sys, &symbolic_options());
    let verdicts = |r: &Report| -> Vec<(String, &'static str)> {
        r.properties
            .iter()
            .map(|p| (p.name.clone(), kind(&p.verdict)))
            .collect()
    };
    let want = [
        ("sum_bounded", "holds"),
        ("sum_small", "fails"),
        ("all_small", "holds"),
        ("some_zero", "fails"),
        // `|| true` would hold: it fails only because the sum overflows on the way
        ("near_max", "fails"),
    ];
    for (name, verdict) in want {
        assert!(
            verdicts(&e).contains(&(name.to_string(), verdict)),
            "explicit {name}: {:?}",
            verdicts(&e)
        );
    }
    assert_eq!(verdicts(&e), verdicts(&s));
}
