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
    assert_eq!(map.cpus, ["main", "io"]);
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
