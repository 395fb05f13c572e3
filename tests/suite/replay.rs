//! `bip replay` on the traces `bip verify --trace-dir` and `bip simulate --trace` write: each
//! replays to its verdict (exit 1 for a failure or a witness, 0 for a plain recording),
//! where range errors, properties that cannot be evaluated and triggers left waiting end
//! the trace. tests/suite/agreement.rs checks the same on random models.

use std::path::Path;

use crate::common::bip;

/// A model of one atom `a`: `go` takes it from `l0` to `l1` and sets `x` to 0; from `l1`,
/// `p` and `q` are guarded by `l1_guard`; `extra` goes into the system's fields
/// (properties, priorities).
fn model(
    dir: &Path,
    name: &str,
    init_x: i64,
    l0_guard: &str,
    l1_guard: &str,
    extra: &str,
) -> String {
    let text = format!(
        r#"System(
            name: "{name}",
            atoms: {{ "A": Atom(locations: ["l0", "l1"], initial: "l0",
                vars: [(name: "x", ty: Int(0, 3), init: {init_x})], ports: ["go", "p", "q"],
                transitions: [
                    (from: "l0", port: "go", to: "l1", guard: "{l0_guard}", action: "x = 0"),
                    (from: "l1", port: "p", to: "l1", guard: "{l1_guard}"),
                    (from: "l1", port: "q", to: "l1", guard: "{l1_guard}"),
                ]) }},
            components: [(name: "a", atom: "A")],
            connectors: [
                (name: "go", ports: ["a.go"]),
                (name: "p", ports: ["a.p"]),
                (name: "q", ports: ["a.q"]),
            ],
            {extra}
        )"#
    );
    let path = dir.join(format!("{name}.ron"));
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

fn out(o: &std::process::Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Verifies `model` saving its traces, replays each, and returns the replays' outputs
/// (each must exit 1: the failure or the witness shows).
fn verify_and_replay(model: &str, dir: &Path) -> Vec<String> {
    let traces = dir.join("traces");
    std::fs::create_dir_all(&traces).unwrap();
    let o = bip(&[
        "verify",
        model,
        "--trace-dir",
        traces.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", out(&o));
    let mut replays = Vec::new();
    for entry in std::fs::read_dir(&traces).unwrap() {
        let path = entry.unwrap().path();
        if !path.to_string_lossy().ends_with(".trace.ron") {
            continue;
        }
        let r = bip(&["replay", model, path.to_str().unwrap()]);
        assert_eq!(
            r.status.code(),
            Some(1),
            "{}: {}\nverify said:\n{}",
            path.display(),
            out(&r),
            out(&o)
        );
        replays.push(out(&r));
    }
    assert!(!replays.is_empty(), "verify saved no trace:\n{}", out(&o));
    replays
}

/// Simulates `model`, saving the trace; the simulation exits `code`, and the trace
/// replays to the same verdict (exit 1 for a failure, 0 for a recording).
fn simulate_and_replay(model: &str, dir: &Path, code: i32) -> String {
    let trace = dir.join("sim.trace.ron");
    let o = bip(&[
        "simulate",
        model,
        "--steps",
        "20",
        "--trace",
        trace.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(code), "{}", out(&o));
    let r = bip(&["replay", model, trace.to_str().unwrap()]);
    assert_eq!(
        r.status.code(),
        Some(code),
        "{}\nsimulate said:\n{}",
        out(&r),
        out(&o)
    );
    out(&o)
}

/// Verify's first trace of `model` replays to a range error from its last state, and
/// simulate finds it too (exit 1, a finding about the model), saying `simulated`.
fn range_error_found_alike(model: &str, dir: &Path, simulated: &str) {
    let replays = verify_and_replay(model, dir);
    assert!(
        replays[0].contains("range error from the last state"),
        "{}",
        replays[0]
    );
    assert!(!replays[0].contains("NOT ALLOWED"), "{}", replays[0]);
    let sim = simulate_and_replay(model, dir, 1);
    assert!(sim.contains(simulated), "{sim}");
}

#[test]
fn a_range_error_in_a_guard_of_the_last_state_replays() {
    let dir = tempfile::tempdir().unwrap();
    let m = model(dir.path(), "guard", 1, "true", "1 / x > 0", "");
    range_error_found_alike(&m, dir.path(), "RANGE ERROR after step 1");
}

#[test]
fn a_range_error_in_the_initial_state_replays_and_simulates_as_a_finding() {
    let dir = tempfile::tempdir().unwrap();
    let m = model(dir.path(), "initial", 0, "1 / x > 0", "true", "");
    range_error_found_alike(&m, dir.path(), "RANGE ERROR after step 0");
}

#[test]
fn a_range_error_in_a_priority_condition_of_the_last_state_replays() {
    let dir = tempfile::tempdir().unwrap();
    let m = model(
        dir.path(),
        "when",
        1,
        "true",
        "true",
        r#"priorities: [(low: "p", high: "q", when: "1 / a.x > 0")],"#,
    );
    verify_and_replay(&m, dir.path());
    simulate_and_replay(&m, dir.path(), 1);
}

#[test]
fn properties_that_cannot_be_evaluated_at_the_end_replay() {
    for (name, property) in [
        (
            "invariant",
            r#"Invariant(name: "inv", expr: "a@l0 || 1 / a.x > 0")"#,
        ),
        (
            "reachable",
            r#"Reachable(name: "reach", expr: "a@l1 && 1 / a.x > 5")"#,
        ),
        (
            "leads_to",
            r#"LeadsTo(name: "resp", from: "a@l1 && 1 / a.x > 0", to: "a@l0")"#,
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let extra = format!("properties: [{property}],");
        let m = model(dir.path(), name, 1, "true", "true", &extra);
        let replays = verify_and_replay(&m, dir.path());
        assert!(
            replays
                .iter()
                .any(|r| r.contains("range error from the last state")),
            "{name}: {replays:?}"
        );
    }
    // the invariant is checked by simulate too
    let dir = tempfile::tempdir().unwrap();
    let m = model(
        dir.path(),
        "simulated",
        1,
        "true",
        "true",
        r#"properties: [Invariant(name: "inv", expr: "a@l0 || 1 / a.x > 0")],"#,
    );
    simulate_and_replay(&m, dir.path(), 1);
}

#[test]
fn a_terminal_condition_that_cannot_be_evaluated_at_the_end_replays() {
    let dir = tempfile::tempdir().unwrap();
    // `l1` has no step: a deadlock, which the terminal condition cannot judge
    let m = model(
        dir.path(),
        "terminal",
        1,
        "true",
        "false",
        r#"properties: [DeadlockFree(terminal: "1 / a.x > 0")],"#,
    );
    range_error_found_alike(&m, dir.path(), "RANGE ERROR");
}

#[test]
fn a_leads_to_whose_state_trigger_holds_at_the_end_replays() {
    let dir = tempfile::tempdir().unwrap();
    let m = model(
        dir.path(),
        "waiting",
        1,
        "true",
        "false",
        r#"properties: [LeadsTo(name: "back", from: "a@l1", to: "a@l0")],"#,
    );
    let replays = verify_and_replay(&m, dir.path());
    assert!(replays[0].contains("result: back fails"), "{}", replays[0]);
}

#[test]
fn a_property_with_a_long_name_keeps_its_verdict_and_saves_its_trace() {
    let dir = tempfile::tempdir().unwrap();
    let long = "n".repeat(300);
    let extra = format!(r#"properties: [Invariant(name: "{long}", expr: "a@l0")],"#);
    let m = model(dir.path(), "long", 1, "true", "true", &extra);
    let replays = verify_and_replay(&m, dir.path());
    assert!(
        replays[0].contains(&format!("result: {long} fails")),
        "{}",
        replays[0]
    );
    let names: Vec<String> = std::fs::read_dir(dir.path().join("traces"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 2, "the trace and its chart: {names:?}");
    assert!(names.iter().all(|n| n.len() < 100), "{names:?}");
}

/// An activity and a function with two `Guard`s, `first` then `second`; `m.x` is 0.
fn guarded(dir: &Path, first: &str, second: &str) -> String {
    let text = format!(
        r#"System(
            name: "guarded",
            modules: [(
                name: "m",
                ids: [(name: "x", ty: Int(0, 3), init: 0)],
                tasks: [(name: "t", period: 1)],
                services: [
                    (name: "Run", kind: Activity, task: "t",
                     codels: [(state: "start", yields: ["ether"])]),
                    (name: "Get", kind: Function),
                ],
            )],
            constraints: [
                Guard(service: "m.Run", when: "{first}"),
                Guard(service: "m.Run", when: "{second}"),
                Guard(service: "m.Get", when: "{first}"),
                Guard(service: "m.Get", when: "{second}"),
            ],
        )"#
    );
    let path = dir.join("guarded.ron");
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

#[test]
fn guards_are_evaluated_in_one_order_by_verify_and_simulate() {
    let dir = tempfile::tempdir().unwrap();
    // `false` refuses first: `1 / m.x` is never evaluated, by the verifier nor the engine
    let m = guarded(dir.path(), "false", "1 / m.x == 0");
    let o = bip(&["verify", &m, "-q", "--method", "explicit"]);
    assert!(out(&o).contains("RangeErrors   holds"), "{}", out(&o));
    let sim = simulate_and_replay(&m, dir.path(), 0);
    assert!(sim.contains("refused"), "{sim}");
    assert!(!sim.contains("RANGE ERROR"), "{sim}");
    // the other way round, `1 / m.x` is evaluated first: a range error for both
    let m = guarded(dir.path(), "1 / m.x == 0", "false");
    let replays = verify_and_replay(&m, dir.path());
    assert!(
        replays
            .iter()
            .any(|r| r.contains("range error from the last state")),
        "{replays:?}"
    );
    let sim = simulate_and_replay(&m, dir.path(), 1);
    assert!(sim.contains("RANGE ERROR"), "{sim}");
}

/// The connected fixture's deadlock (the estimator fails, the controller's codel waits for
/// a fresh frame on its in port for ever) and its witness replay through the engine as
/// the verifier found them: the engine's held codel reads the same age.
#[test]
fn traces_of_a_layer_wired_by_connections_replay() {
    let dir = tempfile::tempdir().unwrap();
    let replays = verify_and_replay("robots/tests/connections.ron", dir.path());
    assert_eq!(replays.len(), 2, "{replays:?}");
    assert!(
        replays.iter().any(|r| r.contains("deadlock")),
        "{replays:?}"
    );
    assert!(
        replays.iter().any(|r| r.contains("controls")),
        "{replays:?}"
    );
}
