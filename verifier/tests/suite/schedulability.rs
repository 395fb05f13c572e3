//! A task's demand per period against an oracle that walks every path between two ticks
//! (depth first, from every state a tick leads to): the exact demand is the oracle's
//! maximum, the bound from the codel automata is never below it, and the analysis on
//! top gives the verdict a hand computation gives.

use std::collections::{HashMap, HashSet};

use bip_lang::load_str;
use bip_model::{Label, State, Steps, System};
use bip_sched::{Assignment, ResponseTime};
use bip_verifier::{schedulability, DemandChoice, DemandMethod, Options};

/// Two activities: `A` runs `main` and `check` in one period (2.5 ms) and stays active,
/// or `main` (2 ms) and ends; `B` runs its `start` (0.3 ms). `Exclusive` keeps them from
/// being active together when `exclusive` is true.
fn layer(exclusive: bool, task_b: &str) -> String {
    let constraint = if exclusive {
        r#"Exclusive(services: ["m.A", "m.B"])"#
    } else {
        ""
    };
    format!(
        r#"System(name: "budget", tick_ms: 10,
    modules: [(name: "m", tasks: [(name: "t", period: 1), (name: "u", period: 2)],
        services: [
            (name: "A", kind: Activity, task: "t", codels: [
                (state: "start", yields: ["pause::main"], wcet: "1ms"),
                (state: "main", yields: ["pause::main", "check", "ether"], wcet: "2ms"),
                (state: "check", yields: ["pause::main"], wcet: 500)]),
            (name: "B", kind: Activity, task: "{task_b}", codels: [
                (state: "start", yields: ["ether"], wcet: 300)]),
        ])],
    constraints: [{constraint}],
)"#
    )
}

/// The costliest path between two ticks for each task, by walking every path from every
/// state a tick (or the start) leads to; `None` for a task whose paths can loop with a
/// cost (no bound). Independent of the verifier: the step relation, a stack, a set.
fn oracle(system: &System) -> Vec<Option<u64>> {
    let map = system.genom.as_ref().unwrap();
    let mut owner: HashMap<u32, (usize, u64)> = HashMap::new();
    let mut tasks = 0;
    for module in &map.modules {
        for (ti, _) in module.tasks.iter().enumerate() {
            for s in module.services.iter().filter(|s| s.task == Some(ti)) {
                for c in &s.codels {
                    let w = c.wcet_us.unwrap_or(0);
                    owner.insert(c.run, (tasks, w));
                    owner.insert(c.fail, (tasks, w));
                }
            }
            tasks += 1;
        }
    }
    let successors = |s: &State| -> Vec<(u32, State)> {
        let mut steps = Steps::new();
        system.enabled_steps(s, &mut steps).unwrap();
        steps
            .iter()
            .map(|step| {
                let mut next = s.clone();
                system.fire(s, step, &mut next).unwrap();
                let label = match step.label {
                    Label::Interaction(i) => i,
                    Label::Internal { .. } => u32::MAX,
                };
                (label, next)
            })
            .collect()
    };
    // every reachable state, and the period starts
    let mut seen = HashSet::new();
    let mut starts = HashSet::new();
    let mut todo = vec![system.initial_state()];
    starts.insert(system.initial_state());
    seen.insert(system.initial_state());
    while let Some(s) = todo.pop() {
        for (label, next) in successors(&s) {
            if label == map.tick {
                starts.insert(next.clone());
            }
            if seen.insert(next.clone()) {
                todo.push(next);
            }
        }
    }
    let mut best: Vec<Option<u64>> = vec![Some(0); tasks];
    for (task, best) in best.iter_mut().enumerate() {
        for start in &starts {
            // depth-first over simple paths; a path that comes back to a state with a
            // higher cost has a costly loop
            let mut path: Vec<(State, u64)> = Vec::new();
            let mut stack = vec![(start.clone(), 0u64, 0usize)];
            while let Some((s, cost, depth)) = stack.pop() {
                path.truncate(depth);
                if let Some(&(_, before)) = path.iter().find(|(p, _)| *p == s) {
                    if cost > before {
                        *best = None;
                    }
                    continue;
                }
                if let Some(b) = best {
                    *b = (*b).max(cost);
                }
                path.push((s.clone(), cost));
                for (label, next) in successors(&s) {
                    if label == map.tick {
                        continue;
                    }
                    let w = match owner.get(&label) {
                        Some(&(t, w)) if t == task => w,
                        _ => 0,
                    };
                    stack.push((next, cost + w, depth + 1));
                }
            }
        }
    }
    best
}

fn demands(system: &System, choice: DemandChoice) -> (Vec<Option<u64>>, DemandMethod) {
    let s = schedulability(system, &Options::default(), Assignment::Given, choice)
        .unwrap()
        .expect("the model has WCETs");
    (s.demands, s.method)
}

/// Checks a model's exact demands against the oracle and the bound against them; returns
/// the first task's exact demand and bound.
fn first_task(text: &str) -> (u64, u64) {
    let system = load_str("budget.ron", text).unwrap();
    let (exact, method) = demands(&system, DemandChoice::Exact);
    assert!(matches!(method, DemandMethod::Exact { .. }), "{method:?}");
    assert_eq!(exact, oracle(&system));
    let (bound, _) = demands(&system, DemandChoice::Bound);
    for (b, e) in bound.iter().zip(&exact) {
        assert!(b.unwrap() >= e.unwrap(), "{bound:?} below {exact:?}");
    }
    (exact[0].unwrap(), bound[0].unwrap())
}

#[test]
fn the_exact_demand_is_the_costliest_period_and_the_bound_is_above_it() {
    // A's costliest chain (main, check: 2.5 ms) and B's start (0.3 ms) in one period; the
    // bound is the same sum
    assert_eq!(first_task(&layer(false, "t")), (2800, 2800));
    // with Exclusive, B's start waits for A to be at ether: A's chain ends there by
    // `check` failing (an error path costs its codel too), then B starts
    assert_eq!(first_task(&layer(true, "t")), (2800, 2800));
    // B on its own task
    assert_eq!(first_task(&layer(false, "u")), (2500, 2500));
    // Exclusive where it matters: B's `run` (0.4 ms) and A's `main` (2 ms) are never in
    // one period, which the bound from the automata cannot know
    let apart = r#"System(name: "apart", tick_ms: 10,
    modules: [(name: "m", tasks: [(name: "t", period: 1)],
        services: [
            (name: "A", kind: Activity, task: "t", codels: [
                (state: "start", yields: ["pause::main"], wcet: "1ms"),
                (state: "main", yields: ["pause::main", "ether"], wcet: "2ms")]),
            (name: "B", kind: Activity, task: "t", codels: [
                (state: "start", yields: ["pause::run"], wcet: 300),
                (state: "run", yields: ["pause::run", "ether"], wcet: 400)]),
        ])],
    constraints: [Exclusive(services: ["m.A", "m.B"])],
)"#;
    assert_eq!(first_task(apart), (2300, 2400));
    // periods of hours: a demand past what 32 bits of microseconds hold
    let long = layer(false, "t")
        .replace("tick_ms: 10,", "tick_ms: 10000000,")
        .replace(r#"wcet: "2ms""#, r#"wcet: "5000s""#);
    assert_eq!(first_task(&long), (5_000_000_800, 5_000_000_800));
}

#[test]
fn the_robots_demands_match_the_oracle() {
    // mini.ron with a WCET on every codel
    let text = include_str!("../../../robots/tests/mini.ron");
    let mut k = 0;
    let timed: String = text
        .split("(state: ")
        .enumerate()
        .map(|(i, part)| {
            if i == 0 {
                part.to_string()
            } else {
                k += 1;
                format!("(wcet: {}, state: {part}", 100 * k)
            }
        })
        .collect();
    let system = load_str("mini.ron", &timed).unwrap();
    let (exact, _) = demands(&system, DemandChoice::Exact);
    assert_eq!(exact, oracle(&system));
    assert!(exact.iter().all(|d| d.is_some_and(|d| d > 0)), "{exact:?}");
    let (bound, _) = demands(&system, DemandChoice::Bound);
    for (b, e) in bound.iter().zip(&exact) {
        assert!(b.unwrap() >= e.unwrap(), "{bound:?} below {exact:?}");
    }
}

/// `t` (10 ms) asks 2.8 ms; with `main` at 9 ms, `t` asks 9.5 ms and `u` (20 ms, below
/// it) responds after 9.8 ms; with `B` at 1 ms `u` responds at 20 ms, its deadline, and
/// with a deadline of 15 ms it misses.
#[test]
fn the_analysis_on_the_demands() {
    let analysed = |text: &str| {
        let system = load_str("budget.ron", text).unwrap();
        schedulability(
            &system,
            &Options::default(),
            Assignment::Given,
            DemandChoice::Exact,
        )
        .unwrap()
        .unwrap()
    };
    let s = analysed(&layer(false, "t"));
    assert!(s.schedulable());
    assert_eq!(
        s.analysis.as_ref().unwrap().tasks[0].response,
        ResponseTime::Exact(2800)
    );
    let heavy = layer(false, "u").replace(r#"wcet: "2ms""#, r#"wcet: "9ms""#);
    let s = analysed(&heavy);
    let a = s.analysis.as_ref().unwrap();
    assert_eq!(a.tasks[0].response, ResponseTime::Exact(9500));
    assert_eq!(a.tasks[1].response, ResponseTime::Exact(9800));
    assert!(s.schedulable());
    let heavier = heavy.replace("wcet: 300", r#"wcet: "1ms""#);
    let s = analysed(&heavier);
    assert_eq!(
        s.analysis.as_ref().unwrap().tasks[1].response,
        ResponseTime::Exact(20_000)
    );
    assert!(s.schedulable());
    let late = heavier.replace(
        r#"(name: "u", period: 2)"#,
        r#"(name: "u", period: 2, deadline: "15ms")"#,
    );
    let s = analysed(&late);
    assert!(!s.schedulable());
    let a = s.analysis.as_ref().unwrap();
    assert_eq!(a.misses(&s.set).collect::<Vec<_>>(), [1]);
}

/// The responses of robots/controllers.ron by hand (Joseph and Pandya's fixed point):
/// control CPU, priorities 40..10: odometry 2; speed 6 + ⌈8/10⌉·2 = 8; motors
/// 3 + ⌈13/10⌉·2 + ⌈13/20⌉·6 = 13; safety 10 + ⌈36/10⌉·2 + ⌈36/20⌉·(6 + 3) = 36 (from
/// 21, then 34, then 36). comm CPU, rate-monotonic: telemetry 30; logger 40 + ⌈70/100⌉·30
/// = 70. The demands are the declared WCETs: no state is explored.
#[test]
fn periodic_atoms_are_analysed_with_their_declared_work() {
    let text = include_str!("../../../robots/controllers.ron");
    let analysed = |text: &str| {
        let system = load_str("controllers.ron", text).unwrap();
        schedulability(
            &system,
            &Options::default(),
            Assignment::Given,
            DemandChoice::Exact,
        )
        .unwrap()
        .expect("the atoms stand for tasks")
    };
    let s = analysed(text);
    assert_eq!(s.method, DemandMethod::Declared);
    let names: Vec<&str> = s.set.tasks.iter().map(|t| t.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "odometry",
            "speed",
            "motors",
            "safety",
            "telemetry",
            "logger"
        ]
    );
    let a = s.analysis.as_ref().unwrap();
    let responses: Vec<ResponseTime> = a.tasks.iter().map(|t| t.response).collect();
    assert_eq!(
        responses,
        [2000, 8000, 13_000, 36_000, 30_000, 70_000].map(ResponseTime::Exact)
    );
    assert!(a.tasks[3].iterations >= 3, "{:?}", a.tasks[3]);
    assert!(s.schedulable());
    // safety at 15 ms: 15 + ⌈54/10⌉·2 + ⌈54/20⌉·9 = 54 > 50
    let heavy = text.replace(
        r#"wcet: "10ms", priority: 10"#,
        r#"wcet: "15ms", priority: 10"#,
    );
    let s = analysed(&heavy);
    assert!(!s.schedulable());
    assert_eq!(
        s.verdict(),
        "not schedulable: safety misses its deadline by 4 ms (responds in 54 ms, deadline 50 ms)"
    );
}

/// A module's task and an atom's task on one CPU: the atom's declared work interferes
/// with the module's exact demand. Rate-monotonic: `watch` (5 ms, 1 ms), `m.t` (10 ms,
/// 2.5 ms: 2.5 + ⌈3.5/5⌉·1 = 3.5), `m.u` (20 ms, 0.3 ms: 0.3 + 1 + 2.5 = 3.8).
#[test]
fn module_tasks_and_atoms_share_a_cpu() {
    let text = layer(false, "u").replace(
        "    modules: [",
        "    atoms: { \"Watch\": Atom(locations: [\"on\"], initial: \"on\", task: (period: \"5ms\", wcet: \"1ms\")) },\n    components: [(name: \"watch\", atom: \"Watch\")],\n    modules: [",
    );
    let system = load_str("mixed.ron", &text).unwrap();
    let (exact, method) = demands(&system, DemandChoice::Exact);
    assert!(matches!(method, DemandMethod::Exact { .. }), "{method:?}");
    assert_eq!(exact, [Some(2500), Some(300), Some(1000)]);
    let (bound, _) = demands(&system, DemandChoice::Bound);
    assert_eq!(bound[2], Some(1000));
    let s = schedulability(
        &system,
        &Options::default(),
        Assignment::Given,
        DemandChoice::Exact,
    )
    .unwrap()
    .unwrap();
    let names: Vec<&str> = s.set.tasks.iter().map(|t| t.name.as_str()).collect();
    assert_eq!(names, ["m.t", "m.u", "watch"]);
    let a = s.analysis.as_ref().unwrap();
    let responses: Vec<ResponseTime> = a.tasks.iter().map(|t| t.response).collect();
    assert_eq!(responses, [3500, 3800, 1000].map(ResponseTime::Exact));
    assert_eq!(a.tasks[2].rank, 0);
}

/// The exact demands come from the parallel exploration: the same demands and counts with
/// one worker as with two. A limit reached (states, memory, time, Ctrl-C) or a range
/// error falls back to the bound and says why.
#[test]
fn exact_demands_are_the_same_with_any_workers_and_stop_at_every_limit() {
    let system = load_str("budget.ron", &layer(true, "t")).unwrap();
    let with = |options: Options| exact_with(&system, options);
    let one = with(Options {
        jobs: 1,
        ..Options::default()
    });
    let two = with(Options {
        jobs: 2,
        ..Options::default()
    });
    assert!(
        matches!(one.method, DemandMethod::Exact { .. }),
        "{:?}",
        one.method
    );
    assert_eq!((&one.demands, &one.method), (&two.demands, &two.method));
    let why = |options: Options| match with(options).method {
        DemandMethod::Bound { why } => why,
        method => panic!("{method:?}"),
    };
    let not_all = "the states were not all explored: ";
    assert_eq!(
        why(Options {
            max_states: Some(3),
            ..Options::default()
        }),
        format!("{not_all}more than 3 states")
    );
    assert_eq!(
        why(Options {
            max_memory: Some(1 << 20),
            ..Options::default()
        }),
        format!("{not_all}more than {} bytes of graph", 1 << 20)
    );
    assert_eq!(
        why(Options {
            timeout: Some(std::time::Duration::ZERO),
            ..Options::default()
        }),
        format!("{not_all}the time limit")
    );
    assert_eq!(
        why(Options {
            interrupt: Some(std::sync::Arc::new(true.into())),
            ..Options::default()
        }),
        format!("{not_all}interrupted")
    );
    // an atom whose variable leaves its range two steps in
    let overflow = layer(false, "u").replace(
        "    modules: [",
        "    atoms: { \"Overflow\": Atom(locations: [\"s\"], initial: \"s\", vars: [(name: \"y\", ty: Int(0, 5))], transitions: [(from: \"s\", to: \"s\", action: \"y = y + 2\")]) },\n    components: [(name: \"b\", atom: \"Overflow\")],\n    modules: [",
    );
    let s = exact_with(
        &load_str("overflow.ron", &overflow).unwrap(),
        Options::default(),
    );
    assert_eq!(
        s.method,
        DemandMethod::Bound {
            why: format!("{not_all}a range error (b.y = 6 is outside its range Int(0, 5) in the action of b: s -internal-> s); `bip verify` shows it")
        }
    );
}

fn exact_with(system: &System, options: Options) -> bip_verifier::Schedulability {
    schedulability(system, &options, Assignment::Given, DemandChoice::Exact)
        .unwrap()
        .expect("the model has WCETs")
}

#[test]
fn a_loop_of_plain_yields_has_no_demand_bound() {
    // `main` and `check` yield to each other without pausing: one period can run them
    // forever, and both methods say so; the other task keeps its bound
    let looping = r#"System(name: "looping", tick_ms: 10,
    modules: [(name: "m", tasks: [(name: "t", period: 1), (name: "u", period: 1)],
        services: [
            (name: "A", kind: Activity, task: "t", codels: [
                (state: "start", yields: ["main"], wcet: "1ms"),
                (state: "main", yields: ["check", "ether"], wcet: "2ms"),
                (state: "check", yields: ["main"], wcet: 500)]),
            (name: "B", kind: Activity, task: "u", codels: [
                (state: "start", yields: ["pause::start", "ether"], wcet: 300)]),
        ])],
)"#;
    let system = load_str("looping.ron", looping).unwrap();
    let (bound, _) = demands(&system, DemandChoice::Bound);
    assert_eq!(bound, vec![None, Some(300)]);
    assert_eq!(oracle(&system), vec![None, Some(300)]);
}

/// The report of `bip verify --method explicit` on a model text.
fn explored(text: &str) -> bip_verifier::Report {
    let system = load_str("ts.ron", text).unwrap();
    bip_verifier::verify(
        &system,
        bip_verifier::Method::Explicit,
        &Options::default(),
        &|_| {},
    )
    .unwrap()
}

/// A timed model (`time: Exact`) decides its deadlines by exploration, one generated
/// invariant per task, and has no `Schedulable` by response-time analysis: `lo` runs
/// 3 ms from 4, 8, ... on the one core, cooperatively, so `hi` (released at 1, 5, ...,
/// 1 ms of work) waits for it and misses its 2 ms deadline, first at 8 ms.
#[test]
fn a_timed_model_decides_its_deadlines_by_exploration() {
    let text = |hi_deadline: &str| {
        format!(
            r#"System(name: "ts", tick_ms: 1, time: Exact, cpus: [(name: "main", preemption: Job)],
    modules: [(name: "m", tasks: [
        (name: "hi", period: 4, delay: 1, priority: 2, deadline: "{hi_deadline}", codels: [
            (state: "start", yields: ["pause::run"], bcet: "1ms", wcet: "1ms"),
            (state: "run", yields: ["pause::run"], bcet: "1ms", wcet: "1ms")]),
        (name: "lo", period: 4, priority: 1, codels: [
            (state: "start", yields: ["pause::run"], bcet: "3ms", wcet: "3ms"),
            (state: "run", yields: ["pause::run"], bcet: "3ms", wcet: "3ms")])])])"#
        )
    };
    let verdicts = |text: &str| -> Vec<(String, bool)> {
        let report = explored(text);
        assert!(
            report.properties.iter().all(|p| p.name != "Schedulable"),
            "no response-time analysis of a timed model"
        );
        report
            .properties
            .iter()
            .filter(|p| p.name.contains("deadline"))
            .map(|p| (p.name.clone(), p.verdict.fails()))
            .collect()
    };
    assert_eq!(
        verdicts(&text("2ms")),
        [
            ("m.hi meets its 2 ms deadline".to_string(), true),
            ("m.lo meets its 4 ms deadline".to_string(), false)
        ]
    );
    // the miss's shortest run ends at 8 ms, 3 ms after `hi`'s release at 5
    let report = explored(&text("2ms"));
    let hi = report
        .properties
        .iter()
        .find(|p| p.name == "m.hi meets its 2 ms deadline")
        .expect("hi's deadline");
    let trace = hi.verdict.trace().expect("a counterexample");
    let system = load_str("timed.ron", &text("2ms")).unwrap();
    assert_eq!(crate::trace_units(&system, trace), 8);
    // with 3 ms, `hi` responds in at most 3 ms: no miss
    assert!(verdicts(&text("3ms")).iter().all(|(_, fails)| !fails));
    // and the worst responses are 3 ms each, each with the run that ends in the job end
    // that takes it; with the 2 ms deadline, which `hi` misses, the same (no job runs
    // past a second release: every figure is exact)
    let worst = |text: &str| -> Vec<(String, Option<String>, Option<String>)> {
        let report = explored(text);
        report
            .properties
            .iter()
            .filter(|p| p.kind == bip_verifier::CheckKind::WorstResponse)
            .map(|p| {
                let last = p
                    .verdict
                    .trace()
                    .and_then(|t| t.steps.last())
                    .map(|s| s.step.clone());
                let figure = p.verdict.holds().then(|| p.note.clone()).flatten();
                (p.name.clone(), figure, last)
            })
            .collect()
    };
    let some = |s: &str| Some(s.to_string());
    assert_eq!(
        worst(&text("3ms")),
        [
            (
                "m.hi worst response".to_string(),
                some("3 ms"),
                some("m_hi_done")
            ),
            (
                "m.lo worst response".to_string(),
                some("3 ms"),
                some("m_lo_done")
            )
        ]
    );
    assert_eq!(worst(&text("2ms")), worst(&text("3ms")));
}

/// A bound in a timed model counts ticks of `tick_ms` in real time, whatever the unit:
/// `robots/tests/timed.ron` (unit 500 µs) runs `Log` on task `log`, period 8 ms, on one of
/// two cores it never waits for, in 1 to 2 ms. A request that comes just after the release
/// at a boundary waits for the next one, 8 ms later: the reply comes at most 10 ms after
/// the request, and 10 ms after it on the worst run; written in ticks or as a duration.
#[test]
fn a_timed_models_reply_bound_is_in_real_time() {
    let text = |k: &str| {
        include_str!("../../../robots/tests/timed.ron").replacen(
            "    ],\n)",
            &format!("    ],\n    properties: [Replies(service: \"nav.Log\", within: {k})],\n)"),
            1,
        )
    };
    let verdict = |k: &'static str| {
        let report = explored(&text(k));
        let p = report
            .properties
            .iter()
            .find(|p| p.name.contains("Log"))
            .expect("the bound's result")
            .clone();
        (k, p.verdict.holds(), p.verdict.fails())
    };
    assert_eq!(verdict("10"), ("10", true, false));
    assert_eq!(verdict("9"), ("9", false, true));
    assert_eq!(verdict(r#""10ms""#), (r#""10ms""#, true, false));
    assert_eq!(verdict(r#""9500us""#), (r#""9500us""#, false, true));
    // the failure says the bound in real time, as written, not in the model's units
    let report = explored(&text(r#""9500us""#));
    let failed = report
        .properties
        .iter()
        .find(|p| p.name.contains("Log"))
        .expect("the bound");
    let reason = match &failed.verdict {
        bip_verifier::PropertyVerdict::Fails { reason, .. } => reason.clone(),
        other => panic!("{other:?}"),
    };
    assert!(
        reason.starts_with("the response does not come within 9.5 ms: "),
        "{reason}"
    );
}

/// A timed model whose task can loop on codels that take no time: time stops in that
/// loop, the job in it never ends, and its deadline never passes. `TimeProgress` fails
/// with the loop, and the deadline and the worst response, true of the model only because
/// time stops, are not reported as holding.
#[test]
fn a_timed_models_deadlines_are_not_said_to_hold_where_time_stops() {
    let text = |spin: &str| {
        format!(
            r#"System(name: "loop", tick_ms: 1, time: Exact,
    cpus: [(name: "main", preemption: Job)],
    modules: [(name: "m", tasks: [
        (name: "t", period: 2, codels: [
            (state: "start", yields: ["spin"], wcet: "1ms"),
            (state: "spin", yields: ["{spin}"])])])])"#
        )
    };
    let verdicts = |text: &str| -> Vec<(String, &'static str)> {
        explored(text)
            .properties
            .iter()
            .map(|p| {
                let v = if p.verdict.holds() {
                    "holds"
                } else if p.verdict.fails() {
                    "fails"
                } else {
                    "inconclusive"
                };
                (p.name.clone(), v)
            })
            .filter(|(n, _)| n.starts_with("m.t") || n == "TimeProgress")
            .collect()
    };
    assert_eq!(
        verdicts(&text("spin")),
        [
            ("m.t meets its 2 ms deadline".to_string(), "inconclusive"),
            ("TimeProgress".to_string(), "fails"),
            ("m.t worst response".to_string(), "inconclusive"),
        ]
    );
    // with a pause in the loop, time passes and both hold
    assert_eq!(
        verdicts(&text("pause::spin")),
        [
            ("m.t meets its 2 ms deadline".to_string(), "holds"),
            ("TimeProgress".to_string(), "holds"),
            ("m.t worst response".to_string(), "holds"),
        ]
    );
}

/// An async codel runs in a thread of its own (docs/genom.md, "Async codels"): its WCET is
/// not its task's demand, exact or bounded, whatever the synchronous codels around it do.
#[test]
fn an_async_codels_wcet_is_not_its_tasks_demand() {
    let text = r#"System(name: "grab", tick_ms: 10,
    modules: [(name: "m", tasks: [(name: "t", period: 1)],
        services: [(name: "A", kind: Activity, task: "t", codels: [
            (state: "start", yields: ["grab"], wcet: "1ms"),
            (state: "grab", yields: ["pause::show", "ether"], wcet: "8ms", async: true),
            (state: "show", yields: ["grab"], wcet: "2ms")])])],
)"#;
    let system = load_str("grab.ron", text).unwrap();
    let (exact, method) = demands(&system, DemandChoice::Exact);
    assert!(matches!(method, DemandMethod::Exact { .. }), "{method:?}");
    // `show` then `grab`'s start, or `start`: never the grab's 8 ms
    assert_eq!(exact, [Some(2000)]);
    let (bound, _) = demands(&system, DemandChoice::Bound);
    assert_eq!(bound, [Some(2000)]);
}

/// In a timed model a request can interrupt an activity while its codel runs: the codel
/// ends, and the activity's `stop` runs in the same job. `nav` is alone on its core, so a
/// job's response is its work: `move` (5 ms) then `stop` (2 ms), 7 ms, which the bound
/// from the codel automata must cover.
#[test]
fn the_bound_counts_a_stop_after_an_interrupted_codel() {
    let text = r#"System(name: "nav", tick_ms: 10, time: Exact,
    modules: [(name: "ndd", tasks: [(name: "nav", period: 1)],
        services: [
            (name: "GoTo", kind: Activity, task: "nav", interrupts: ["GoTo"], codels: [
                (state: "start", yields: ["pause::move"], bcet: "1ms", wcet: "1ms"),
                (state: "move", yields: ["pause::move", "ether"], bcet: "5ms", wcet: "5ms"),
                (state: "stop", yields: ["ether"], bcet: "2ms", wcet: "2ms")]),
            (name: "Stop", kind: Function, interrupts: ["GoTo"]),
        ])],
)"#;
    let report = explored(text);
    let worst = report
        .properties
        .iter()
        .find(|p| p.kind == bip_verifier::CheckKind::WorstResponse)
        .expect("nav's worst response");
    assert!(worst.verdict.holds(), "{worst:?}");
    assert_eq!(worst.note.as_deref(), Some("7 ms"));
    let system = load_str("nav.ron", text).unwrap();
    let (bound, _) = demands(&system, DemandChoice::Bound);
    assert_eq!(bound, vec![Some(7000)]);
}

/// The activity of [`interruptible`]: per codel (`start`, `a`, `b`, `stop`), its yields
/// (0: pause to `a`, 1: go on to `a`, 2: go on to `b`, 3: pause to `b`, 4: end) and its
/// duration in ms.
type Automaton = [(Vec<u8>, u64); 4];

/// A timed layer of one task alone on its core running one activity that a request can
/// interrupt at any moment; each codel yields as drawn, or ends, but never to `stop`.
fn interruptible(codels: &Automaton) -> String {
    let target = |y: u8| match y {
        0 => "pause::a",
        1 => "a",
        2 => "b",
        3 => "pause::b",
        _ => "ether",
    };
    // the codels `start` and `stop` reach (the others are an error)
    let mut reached = [true, false, false, true];
    for _ in 0..2 {
        for (k, (yields, _)) in codels.iter().enumerate() {
            if reached[k] {
                for &y in yields {
                    match y {
                        0 | 1 => reached[1] = true,
                        2 | 3 => reached[2] = true,
                        _ => {}
                    }
                }
            }
        }
    }
    let codels: Vec<String> = ["start", "a", "b", "stop"]
        .iter()
        .zip(codels)
        .zip(reached)
        .filter(|(_, reached)| *reached)
        .map(|((state, (yields, ms)), _)| {
            // every codel may end the activity, so that every codel has a way to `ether`
            let mut yields: Vec<&str> = yields.iter().map(|&y| target(y)).collect();
            yields.push("ether");
            yields.sort_unstable();
            yields.dedup();
            let yields: Vec<String> = yields.iter().map(|y| format!("{y:?}")).collect();
            format!(
                r#"(state: "{state}", yields: [{}], bcet: "{ms}ms", wcet: "{ms}ms")"#,
                yields.join(", ")
            )
        })
        .collect();
    format!(
        r#"System(name: "one", tick_ms: 20, time: Exact,
    modules: [(name: "m", tasks: [(name: "t", period: 1)],
        services: [
            (name: "A", kind: Activity, task: "t", interrupts: ["A"], codels: [{}]),
            (name: "Stop", kind: Function, interrupts: ["A"]),
        ])],
)"#,
        codels.join(",\n                ")
    )
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
    /// A task alone on its core responds in a job's work: the exploration's worst
    /// response is never above the bound from the codel automata, interrupts included.
    #[test]
    fn the_bound_covers_every_job_of_an_interruptible_activity(
        codels in proptest::array::uniform4((
            proptest::collection::vec(0u8..5, 1..3),
            1u64..4,
        ))
    ) {
        let text = interruptible(&codels);
        let system = load_str("one.ron", &text).unwrap();
        let (bound, _) = demands(&system, DemandChoice::Bound);
        let report = explored(&text);
        let worst = report
            .properties
            .iter()
            .find(|p| p.kind == bip_verifier::CheckKind::WorstResponse)
            .expect("the task's worst response");
        // a chain that loops has no bound and may run past the period: nothing to compare
        if let (Some(bound), Some(figure)) = (bound[0], worst.verdict.holds().then_some(&worst.note)) {
            let figure = figure.as_deref().expect("a figure");
            let ms: u64 = figure.trim_end_matches(" ms").parse().expect("a figure in ms");
            proptest::prop_assert!(ms * 1000 <= bound, "{figure} above {bound} µs\n{text}");
        }
    }
}
