//! Verdicts, state counts and counterexample lengths known independently of bip.
//!
//! Dining philosophers, left fork then right fork (robots/philosophers.ron). A state is the
//! cyclic word of the philosophers' locations (thinking T, hungry H holding the left fork,
//! eating E holding both); the forks follow from it. Fork `i+1` is wanted by philosopher
//! `i` only when eating and by philosopher `i+1` when hungry or eating, so a word is a state
//! iff no `E` is followed (cyclically) by `H` or `E`; every such word is reachable (release
//! the eaters, then take forks in order). The number of cyclic words avoiding those pairs is
//! trace(M^N) with the transfer matrix M = [[1,1,1],[1,1,1],[1,0,0]] (rows and columns
//! T, H, E; M[a][b] = 0 iff a = E and b ≠ T): 14, 34, 82, 198 for N = 3..6. The only
//! deadlock is all hungry, each holding the left fork, which takes N `left` steps and no
//! fewer. An independent brute-force breadth-first search (a 30-line Python script over
//! the words) and SPIN on `bip export --promela` (`spin -o2 -a`, `pan -c0`) give the same
//! counts; SPIN finds the deadlock too.
//!
//! The asymmetric variant (robots/philosophers-asymmetric.ron, the last philosopher takes
//! the right fork first) is deadlock-free; the same brute-force search and SPIN give
//! 12, 29, 70, 169 states for N = 3..6.

use std::time::Duration;

use bip_lang::load_str;
use bip_model::{System, Verdict as TraceVerdict};
use bip_verifier::{
    verify, CheckKind, Method, Options, PropertyVerdict, Report, Stop, RANGE_ERRORS,
};

fn with_n(file: &str, n: u32) -> System {
    let text = std::fs::read_to_string(format!("{}/../robots/{file}", env!("CARGO_MANIFEST_DIR")))
        .unwrap();
    let text = text.replace("\"N\": 5", &format!("\"N\": {n}"));
    load_str(file, &text).unwrap()
}

fn run(system: &System, options: &Options) -> Report {
    verify(system, Method::Explicit, options, &|_| {}).unwrap()
}

fn opts(jobs: usize) -> Options {
    Options {
        jobs,
        ..Options::default()
    }
}

/// trace(M^n) for the philosophers' transfer matrix.
fn transfer_count(n: u32) -> u64 {
    let m = [[1u64, 1, 1], [1, 1, 1], [1, 0, 0]];
    let mut p = [[1u64, 0, 0], [0, 1, 0], [0, 0, 1]];
    for _ in 0..n {
        let mut q = [[0u64; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                q[i][j] = (0..3).map(|k| p[i][k] * m[k][j]).sum();
            }
        }
        p = q;
    }
    p[0][0] + p[1][1] + p[2][2]
}

#[test]
fn philosophers_deadlock_with_the_shortest_counterexample() {
    assert_eq!(
        (3..=6).map(transfer_count).collect::<Vec<_>>(),
        vec![14, 34, 82, 198]
    );
    for n in 3..=6 {
        let sys = with_n("philosophers.ron", n);
        for jobs in [1, 2] {
            let r = run(&sys, &opts(jobs));
            assert_eq!(r.stats.states, transfer_count(n), "N = {n}");
            assert_eq!(r.stats.depth, n, "N = {n}");
            let p = r.property("DeadlockFree").unwrap();
            let PropertyVerdict::Fails { trace: Some(t), .. } = &p.verdict else {
                panic!("N = {n}: {:?}", p.verdict)
            };
            assert_eq!(t.verdict, TraceVerdict::Deadlock);
            assert_eq!(t.steps.len(), n as usize, "N = {n}");
            assert!(t.steps.iter().all(|s| s.step.starts_with("left[")));
            // the trace is a real run of the model that ends in a deadlock
            let path = t.replay(&sys).unwrap();
            let last = &path.last().unwrap().1;
            assert!(sys.successors(last).unwrap().is_empty());
            assert!(r
                .property("neighbours_never_both_eat")
                .unwrap()
                .verdict
                .holds());
            let PropertyVerdict::Holds { witness: Some(w) } =
                &r.property("someone_eats").unwrap().verdict
            else {
                panic!("no witness")
            };
            assert_eq!(w.steps.len(), 2); // take left, take right
            assert!(r.property(RANGE_ERRORS).unwrap().verdict.holds());
        }
    }
}

#[test]
fn asymmetric_philosophers_are_deadlock_free() {
    for (n, states) in [(3, 12), (4, 29), (5, 70), (6, 169)] {
        let sys = with_n("philosophers-asymmetric.ron", n);
        let r = run(&sys, &opts(2));
        assert_eq!(r.stats.states, states, "N = {n}");
        assert!(
            r.properties.iter().all(|p| p.verdict.holds()),
            "{:?}",
            r.properties
        );
        assert!(r.stopped.is_none());
    }
}

/// Two counters; `a` can reach 5 in 5 steps, `b` jumps by 2 and reaches 4 in 2 steps.
const COUNTERS: &str = r#"System(
    name: "counters",
    atoms: {
        "A": Atom(locations: ["s"], initial: "s",
                  vars: [(name: "x", ty: Int(0, 9))],
                  transitions: [(from: "s", to: "s", guard: "x < 9", action: "x = x + 1")]),
        "B": Atom(locations: ["s"], initial: "s",
                  vars: [(name: "y", ty: Int(0, 5))],
                  transitions: [(from: "s", to: "s", action: "y = y + 2")]),
    },
    components: [(name: "a", atom: "A"), (name: "b", atom: "B")],
    properties: [
        Invariant(name: "sum_small", expr: "a.x + b.y < 4"),
        Reachable(name: "x_five", expr: "a.x == 5"),
        Reachable(name: "never", expr: "a.x == 9 && b.y == 5"),
    ],
)"#;

#[test]
fn invariant_violation_range_error_and_witness_have_shortest_traces() {
    let sys = load_str("counters.ron", COUNTERS).unwrap();
    for jobs in [1, 2, 4] {
        let r = run(&sys, &opts(jobs));
        // a.x + b.y >= 4 first with b.y = 4 (2 steps)
        let PropertyVerdict::Fails { trace: Some(t), .. } =
            &r.property("sum_small").unwrap().verdict
        else {
            panic!()
        };
        assert_eq!(t.verdict, TraceVerdict::Violation("sum_small".into()));
        assert_eq!(t.steps.len(), 2);
        t.replay(&sys).unwrap();
        // b.y = 4 + 2 is out of 0..=5: the state with b.y = 4 is 2 steps away
        let p = r.property(RANGE_ERRORS).unwrap();
        assert_eq!(p.kind, CheckKind::RangeErrors);
        let PropertyVerdict::Fails {
            trace: Some(t),
            reason,
        } = &p.verdict
        else {
            panic!()
        };
        assert_eq!(t.steps.len(), 2);
        assert!(
            reason.contains("b.y = 6 is outside its range Int(0, 5)"),
            "{reason}"
        );
        assert!(matches!(&t.verdict, TraceVerdict::RangeError(m) if m.contains("b.y")));
        // witness: five steps of a
        let PropertyVerdict::Holds { witness: Some(w) } = &r.property("x_five").unwrap().verdict
        else {
            panic!()
        };
        assert_eq!(w.steps.len(), 5);
        assert_eq!(w.verdict, TraceVerdict::Witness("x_five".into()));
        // y is always even: never 5
        let PropertyVerdict::Fails { trace: None, .. } = &r.property("never").unwrap().verdict
        else {
            panic!()
        };
        // x: 0..=9 (10 values), y: 0, 2, 4 (6 overflows)
        assert_eq!(r.stats.states, 30);
        assert_eq!(r.property("DeadlockFree"), None);
    }
}

#[test]
fn stop_at_first_leaves_the_rest_undecided() {
    let sys = load_str("counters.ron", COUNTERS).unwrap();
    let r = run(
        &sys,
        &Options {
            stop_at_first: true,
            jobs: 1,
            ..Options::default()
        },
    );
    assert_eq!(r.stopped, Some(Stop::FirstFailure));
    assert!(r.property("sum_small").unwrap().verdict.fails());
    assert!(matches!(
        r.property("never").unwrap().verdict,
        PropertyVerdict::Inconclusive { .. }
    ));
}

#[test]
fn no_property_means_deadlock_freedom_and_terminal_excuses() {
    let text = r#"System(
        name: "line",
        atoms: { "L": Atom(locations: ["a", "b", "c"], initial: "a",
                           transitions: [(from: "a", to: "b"), (from: "b", to: "c")]) },
        components: [(name: "l", atom: "L")],
    )"#;
    let sys = load_str("line.ron", text).unwrap();
    let r = run(&sys, &opts(1));
    let PropertyVerdict::Fails { trace: Some(t), .. } =
        &r.property("DeadlockFree").unwrap().verdict
    else {
        panic!()
    };
    assert_eq!(t.steps.len(), 2);
    let excused = text.replace(
        "components:",
        r#"properties: [DeadlockFree(terminal: "l@c")], components:"#,
    );
    let r = run(&load_str("line.ron", &excused).unwrap(), &opts(1));
    assert!(r.property("DeadlockFree").unwrap().verdict.holds());
}

/// A clock that ticks forever and a worker that is done after one step: with the tick as
/// `Time`, the worker's end is a deadlock (nothing but time can happen), found through the
/// time steps.
const CLOCKED: &str = r#"System(
    name: "clocked",
    atoms: {
        "Clock": Atom(locations: ["run"], initial: "run", ports: ["tick"],
                      vars: [(name: "t", ty: Int(0, 3))],
                      transitions: [(from: "run", port: "tick", to: "run", action: "t = (t + 1) % 4")]),
        "Worker": Atom(locations: ["idle", "busy", "done"], initial: "idle", ports: ["go"],
                       transitions: [(from: "idle", port: "go", to: "busy"),
                                     (from: "busy", to: "done")]),
    },
    components: [(name: "clock", atom: "Clock"), (name: "w", atom: "Worker")],
    connectors: [
        (name: "tick", ports: ["clock.tick"], role: Time),
        (name: "go", ports: ["w.go"], guard: "clock.t == 3"),
    ],
    properties: [DeadlockFree],
)"#;

#[test]
fn deadlocks_are_found_through_time_steps() {
    let sys = load_str("clocked.ron", CLOCKED).unwrap();
    let r = run(&sys, &opts(2));
    let PropertyVerdict::Fails { trace: Some(t), .. } =
        &r.property("DeadlockFree").unwrap().verdict
    else {
        panic!("{:?}", r.properties)
    };
    // three ticks, go, the internal step
    assert_eq!(t.steps.len(), 5);
    assert_eq!(t.steps.last().unwrap().step, "w.internal");
    // the idle worker waiting for t == 3 is not a deadlock: excusing `done` makes it hold
    let fixed = CLOCKED.replace("[DeadlockFree]", r#"[DeadlockFree(terminal: "w@done")]"#);
    let r = run(&load_str("clocked.ron", &fixed).unwrap(), &opts(2));
    assert!(r.property("DeadlockFree").unwrap().verdict.holds());
    // a liveness search bounded below the 4 states of the clock cannot decide: inconclusive,
    // never "holds"
    let r = run(
        &load_str("clocked.ron", &fixed).unwrap(),
        &Options {
            liveness_bound: 2,
            ..opts(1)
        },
    );
    let v = &r.property("DeadlockFree").unwrap().verdict;
    assert!(
        matches!(v, PropertyVerdict::Inconclusive { reason } if reason.contains("liveness")),
        "{v:?}"
    );
}

/// Eight independent counters of ten values: 10^8 states.
fn huge() -> System {
    let text = r#"System(
        name: "huge",
        constants: { "K": 8 },
        atoms: { "C": Atom(locations: ["s"], initial: "s", vars: [(name: "v", ty: Int(0, 9))],
                           transitions: [(from: "s", to: "s", action: "v = (v + 1) % 10")]) },
        components: [(name: "c", atom: "C", count: "K")],
        properties: [Invariant(name: "fine", expr: "c[0].v >= 0")],
    )"#;
    load_str("huge.ron", text).unwrap()
}

#[test]
fn limits_end_the_run_inconclusive() {
    let sys = huge();
    let r = run(
        &sys,
        &Options {
            max_states: Some(100_000),
            ..opts(2)
        },
    );
    assert_eq!(r.stopped, Some(Stop::MaxStates { limit: 100_000 }));
    // the limit is checked inside a batch too: it ends near its bound
    assert!(
        r.stats.states >= 100_000 && r.stats.states <= 110_000,
        "{}",
        r.stats.states
    );
    assert!(r.properties.iter().all(
        |p| matches!(&p.verdict, PropertyVerdict::Inconclusive { reason } if reason.contains("state limit"))
    ));
    assert_eq!(r.outcome(), bip_verifier::VerifyOutcome::Inconclusive);

    let r = run(
        &sys,
        &Options {
            timeout: Some(Duration::from_millis(300)),
            ..opts(2)
        },
    );
    assert!(matches!(r.stopped, Some(Stop::Timeout { .. })));
    assert!(r.stats.seconds < 20.0);

    // a limit far below what the exploration needs: it stops before reaching it
    let limit = bip_verifier::resident_bytes().unwrap_or(0) + (48 << 20);
    let r = run(
        &sys,
        &Options {
            max_memory: Some(limit),
            ..opts(2)
        },
    );
    assert_eq!(r.stopped, Some(Stop::MaxMemory { limit }));
    assert!(r.stats.store_bytes < limit);
}

/// A raised interrupt flag (Ctrl-C) ends every method at once: every property undecided
/// with the reason, and the run's stop says so.
#[test]
fn an_interrupt_ends_every_method_inconclusive() {
    let sys = huge();
    for method in [Method::Explicit, Method::Auto, Method::Symbolic] {
        let flag = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(true));
        let r = verify(
            &sys,
            method,
            &Options {
                interrupt: Some(flag),
                ..opts(2)
            },
            &|_| {},
        )
        .unwrap();
        assert_eq!(r.stopped, Some(Stop::Interrupted), "{method}");
        assert!(
            r.properties.iter().all(|p| matches!(
                &p.verdict,
                PropertyVerdict::Inconclusive { reason } if reason.contains("interrupted")
            )),
            "{method}: {:?}",
            r.properties
        );
    }
}
