//! `TimeProgress`: in a model with `Time` connectors, from every reachable state some run
//! fires a tick. Checked against a naive search for a tick from every state (response.rs's
//! `timelocked`) on random systems, and on the two situations a fuzzer found where
//! liveness properties held only because time could not pass: an urgent self-loop above
//! the tick, and a `Time` connector that never fires.

use bip_lang::load_str;
use std::collections::{HashSet, VecDeque};

use bip_model::{Role, State, System, Verdict};
use bip_verifier::{
    verify, CheckKind, Method, Options, PropertyResult, PropertyVerdict, Report, TIME_PROGRESS,
};
use proptest::prelude::*;

use super::response::{explore, timelocked, Naive};

fn run(sys: &System, method: Method, jobs: usize) -> Report {
    verify(
        sys,
        method,
        &Options {
            jobs,
            ..Options::default()
        },
        &|_| {},
    )
    .unwrap()
}

fn result<'r>(report: &'r Report, name: &str) -> &'r PropertyResult {
    report
        .property(name)
        .unwrap_or_else(|| panic!("no result for {name}"))
}

fn load(text: &str) -> System {
    load_str("model.ron", text).unwrap_or_else(|e| panic!("{}", e.summary()))
}

/// A worker that waits for an answer that never comes: `spin` loops in `wait`, and with
/// `urgent` it is above the tick, which then never fires once the worker waits.
fn spinning(urgent: bool) -> String {
    let priority = if urgent {
        r#"(low: "tick", high: "spin")"#
    } else {
        ""
    };
    format!(
        r#"System(
    name: "spinning",
    atoms: {{
        "A": Atom(locations: ["idle", "wait"], initial: "idle", ports: ["go", "spin", "done", "tick"],
            transitions: [
                (from: "idle", port: "go", to: "wait"),
                (from: "wait", port: "spin", to: "wait"),
                (from: "wait", port: "done", to: "idle"),
                (from: "idle", port: "tick", to: "idle"),
                (from: "wait", port: "tick", to: "wait"),
            ]),
        "Clock": Atom(locations: ["on"], initial: "on", ports: ["tick"],
            transitions: [(from: "on", port: "tick", to: "on")]),
    }},
    components: [(name: "a", atom: "A"), (name: "clock", atom: "Clock")],
    connectors: [
        (name: "go", ports: ["a.go"]),
        (name: "spin", ports: ["a.spin"]),
        (name: "done", ports: ["a.done"], guard: "false"),
        (name: "tick", ports: ["clock.tick", "a.tick"], role: Time),
    ],
    priorities: [{priority}],
    properties: [
        DeadlockFree,
        LeadsTo(name: "answered", from: "a@wait", to: "a@idle"),
        Response(name: "in_three", trigger: "a@wait", response: "a@idle", within: 3),
    ],
)"#
    )
}

/// The step names of a trace.
fn names(v: &PropertyVerdict) -> (Vec<String>, Option<usize>) {
    let t = v.trace().expect("a trace");
    (
        t.steps.iter().map(|s| s.step.clone()).collect(),
        t.loop_start,
    )
}

#[test]
fn an_urgent_self_loop_above_the_tick_is_a_timelock_and_fails_the_liveness_properties() {
    let sys = load(&spinning(true));
    let r = run(&sys, Method::Explicit, 1);
    assert_eq!(run(&sys, Method::Explicit, 3).properties, r.properties);
    // the worker always has a step: no deadlock
    assert!(result(&r, "DeadlockFree").verdict.holds());
    let tp = result(&r, TIME_PROGRESS);
    assert_eq!(tp.kind, CheckKind::TimeProgress);
    let PropertyVerdict::Fails { reason, trace } = &tp.verdict else {
        panic!("TimeProgress should fail: {tp:?}");
    };
    assert!(
        reason.contains("time stops after 1 step")
            && reason.contains("`tick` is below `spin` (priority `tick < spin`)"),
        "{reason}"
    );
    let trace = trace.as_ref().unwrap();
    assert_eq!(trace.verdict, Verdict::Violation(TIME_PROGRESS.into()));
    trace.replay(&sys).unwrap();
    assert_eq!(
        names(&tp.verdict),
        (vec!["go".into(), "spin".into()], Some(1))
    );
    // the response never comes: both liveness properties fail with the timelock's lasso
    for name in ["answered", "in_three"] {
        let p = result(&r, name);
        let PropertyVerdict::Fails { reason, .. } = &p.verdict else {
            panic!("{name} should fail: {p:?}");
        };
        assert!(reason.contains("time cannot pass on it"), "{reason}");
        assert_eq!(
            names(&p.verdict),
            (vec!["go".into(), "spin".into()], Some(1))
        );
    }
}

#[test]
fn a_self_loop_below_the_tick_lets_time_pass() {
    let sys = load(&spinning(false));
    let r = run(&sys, Method::Explicit, 1);
    assert!(result(&r, TIME_PROGRESS).verdict.holds());
    // time passes forever while the worker waits: the lasso is a tick
    let (steps, start) = names(&result(&r, "answered").verdict);
    assert_eq!((steps, start), (vec!["go".into(), "tick".into()], Some(1)));
    assert!(result(&r, "in_three").verdict.fails());
}

/// A worker whose answer may be skipped forever by `spin` (a cycle of two steps), with
/// `tick` as the last connector (none if empty).
fn skipping(tick: &str) -> String {
    format!(
        r#"System(
    name: "skipping",
    atoms: {{
        "A": Atom(locations: ["idle", "wait", "other"], initial: "idle", ports: ["go", "spin", "done", "tick"],
            transitions: [
                (from: "idle", port: "go", to: "wait"),
                (from: "wait", port: "spin", to: "other"),
                (from: "other", port: "spin", to: "wait"),
                (from: "wait", port: "done", to: "idle"),
                (from: "idle", port: "tick", to: "idle"),
            ]),
        "Clock": Atom(locations: ["on"], initial: "on", ports: ["tick"],
            transitions: [(from: "on", port: "tick", to: "on")]),
    }},
    components: [(name: "a", atom: "A"), (name: "clock", atom: "Clock")],
    connectors: [
        (name: "go", ports: ["a.go"]),
        (name: "spin", ports: ["a.spin"]),
        (name: "done", ports: ["a.done"]),
        {tick}
    ],
    properties: [LeadsTo(name: "answered", from: "a@wait", to: "a@idle")],
)"#
    )
}

#[test]
fn a_time_connector_that_never_fires_does_not_excuse_a_cycle() {
    let untimed = load(&skipping(""));
    let r = run(&untimed, Method::Explicit, 1);
    assert!(r.property(TIME_PROGRESS).is_none(), "no time, no check");
    let (before, _) = names(&result(&r, "answered").verdict);
    let timed = load(&skipping(
        r#"(name: "tick", ports: ["clock.tick", "a.tick"], guard: "false", role: Time),"#,
    ));
    let r = run(&timed, Method::Explicit, 1);
    // the same lasso as without the tick: time cannot pass on it
    let p = result(&r, "answered");
    assert!(p.verdict.fails(), "{p:?}");
    assert_eq!(names(&p.verdict).0, before);
    let tp = result(&r, TIME_PROGRESS);
    let PropertyVerdict::Fails { reason, .. } = &tp.verdict else {
        panic!("TimeProgress should fail: {tp:?}");
    };
    assert!(
        reason.contains("time stops after 0 steps") && reason.contains("its guard is false"),
        "{reason}"
    );
}

#[test]
fn a_tick_whose_participant_is_not_ready_says_which() {
    let text = skipping(r#"(name: "tick", ports: ["clock.tick", "a.tick"], role: Time),"#).replace(
        r#"(name: "done", ports: ["a.done"]),"#,
        r#"(name: "done", ports: ["a.done"], guard: "false"),"#,
    );
    let r = run(&load(&text), Method::Explicit, 1);
    let PropertyVerdict::Fails { reason, .. } = &result(&r, TIME_PROGRESS).verdict else {
        panic!("TimeProgress should fail");
    };
    // `a` ticks only when idle, and once it waits it spins forever
    assert!(
        reason.contains("time stops after 1 step")
            && reason.contains("`tick` cannot fire: `a.tick` is not ready (at `wait`)"),
        "{reason}"
    );
}

#[test]
fn the_symbolic_method_proves_time_progress_or_says_it_cannot() {
    let served = std::fs::read_to_string(format!(
        "{}/../robots/served.ron",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let r = run(&load(&served), Method::Symbolic, 1);
    let tp = result(&r, TIME_PROGRESS);
    assert!(tp.verdict.holds(), "{tp:?}");
    assert_eq!(tp.method, Method::Symbolic);
    // a timelock: never "holds", and a bounded response proved on the runs where time
    // diverges is not a verdict either
    let r = run(&load(&spinning(true)), Method::Symbolic, 1);
    assert!(matches!(
        result(&r, TIME_PROGRESS).verdict,
        PropertyVerdict::Inconclusive { .. }
    ));
    let PropertyVerdict::Inconclusive { reason } = &result(&r, "in_three").verdict else {
        panic!("in_three must not hold symbolically");
    };
    assert!(reason.contains("time progress is not proved"), "{reason}");
    // auto: the explicit phase decides it
    let r = run(&load(&spinning(true)), Method::Auto, 1);
    assert!(result(&r, TIME_PROGRESS).verdict.fails());
    assert!(result(&r, "in_three").verdict.fails());
}

/// The explicit verdict against the naive search (and `System::time_can_pass` too): it
/// fails iff some reachable state is timelocked or lies on a busy loop. For a timelock,
/// its trace replays, reaches a timelocked state in as few steps as any, and stays in
/// timelocked states, on a cycle that comes back or to a state with no step; for a busy
/// loop (reported where no state is timelocked), its lasso replays, enters the loop in as
/// few steps as any, and comes back through states on busy loops only.
fn check_against_naive(sys: &System, report: &Report) -> Result<(), String> {
    let Some(p) = report.property(TIME_PROGRESS) else {
        return if sys.has_time() {
            Err("no TimeProgress result in a model with time".into())
        } else {
            Ok(())
        };
    };
    let g = explore(sys);
    let locked = timelocked(sys, &g);
    // bip-model's own search, which `bip replay` uses, answers alike in every state
    for (s, state) in g.states.iter().enumerate() {
        if sys.time_can_pass(state) != Ok(Some(!locked[s])) {
            return Err(format!("time_can_pass disagrees in state {s}"));
        }
    }
    let index = |s: &State| g.states.iter().position(|x| x == s).expect("reachable");
    // breadth-first depths (g.states is in breadth-first order)
    let mut depth = vec![usize::MAX; g.states.len()];
    depth[0] = 0;
    for s in 0..g.states.len() {
        for (_, t) in &g.edges[s] {
            if depth[*t] == usize::MAX {
                depth[*t] = depth[s] + 1;
            }
        }
    }
    let nearest = (0..g.states.len())
        .filter(|&s| locked[s])
        .map(|s| depth[s])
        .min();
    let on_busy_loop = busy_loops(sys, &g);
    let nearest_loop = (0..g.states.len())
        .filter(|&s| on_busy_loop[s])
        .map(|s| depth[s])
        .min();
    match (&p.verdict, nearest) {
        (PropertyVerdict::Holds { .. }, None) if nearest_loop.is_none() => Ok(()),
        (PropertyVerdict::Fails { trace: Some(t), .. }, None) if nearest_loop.is_some() => {
            let path = t.replay(sys).map_err(|e| e.to_string())?;
            let states: Vec<State> = std::iter::once(sys.initial_state())
                .chain(path.iter().map(|(_, s)| s.clone()))
                .collect();
            let k = t.loop_start.ok_or("a busy loop without a cycle")?;
            if Some(k) != nearest_loop {
                return Err(format!(
                    "the busy loop after {k} steps, not {nearest_loop:?}"
                ));
            }
            if states[k] != states[states.len() - 1] {
                return Err("the busy loop does not return".into());
            }
            if !states[k..].iter().all(|s| on_busy_loop[index(s)]) {
                return Err("the busy loop passes a state that lets time pass".into());
            }
            Ok(())
        }
        (PropertyVerdict::Fails { trace: Some(t), .. }, Some(d)) => {
            let path = t.replay(sys).map_err(|e| e.to_string())?;
            let states: Vec<State> = std::iter::once(sys.initial_state())
                .chain(path.iter().map(|(_, s)| s.clone()))
                .collect();
            let first = states
                .iter()
                .position(|s| locked[index(s)])
                .ok_or("the trace reaches no timelocked state")?;
            if first != d {
                return Err(format!("the first timelock after {first} steps, not {d}"));
            }
            if states[first..].iter().any(|s| !locked[index(s)]) {
                return Err("the trace leaves the timelocked states".into());
            }
            let last = index(states.last().expect("a state"));
            match t.loop_start {
                Some(k) if states[k] != states[states.len() - 1] => {
                    Err("the cycle does not return".into())
                }
                Some(_) => Ok(()),
                None if g.edges[last].is_empty() => Ok(()),
                None => Err("the trace ends in a state with steps, and no cycle".into()),
            }
        }
        (v, n) => Err(format!(
            "the verifier says {v:?}, the naive search finds a timelock at depth {n:?} and \
             a busy loop at depth {nearest_loop:?}"
        )),
    }
}

/// Per state of `g`: it lies on a busy loop, a cycle of states with no tick among their
/// steps and not in range error, by steps of the model's own (no `Environment` step),
/// found by a search from each such state back to itself.
fn busy_loops(sys: &System, g: &Naive) -> Vec<bool> {
    if !sys.has_time() {
        return vec![false; g.states.len()];
    }
    let held = |s: usize| {
        !g.error[s]
            && g.edges[s]
                .iter()
                .all(|(step, _)| sys.role(step.label) != Role::Time)
    };
    let follow = |s: usize| {
        g.edges[s]
            .iter()
            .filter(|(step, t)| sys.role(step.label) != Role::Environment && held(*t))
            .map(|(_, t)| *t)
            .collect::<Vec<_>>()
    };
    (0..g.states.len())
        .map(|s| {
            if !held(s) {
                return false;
            }
            let mut seen = HashSet::new();
            let mut queue: VecDeque<usize> = follow(s).into();
            while let Some(u) = queue.pop_front() {
                if u == s {
                    return true;
                }
                if seen.insert(u) {
                    queue.extend(follow(u));
                }
            }
            false
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    /// Random systems with Time and Environment roles: one worker and three agree, and the
    /// verdict and trace agree with the naive search.
    #[test]
    fn random_systems_match_the_naive_search(seed in any::<u64>()) {
        let opts = bip_random_systems::Options {
            responses: true,
            ..bip_random_systems::Options::verifier(true)
        };
        let text = bip_random_systems::generate_with(seed, &opts).to_ron();
        let sys = load_str("random.ron", &text)
            .map_err(|e| TestCaseError::fail(format!("{}\n{text}", e.summary())))?;
        let one = run(&sys, Method::Explicit, 1);
        prop_assert_eq!(&run(&sys, Method::Explicit, 3).properties, &one.properties, "{}", text);
        prop_assume!(one.stats.complete);
        check_against_naive(&sys, &one).map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
    }
}

/// The random comparison is not vacuous: over its seeds, some models have a timelock and
/// some have time but none.
#[test]
fn random_systems_have_timelocks_and_time_progress() {
    let (mut fails, mut holds) = (0, 0);
    for seed in 0..120u64 {
        let opts = bip_random_systems::Options {
            responses: true,
            ..bip_random_systems::Options::verifier(true)
        };
        let text = bip_random_systems::generate_with(seed, &opts).to_ron();
        let Ok(sys) = load_str("random.ron", &text) else {
            continue;
        };
        let r = run(&sys, Method::Explicit, 1);
        match r.property(TIME_PROGRESS).map(|p| &p.verdict) {
            Some(v) if v.fails() => fails += 1,
            Some(v) if v.holds() => holds += 1,
            _ => {}
        }
        check_against_naive(&sys, &r).unwrap_or_else(|e| panic!("{e}\n{text}"));
    }
    assert!(fails >= 3 && holds >= 3, "{fails} fail, {holds} hold");
}
