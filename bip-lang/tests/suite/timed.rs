//! Timed models (`time: Exact`): their fields, what the engine's map carries of them, and
//! every bad value with its message and position.

use bip_lang::load_str;

use crate::support::errors::assert_error;

const TIMED: &str = r#"System(
    name: "ts",
    tick_ms: 1,
    time: Exact,
    cpus: [(name: "main", cores: 2, policy: FixedPriority, preemption: Job),
           (name: "io", preemption: Job)],
    modules: [
        (name: "m0", tasks: [
            (name: "t0", period: 5, delay: 1, cpu: "main", priority: 3, deadline: "4ms",
             codels: [
                (state: "start", yields: ["c1"], bcet: "1ms", wcet: "2ms"),
                (state: "c1", yields: ["pause::c1", "c2"], bcet: "0ms", wcet: "1ms"),
                (state: "c2", yields: ["pause::c1"], wcet: "1ms"),
             ]),
            (name: "t1", period: 10, cpu: "main", priority: 2),
            (name: "log", period: 20, cpu: "io", core: 0),
         ],
         services: [
            (name: "Run", kind: Activity, task: "t1",
             codels: [(state: "start", yields: ["ether"], wcet: "500us")]),
         ]),
    ],
)"#;

fn bad(from: &str, to: &str) -> String {
    assert!(TIMED.contains(from), "{from}");
    TIMED.replacen(from, to, 1)
}

/// The model with one CPU whose tasks are `t0` and `t1`, pinned to `cores`.
fn pinned(t0: &str, t1: &str) -> String {
    bad(
        r#"cpu: "main", priority: 3,"#,
        &format!(r#"cpu: "main", priority: 3, {t0},"#),
    )
    .replacen(
        r#"cpu: "main", priority: 2)"#,
        &format!(r#"cpu: "main", priority: 2, {t1})"#),
        1,
    )
}

#[test]
fn a_timed_model_loads_with_its_unit() {
    let unit = |text: &str| {
        let system = load_str("ts.ron", text).unwrap_or_else(|e| panic!("{}", e.summary()));
        let map = system.genom.expect("a GenoM layer");
        let t0 = &map.modules[0].tasks[0];
        assert_eq!((t0.period, t0.delay), (Some(5), 1));
        map.time_unit_us
    };
    // the largest that divides 1 ms (the tick, periods, delay, deadline) and 500 µs
    assert_eq!(unit(TIMED), Some(500));
    assert_eq!(
        unit(&bad("time: Exact,", r#"time: Exact(unit: "250us"),"#)),
        Some(250)
    );
    let system = load_str("p.ron", &pinned("core: 1", "core: 0")).expect("loads");
    let tasks = &system.genom.expect("a GenoM layer").modules[0].tasks;
    assert_eq!((tasks[0].core, tasks[1].core), (Some(1), Some(0)));
}

#[test]
fn the_map_carries_delays_cores_and_bcets_of_an_untimed_model() {
    let untimed = r#"System(
    name: "u",
    tick_ms: 1,
    cpus: ["main"],
    modules: [(name: "m", tasks: [(name: "t", period: 5, delay: 2)],
        services: [(name: "S", kind: Activity, task: "t",
            codels: [(state: "start", yields: ["ether"], bcet: "100us", wcet: "1ms")])])],
)"#;
    let system = load_str("u.ron", untimed).expect("loads");
    let map = system.genom.as_ref().expect("a GenoM layer");
    assert_eq!(map.time_unit_us, None);
    let task = &map.modules[0].tasks[0];
    assert_eq!((task.period, task.delay, task.core), (Some(5), 2, None));
    let codel = &map.modules[0].services[0].codels[0];
    assert_eq!((codel.bcet_us, codel.wcet_us), (Some(100), Some(1000)));
}

#[test]
fn bad_execution_times() {
    assert_error(
        &bad(r#"bcet: "1ms", wcet: "2ms""#, r#"bcet: "3ms", wcet: "2ms""#),
        "codel `start` of `m0.t0` takes at least 3 ms, more than its WCET (2 ms)",
        "3ms",
    );
    assert_error(
        &bad(
            r#"(state: "c2", yields: ["pause::c1"], wcet: "1ms")"#,
            r#"(state: "c2", yields: ["pause::c1"], bcet: "1ms")"#,
        ),
        "codel `c2` of `m0.t0` takes at least 1 ms, and has no WCET",
        "1ms",
    );
    assert_error(
        &bad(r#"bcet: "0ms""#, r#"bcet: "-1ms""#),
        "a BCET must be a duration",
        "-1ms",
    );
}

#[test]
fn bad_units() {
    assert_error(
        &bad("time: Exact,", r#"time: Exact(unit: "2ms"),"#),
        "a tick (`tick_ms`) (1 ms) is not a whole number of time units of 2 ms",
        "1",
    );
    assert_error(
        &bad("time: Exact,", r#"time: Exact(unit: "1ms"),"#),
        "the WCET of codel `start` of `m0.Run` (500 µs) is not a whole number of time units of 1 ms",
        "500us",
    );
    assert_error(
        &bad("time: Exact,", r#"time: Exact(unit: "0ms"),"#),
        "a time unit of zero",
        "0ms",
    );
    let no_tick = bad("    tick_ms: 1,\n", "");
    let errors = load_str("bad.ron", &no_tick).expect_err("no tick");
    let e = errors
        .errors()
        .iter()
        .find(|e| {
            e.message
                .contains("a timed model needs the model's `tick_ms`")
        })
        .expect("the timed model's error");
    assert_eq!(&no_tick[e.span.start..e.span.end], "Exact");
    // 2^20 units of 1 µs: a common cycle of a second and more is too long at that unit
    assert_error(
        &bad("period: 20,", "period: 1048,").replacen(r#""500us""#, r#""1us""#, 1),
        "the task periods have a common cycle longer than 1048576 time units of 1 µs",
        "1048",
    );
}

/// Every preemption loads, and a CPU named alone is one preemptive core, as in an
/// untimed model: the tasks that may lose their cores get the steps that take them.
#[test]
fn every_preemption_loads() {
    let connectors = |text: &str| {
        let system = load_str("ts.ron", text).unwrap_or_else(|e| panic!("{}", e.summary()));
        let names: Vec<&String> = system.interactions.iter().map(|i| &i.name).collect();
        (
            names.iter().filter(|n| n.ends_with("_yield")).count(),
            names.iter().filter(|n| n.contains("_preempts_")).count(),
        )
    };
    assert_eq!(connectors(TIMED), (0, 0));
    // `t0` and `t1` share one core of `main`: each may give it to the other (EDF) or `t1`
    // to `t0` (fixed priorities); on two cores, never
    let one_core = |p: &str| {
        bad("preemption: Job),\n", &format!("preemption: {p}),\n"))
            .replacen("cores: 2", "cores: 1", 1)
    };
    let two_cores = bad("preemption: Job),\n", "preemption: Preemptive),\n");
    assert_eq!(connectors(&two_cores), (0, 0));
    let codel = one_core("Codel");
    assert_eq!(connectors(&codel), (1, 0));
    let preemptive = one_core("Preemptive");
    assert_eq!(connectors(&preemptive), (0, 1));
    let edf = preemptive.replacen("policy: FixedPriority", "policy: Edf", 1);
    assert_eq!(connectors(&edf), (0, 2));
    // `log`, alone on `io`, is never preempted
    let alone = bad(r#"(name: "io", preemption: Job)"#, r#""io""#).replacen(
        r#"cpu: "io", core: 0"#,
        r#"cpu: "io""#,
        1,
    );
    assert_eq!(connectors(&alone), (0, 0));
}

/// Tasks that compete for a preemptive CPU's cores and share a lock are refused (a task
/// waiting for a lock keeps its core, a spin); on cooperative CPUs, or on separate cores,
/// they load.
#[test]
fn a_lock_shared_on_a_preemptive_cpu_is_refused() {
    let locked = bad(
        r#"(state: "c2", yields: ["pause::c1"], wcet: "1ms"),"#,
        r#"(state: "c2", yields: ["pause::c1"], wcet: "1ms", uses: ["pose"]),"#,
    )
    .replacen(
        r#"codels: [(state: "start", yields: ["ether"], wcet: "500us")]"#,
        r#"codels: [(state: "start", yields: ["ether"], wcet: "500us", uses: ["pose"])]"#,
        1,
    );
    let preemptive = locked.replacen("preemption: Job),\n", "preemption: Preemptive),\n", 1);
    assert_error(
        &preemptive,
        "tasks `m0.t0` and `m0.t1` share `m0.pose` on the preemptive CPU `main`, whose lock waits the model does not have yet",
        "start",
    );
    for fine in [
        locked.clone(),
        locked.replacen("preemption: Job),\n", "preemption: Codel),\n", 1),
        preemptive
            .replacen(r#"priority: 3,"#, r#"priority: 3, core: 0,"#, 1)
            .replacen(r#"priority: 2)"#, r#"priority: 2, core: 1)"#, 1),
    ] {
        load_str("ts.ron", &fine).unwrap_or_else(|e| panic!("{}\n{fine}", e.summary()));
    }
}

#[test]
fn bad_cores_and_scheduling() {
    assert_error(
        &pinned("core: 2", "core: 0"),
        "task `t0` is pinned to core 2 of CPU `main`, which has 2",
        "2",
    );
    assert_error(
        &pinned("core: 1", ""),
        "task `m0.t1` runs on any free core of CPU `main`, where another task is pinned to a core",
        "t1",
    );
    assert_error(
        &bad("cores: 2,", "cores: 0,"),
        "CPU `main` has 0 cores",
        "0",
    );
    assert_error(
        &bad(r#"deadline: "4ms""#, r#"deadline: "6ms""#),
        "task `m0.t0` has a deadline of 6 ms, past its period (5 ms)",
        "6ms",
    );
    assert_error(
        &bad("(name: \"t1\", period: 10,", "(name: \"t1\","),
        "task `m0.t1` is aperiodic, which a timed model does not support yet",
        "t1",
    );
}

#[test]
fn timed_fields_in_an_untimed_model() {
    let untimed = |from: &str, to: &str| bad("    time: Exact,\n", "").replacen(from, to, 1);
    assert_error(
        &untimed("", ""),
        "CPU `main` has several cores in an untimed model",
        "2",
    );
    let one_core = |from: &str, to: &str| untimed("cores: 2, ", "").replacen(from, to, 1);
    assert_error(
        &one_core("", ""),
        "CPU `main` has `preemption: Job` in an untimed model",
        "Job",
    );
    assert_error(
        &one_core("policy: FixedPriority", "policy: Edf"),
        "CPU `main` schedules by `Edf` in an untimed model",
        "Edf",
    );
    let plain = one_core(", preemption: Job)", ")").replacen(
        r#"(name: "io", preemption: Job)"#,
        r#""io""#,
        1,
    );
    assert_error(
        &plain,
        "task `log` is pinned to a core in an untimed model",
        "0",
    );
    // and the string and struct forms of a CPU mean the same
    let plain = plain.replacen(", core: 0", "", 1);
    let a = load_str("a.ron", &plain).expect("loads");
    let b = load_str(
        "b.ron",
        &plain.replacen(r#"(name: "main", policy: FixedPriority)"#, r#""main""#, 1),
    )
    .expect("loads");
    assert_eq!(a.budgets, b.budgets);
    assert_eq!(a.budgets.cpus, ["main", "io"]);
}

#[test]
fn time_in_a_model_without_genom_layer() {
    assert_error(
        r#"System(name: "core", time: Exact, atoms: {"A": (locations: ["l"], initial: "l")},
            components: [(name: "a", atom: "A")])"#,
        "`time: Exact` times a GenoM layer, and this model has none",
        "Exact",
    );
}

/// A bound counts ticks of `tick_ms`, whatever the unit: the core's bound is in units,
/// which the time steps count.
#[test]
fn a_bound_in_ticks_counts_the_units_of_its_ticks() {
    let with_response = TIMED.replacen(
        "    ],\n)",
        "    ],\n    properties: [Replies(service: \"m0.Run\", within: 3)],\n)",
        1,
    );
    assert!(with_response.contains("within: 3"));
    let bound = |text: &str| {
        let system = load_str("ts.ron", text).unwrap_or_else(|e| panic!("{}", e.summary()));
        let units = system.genom.as_ref().and_then(|g| g.time_unit_us);
        let within = system.properties.iter().find_map(|p| match p.kind {
            bip_model::PropertyKind::Response { within, .. } => within,
            _ => None,
        });
        (units, within)
    };
    // a tick of 1 ms is two units of 500 µs
    assert_eq!(bound(&with_response), (Some(500), Some(6)));
    // with the tick as the unit, a bound counts units that are ticks
    let whole = with_response
        .replacen(r#""500us""#, r#""1ms""#, 1)
        .replacen("time: Exact,", r#"time: Exact(unit: "1ms"),"#, 1);
    assert_eq!(bound(&whole), (Some(1000), Some(3)));
    // a bound in real time counts units, and takes part in deriving them
    let in_time = |k: &str| with_response.replacen("within: 3", &format!("within: {k:?}"), 1);
    assert_eq!(bound(&in_time("3ms")), (Some(500), Some(6)));
    assert_eq!(bound(&in_time("2500us")), (Some(500), Some(5)));
    assert_eq!(bound(&in_time("2750us")), (Some(250), Some(11)));
    let declared = in_time("2500us")
        .replacen(r#""500us""#, r#""1ms""#, 1)
        .replacen("time: Exact,", r#"time: Exact(unit: "1ms"),"#, 1);
    assert_error(
        &declared,
        "the bound of `Replies(m0.Run, within: 2500us)`",
        "2500us",
    );
}

#[test]
fn an_untimed_model_loads_timed_on_request() {
    let untimed = TIMED
        .replacen("    time: Exact,\n", "", 1)
        .replacen(", cores: 2, policy: FixedPriority, preemption: Job", "", 1)
        .replacen(r#"(name: "io", preemption: Job)"#, r#""io""#, 1)
        .replacen(r#"cpu: "io", core: 0"#, r#"cpu: "io""#, 1);
    let path = std::env::temp_dir().join(format!("bip-timed-{}.ron", std::process::id()));
    std::fs::write(&path, &untimed).expect("the model written");
    let unit = |system: bip_model::System| system.genom.expect("a GenoM layer").time_unit_us;
    assert_eq!(unit(bip_lang::load_file(&path).expect("loads")), None);
    let timed = bip_lang::load_file_timed(&path)
        .map(unit)
        .map_err(|e| e.summary());
    assert_eq!(timed, Ok(Some(500)));
    // a model that says `time: Exact` is loaded as written
    std::fs::write(&path, TIMED).expect("the model written");
    assert_eq!(
        unit(bip_lang::load_file_timed(&path).expect("loads")),
        Some(500)
    );
    std::fs::remove_file(&path).expect("removed");
}
