//! End-to-end tests of the GenoM layer through the `bip` command: `bip expand` prints core
//! that `bip check` reads back with the same sizes, and bad GenoM input gets a diagnostic
//! with its position and exit code 2.

use crate::common;

use crate::common::bip;
use std::path::Path;
use std::process::Output;

/// `bip check`'s summary without its first line (which names the file).
fn summary(out: &Output) -> String {
    let text = String::from_utf8_lossy(&out.stdout);
    text.lines().skip(1).collect::<Vec<_>>().join("\n")
}

#[test]
fn expand_prints_core_that_checks_with_the_same_sizes() {
    let dir = tempfile::tempdir().expect("temp dir");
    for model in [
        "robots/rover.ron",
        "robots/satellite.ron",
        "robots/tests/mini.ron",
        "robots/tests/timed.ron",
    ] {
        let out = bip(&["expand", model]);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{model}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let core = String::from_utf8(out.stdout).expect("utf-8");
        assert!(
            !core.contains("modules:") && !core.contains("constraints:"),
            "{model}"
        );
        assert!(
            core.contains("role: Time") && core.contains("role: Environment"),
            "{model}"
        );
        let path = dir.path().join("expanded.ron");
        std::fs::write(&path, &core).expect("write");
        let again = bip(&["check", path.to_str().expect("utf-8")]);
        assert_eq!(
            again.status.code(),
            Some(0),
            "{model}: {}",
            String::from_utf8_lossy(&again.stderr)
        );
        // the same, but for the time budgets, which the core has no tasks for
        let direct = bip(&["check", model]);
        let without_budgets = summary(&direct)
            .replace(
                " checked (declared, time progress, range errors, schedulability):",
                " checked (declared, time progress, range errors):",
            )
            .replace(", RangeErrors, Schedulable", ", RangeErrors")
            .replace("properties    11 checked", "properties    10 checked");
        assert_eq!(summary(&again), without_budgets, "{model}");
        // expanding the expanded model changes nothing
        let twice = bip(&["expand", path.to_str().expect("utf-8")]);
        let twice = String::from_utf8(twice.stdout).expect("utf-8");
        let body = |t: &str| t.lines().skip(1).collect::<Vec<_>>().join("\n");
        assert_eq!(body(&twice), body(&core), "{model}");
    }
}

#[test]
fn expand_names_the_generated_parts() {
    let out = bip(&["expand", "robots/rover.ron"]);
    let core = String::from_utf8_lossy(&out.stdout);
    for name in [
        "\"Activity_ndd_GoTo\": Atom(",
        "name: \"ndd_GoTo\"",
        "name: \"ndd_GoTo_request\"",
        "name: \"ndd_GoTo_move\"",
        "name: \"ndd_GoTo_move_fail\"",
        "name: \"tick\"",
        "pom.age_pose = 0",
        "trigger: \"clock.tick\"",
        "low: \"tick\"",
    ] {
        assert!(core.contains(name), "`{name}` not in the expanded rover");
    }
}

/// Writes a broken copy of rover.ron and checks `bip expand`'s diagnostic.
fn expand_bad(name: &str, replace: (&str, &str), expect: &[&str]) {
    let dir = tempfile::tempdir().expect("temp dir");
    let good =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/rover.ron"))
            .expect("rover.ron");
    assert!(good.contains(replace.0), "{name}: pattern not in rover.ron");
    let path = dir.path().join(format!("{name}.ron"));
    std::fs::write(&path, good.replacen(replace.0, replace.1, 1)).expect("write");
    for command in ["expand", "check"] {
        let out = bip(&[command, path.to_str().expect("utf-8")]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {stderr}");
        assert!(
            out.stdout.is_empty() || command == "check",
            "{name}: printed a model"
        );
        for e in expect {
            assert!(stderr.contains(e), "{name}: `{e}` not in\n{stderr}");
        }
        assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    }
}

#[test]
fn bad_genom_input_gets_positions_and_exit_2() {
    expand_bad(
        "yield",
        (
            r#"yields: ["pause::move", "ether"]"#,
            r#"yields: ["pause::mvoe", "ether"]"#,
        ),
        &[
            "yields to `mvoe`, which is not a codel state of `GoTo`",
            "yield.ron:74:49]",
            "undeclared state",
        ],
    );
    expand_bad(
        "ether",
        (
            r#"(state: "stop",  yields: ["ether"], wcet: "2ms")"#,
            r#"(state: "stop",  yields: ["pause::stop"], wcet: "2ms")"#,
        ),
        &[
            "no path from `stop` to `ether` in activity `GoTo`",
            "ether.ron:75:",
        ],
    );
    expand_bad(
        "service",
        (r#"active: ["sick.Scan"]"#, r#"active: ["sick.Scna"]"#),
        &[
            "module `sick` has no service `Scna`",
            "its services are: Scan, Stop",
        ],
    );
    expand_bad(
        "period",
        (
            r#"(name: "nav", period: 1, cpu"#,
            r#"(name: "nav", period: 0, cpu"#,
        ),
        &["task `nav` has period 0", "a period is at least 1 tick"],
    );
    expand_bad(
        "age",
        (
            r#"guard: "!active(sick.Scan) || age(pom.pose) > 2""#,
            r#"guard: "!active(sick.Scan) || age(pom.pose) > pack.level""#,
        ),
        &["may only be compared with a constant"],
    );
}

#[test]
fn expand_reads_core_models_too_and_reports_io_errors() {
    let out = bip(&["expand", "robots/philosophers.ron"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stdout).contains("\"Philosopher\": Atom("));
    let out = bip(&["expand", "no/such/model.ron"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read no/such/model.ron"));
    assert_eq!(bip(&["expand"]).status.code(), Some(2));
}

/// `bip verify` on a robot model: exit code, stdout, and the traces it saved.
fn verify(model: &str) -> (Option<i32>, String, tempfile::TempDir) {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = bip(&[
        "verify",
        model,
        "-q",
        "--trace-dir",
        dir.path().to_str().expect("utf-8"),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.stderr.is_empty() || out.status.code() != Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.code(), stdout, dir)
}

#[test]
fn the_rover_verifies() {
    let (code, stdout, _dir) = verify("robots/rover.ron");
    assert_eq!(code, Some(0), "{stdout}");
    for property in [
        "DeadlockFree",
        "no_motion_while_communicating",
        "navigation_sees",
        "navigation_knows_where_it_is",
        "battery_keeps_its_reserve",
        "power_budget",
        "drives_while_navigating",
        "waits_for_charge",
    ] {
        let line = stdout
            .lines()
            .find(|l| l.trim_start().starts_with(property))
            .unwrap_or("");
        assert!(line.contains("holds"), "{property}: {stdout}");
    }
    let schedulable = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("Schedulable"))
        .unwrap_or("");
    assert!(
        schedulable.contains("holds") && schedulable.contains("response-time analysis"),
        "{stdout}"
    );
    assert!(
        stdout.contains("result: all 11 properties hold"),
        "{stdout}"
    );
}

#[test]
fn the_rover_with_its_mistake_deadlocks_with_a_short_trace() {
    let (code, stdout, dir) = verify("robots/rover-deadlock.ron");
    assert_eq!(code, Some(1), "{stdout}");
    assert!(
        stdout.contains("result: 1 of 10 properties fail"),
        "{stdout}"
    );
    // the report says which constraint holds the navigation back
    assert!(
        stdout.contains(
            "ndd.GoTo codel start is ready after 1 tick but held by\n      navigate_with_laser (line 145): Requires(service: \"ndd.GoTo\", active: [\"sick.Scan\"])\n      fresh_pose (line 146): Fresh("
        ),
        "{stdout}"
    );
    let system = bip_lang::load_file("robots/rover-deadlock.ron").expect("loads");
    let text = std::fs::read_to_string(dir.path().join("DeadlockFree.trace.ron")).expect("a trace");
    let trace = bip_lang::trace_file::from_ron(&text).expect("reads");
    assert_eq!(trace.verdict, bip_model::Verdict::Deadlock);
    assert!(trace.steps.len() <= 5, "a short trace: {text}");
    // replayed with the one step relation, it ends in a state that the one deadlock
    // definition calls a deadlock, and that the idle excuse does not cover
    let path = trace.replay(&system).expect("replays");
    let last = path
        .last()
        .map_or(system.initial_state(), |(_, s)| s.clone());
    let mut steps = bip_model::Steps::new();
    system
        .enabled_steps(&last, &mut steps)
        .expect("no range error");
    let mut checker = bip_model::LivenessChecker::default();
    assert_eq!(
        system
            .liveness(&last, &steps, &mut checker)
            .expect("no range error"),
        bip_model::Liveness::Deadlock
    );
    let idle = system
        .genom
        .as_ref()
        .and_then(|g| g.idle.as_ref())
        .expect("the layer is open");
    assert!(!system.holds(idle, &last, "idle").expect("evaluates"));
    assert_eq!(
        trace.steps.last().map(|s| s.step.as_str()),
        Some("ndd_GoTo_request")
    );
    // through the engine: each step allowed, the deadlock reached, and why
    let saved = dir.path().join("DeadlockFree.trace.ron");
    let out = bip(&[
        "replay",
        "robots/rover-deadlock.ron",
        saved.to_str().expect("utf-8"),
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(text.contains("allowed: request accepted"), "{text}");
    assert!(text.contains("deadlock reached after"), "{text}");
    assert!(
        text.contains("waiting: ndd.GoTo codel `start`")
            && text.contains("held by navigate_with_laser (line 145): Requires("),
        "{text}"
    );
}

/// A GenoM model that states no property is checked for deadlock freedom as if it wrote
/// `DeadlockFree`: the idle layer, waiting for its operator, is not a deadlock, and a
/// request held forever still is, with either method.
#[test]
fn the_implicit_deadlock_check_excuses_the_idle_layer_as_a_written_one_does() {
    let layer = |constraints: &str| {
        format!(
            r#"System(name: "two",
    modules: [(name: "m", tasks: [(name: "t", period: 1)],
        services: [
            (name: "A", kind: Activity, task: "t", codels: [(state: "start", yields: ["ether"])]),
            (name: "B", kind: Activity, task: "t", codels: [(state: "start", yields: ["pause::start", "ether"])]),
        ])],
    constraints: [{constraints}],
)"#
        )
    };
    let dir = tempfile::tempdir().expect("temp dir");
    let idle = dir.path().join("idle.ron");
    let held = dir.path().join("held.ron");
    std::fs::write(&idle, layer("")).expect("write");
    std::fs::write(&held, layer(r#"Requires(service: "m.A", active: ["m.B"])"#)).expect("write");
    for method in ["explicit", "symbolic"] {
        let out = bip(&["verify", idle.to_str().unwrap(), "--method", method]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_eq!(out.status.code(), Some(0), "{method}: {stdout}");
        assert!(
            stdout
                .lines()
                .any(|l| l.trim_start().starts_with("DeadlockFree") && l.contains("holds")),
            "{method}: {stdout}"
        );
    }
    let out = bip(&["verify", held.to_str().unwrap(), "--method", "explicit"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(
        stdout
            .lines()
            .any(|l| l.trim_start().starts_with("DeadlockFree") && l.contains("FAILS")),
        "{stdout}"
    );
}

#[test]
fn the_satellite_verifies() {
    let (code, stdout, _dir) = verify("robots/satellite.ron");
    assert_eq!(code, Some(0), "{stdout}");
    assert!(stdout.contains("result: all 7 properties hold"), "{stdout}");
}

/// An activity requested before the one it interrupts is not starved (docs/genom.md,
/// "Interrupts"): the verifier proves its replies, and the engine runs the model.
#[test]
fn interrupts_are_sent_again_while_the_interrupter_waits() {
    let model = "robots/tests/interrupts.ron";
    let (code, stdout, _dir) = verify(model);
    assert_eq!(code, Some(0), "{stdout}");
    for property in [
        "Replies(gripper.Open)",
        "Replies(hand.Open)",
        "open_waits_for_a_stop",
    ] {
        let line = stdout
            .lines()
            .find(|l| l.trim_start().starts_with(property))
            .unwrap_or("");
        assert!(line.contains("holds"), "{property}: {stdout}");
    }
    let out = bip(&["simulate", model, "--steps", "300", "--seed", "3"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
}

/// SPIN on the exported Promela stores as many states as bip explores, for expanded GenoM
/// models (an independent check of the expansion's step relation through the exporter).
#[test]
fn spin_counts_the_same_states_on_expanded_models() {
    if !common::spin_available("spin_counts_the_same_states_on_expanded_models") {
        return;
    }
    for model in ["robots/satellite.ron", "robots/tests/mini.ron"] {
        let dir = tempfile::tempdir().expect("temp dir");
        let pml = dir.path().join("model.pml");
        let o = bip(&["export", model, "--promela", pml.to_str().expect("utf-8")]);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        let (stored, _) = common::spin(dir.path(), "model.pml", &[]);
        let ours = bip(&["verify", model, "-q", "--format", "json"]);
        let doc: serde_json::Value =
            serde_json::from_slice(&ours.stdout).expect("one JSON document");
        let states = doc["stats"]["states"]
            .as_u64()
            .expect("bip reports its states");
        assert_eq!(stored, states, "{model}");
    }
}
