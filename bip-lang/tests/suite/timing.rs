//! Time budgets in a GenoM layer: what the engine's map carries, and every bad value with
//! its message and position.

use bip_lang::load_str;

use crate::support::errors::assert_error;

const TIMED: &str = r#"System(
    name: "timed",
    tick_ms: 10,
    cpus: ["main", "io"],
    constants: { "RUN_US": 3000 },
    modules: [
        (name: "loc", tasks: [(name: "fast", period: 1, cpu: "main", priority: 5, deadline: "8ms"),
                              (name: "slow", period: 5, cpu: "io")],
         services: [
            (name: "Track", kind: Activity, task: "fast",
             codels: [(state: "start", yields: ["pause::run"], wcet: "1.5ms"),
                      (state: "run", yields: ["pause::run", "ether"], wcet: "RUN_US")]),
            (name: "Log", kind: Activity, task: "slow",
             codels: [(state: "start", yields: ["ether"], wcet: 250)]),
         ]),
    ],
)"#;

#[test]
fn the_map_carries_cpus_priorities_deadlines_and_wcets() {
    let system = load_str("timed.ron", TIMED).expect("loads");
    let map = system.genom.as_ref().expect("a GenoM layer");
    assert_eq!(system.budgets.cpus, ["main", "io"]);
    let loc = &map.modules[0];
    let fast = &loc.tasks[0];
    assert_eq!(
        (fast.cpu, fast.priority, fast.deadline_us),
        (0, Some(5), Some(8000))
    );
    let slow = &loc.tasks[1];
    assert_eq!((slow.cpu, slow.priority, slow.deadline_us), (1, None, None));
    let wcets: Vec<(&str, Option<u64>)> = loc
        .services
        .iter()
        .flat_map(|s| s.codels.iter().map(|c| (c.state.as_str(), c.wcet_us)))
        .collect();
    assert!(wcets.contains(&("run", Some(3000))), "{wcets:?}");
    assert!(wcets.contains(&("start", Some(1500))), "{wcets:?}");
    assert!(wcets.contains(&("start", Some(250))), "{wcets:?}");
}

fn bad(from: &str, to: &str) -> String {
    assert!(TIMED.contains(from), "{from}");
    TIMED.replacen(from, to, 1)
}

#[test]
fn bad_time_budgets() {
    assert_error(
        &bad(r#"cpu: "io""#, r#"cpu: "gpu""#),
        "unknown CPU `gpu`",
        "gpu",
    );
    assert_error(
        &bad(r#"wcet: "RUN_US""#, r#"wcet: "11ms""#),
        "codel `run` of `loc.Track` may take 11 ms, more than the period of its task `fast` (10 ms)",
        "11ms",
    );
    assert_error(&bad(r#"wcet: 250"#, r#"wcet: 0"#), "a WCET of zero", "0");
    assert_error(
        &bad(r#"wcet: 250"#, r#"wcet: "0.5us""#),
        "a WCET must be a duration: `0.5us` is not a whole number of microseconds",
        "0.5us",
    );
    assert_error(
        &bad(r#"wcet: 250"#, r#"wcet: -4"#),
        "a WCET must be a duration: -4 µs is negative",
        "-4",
    );
    assert_error(
        &bad(r#"deadline: "8ms""#, r#"deadline: "soon""#),
        "a deadline must be a duration",
        "soon",
    );
    assert_error(
        &bad(r#"    tick_ms: 10,"#, ""),
        "a time budget needs the model's `tick_ms`",
        "8ms",
    );
    // a `tick_ms` given, but too long to count in microseconds
    assert_error(
        &bad(r#"    tick_ms: 10,"#, "    tick_ms: 9223372036854775807,"),
        "`tick_ms` of 9223372036854775807 ms overflows",
        "9223372036854775807",
    );
    // a number without a unit is microseconds: below 100, a unit is required
    assert_error(
        &bad(r#"wcet: 250"#, r#"wcet: 4"#),
        "a WCET of 4 µs, written without a unit",
        "4",
    );
    assert_error(
        &bad(r#"deadline: "8ms""#, r#"deadline: 8"#),
        "a deadline of 8 µs, written without a unit",
        "8",
    );
    assert_error(
        &bad(r#"cpu: "io")"#, r#"cpu: "main")"#),
        "some tasks on this CPU have a priority, and this one has none",
        "slow",
    );
    assert_error(
        &bad(r#"    cpus: ["main", "io"],"#, ""),
        "unknown CPU `main`",
        "main",
    );
    assert_error(
        &bad(r#"cpus: ["main", "io"]"#, r#"cpus: ["main", "main"]"#),
        "duplicate CPU `main`",
        "main",
    );
}

/// Plain periodic tasks, PECOS-style: atoms that stand for tasks, without GenoM modules.
const PERIODIC: &str = r#"System(
    name: "periodic",
    cpus: ["control", "comm"],
    constants: { "FAST_US": 10000 },
    atoms: {
        "Sensor": Atom(locations: ["run"], initial: "run",
                       task: (period: "FAST_US", wcet: "2ms", priority: 3, cpu: "control")),
        "Filter": Atom(locations: ["run"], initial: "run",
                       task: (period: "20ms", wcet: 4000, priority: 2, cpu: "control", deadline: "15ms")),
        "Logger": Atom(locations: ["run"], initial: "run",
                       task: (period: "1s", wcet: "0.25s", cpu: "comm")),
        "Passive": Atom(locations: ["run"], initial: "run"),
    },
    components: [
        (name: "sensor", atom: "Sensor"),
        (name: "passive", atom: "Passive"),
        (name: "filter", atom: "Filter"),
        (name: "log", atom: "Logger", count: 2),
    ],
)"#;

#[test]
fn atoms_stand_for_periodic_tasks_one_per_component() {
    let system = load_str("periodic.ron", PERIODIC).expect("loads");
    let b = &system.budgets;
    assert_eq!(b.cpus, ["control", "comm"]);
    let got: Vec<String> = b
        .tasks
        .iter()
        .map(|t| {
            let name = &system.components[t.component as usize].name;
            let (p, w, c) = (t.period_us, t.wcet_us, t.cpu);
            format!("{name} {p} {w} {c} {:?} {:?}", t.priority, t.deadline_us)
        })
        .collect();
    assert_eq!(
        got,
        [
            "sensor 10000 2000 0 Some(3) None",
            "filter 20000 4000 0 Some(2) Some(15000)",
            "log[0] 1000000 250000 1 None None",
            "log[1] 1000000 250000 1 None None",
        ]
    );
    // the expansion of a model without modules keeps them, and prints them back
    let expanded = bip_lang::expand_str("periodic.ron", PERIODIC).expect("expands");
    let again = load_str("again.ron", &expanded.to_ron().expect("prints")).expect("reloads");
    assert_eq!(again.budgets, system.budgets);
}

fn bad_periodic(from: &str, to: &str) -> String {
    assert!(PERIODIC.contains(from), "{from}");
    PERIODIC.replacen(from, to, 1)
}

#[test]
fn bad_periodic_atoms() {
    assert_error(
        &bad_periodic(r#"period: "20ms""#, r#"period: 0"#),
        "a period of zero",
        "0",
    );
    assert_error(
        &bad_periodic(r#"period: "20ms""#, r#"period: -5"#),
        "a period must be a duration: -5 µs is negative",
        "-5",
    );
    assert_error(
        &bad_periodic(r#"period: "20ms""#, r#"period: "often""#),
        "a period must be a duration",
        "often",
    );
    assert_error(
        &bad_periodic(r#"wcet: 4000"#, r#"wcet: "21ms""#),
        "atom `Filter` may work 21 ms per period, more than its period (20 ms)",
        "21ms",
    );
    assert_error(
        &bad_periodic(r#"wcet: 4000"#, r#"wcet: 0"#),
        "a WCET of zero",
        "0",
    );
    assert_error(
        &bad_periodic(r#"deadline: "15ms""#, r#"deadline: "0ms""#),
        "a deadline of zero",
        "0ms",
    );
    assert_error(
        &bad_periodic(r#"cpu: "comm")"#, r#"cpu: "gpu")"#),
        "unknown CPU `gpu`",
        "gpu",
    );
    assert_error(
        &bad_periodic(r#"priority: 2"#, r#"priority: 3"#),
        "`sensor` and `filter` both have priority 3 on one CPU",
        "3",
    );
    assert_error(
        &bad_periodic(r#"priority: 2, "#, ""),
        "some tasks on this CPU have a priority, and this one has none",
        "filter",
    );
    // a family shares its atom's priority
    assert_error(
        &bad_periodic(r#"cpu: "comm")"#, r#"priority: 1, cpu: "comm")"#),
        "`log[0]` and `log[1]` both have priority 1 on one CPU",
        "1",
    );
    assert_error(
        &bad_periodic(r#"priority: 3, "#, r#"priority: 3, priority: 4, "#),
        "duplicate field named `priority`",
        "priority",
    );
}

/// A GenoM layer's tasks and the atoms' share the CPUs, and their priority rules.
#[test]
fn atoms_and_module_tasks_share_the_cpus() {
    let with_atom = |task: &str| {
        TIMED.replacen(
            "    modules: [",
            &format!(
                "    atoms: {{ \"Watch\": Atom(locations: [\"on\"], initial: \"on\", task: ({task})) }},\n    components: [(name: \"watch\", atom: \"Watch\")],\n    modules: ["
            ),
            1,
        )
    };
    let system = load_str(
        "mixed.ron",
        &with_atom(r#"period: "5ms", wcet: "1ms", priority: 9, cpu: "main""#),
    )
    .expect("loads");
    assert_eq!(system.budgets.cpus, ["main", "io"]);
    assert_eq!(system.budgets.tasks.len(), 1);
    assert_eq!(system.budgets.tasks[0].priority, Some(9));
    assert_error(
        &with_atom(r#"period: "5ms", wcet: "1ms", cpu: "main""#),
        "some tasks on this CPU have a priority, and this one has none",
        "watch",
    );
    assert_error(
        &with_atom(r#"period: "5ms", wcet: "1ms", priority: 5, cpu: "main""#),
        "`loc.fast` and `watch` both have priority 5 on one CPU",
        "5",
    );
    assert_error(
        &with_atom(r#"period: "5ms", wcet: "6ms", cpu: "io""#),
        "atom `Watch` may work 6 ms per period, more than its period (5 ms)",
        "6ms",
    );
}

#[test]
fn a_short_duration_with_its_unit_and_a_long_bare_one_are_fine() {
    for (from, to) in [
        (r#"wcet: 250"#, r#"wcet: "4us""#),
        (r#"wcet: 250"#, r#"wcet: 100"#),
    ] {
        let text = bad(from, to);
        if let Err(e) = load_str("timed.ron", &text) {
            panic!("{to}: {}", e.summary());
        }
    }
}

#[test]
fn a_common_cycle_too_long_is_reported_at_the_period_that_makes_it() {
    // 1031 and 1033 are each fine; together (both prime) they pass 2^20 ticks
    let text = bad("period: 1,", "period: 1031,").replacen("period: 5,", "period: 1033,", 1);
    assert_error(&text, "common cycle longer than", "1033");
}
