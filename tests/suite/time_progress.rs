//! `bip verify` on the timelocks a fuzzer found: an urgent self-loop above the tick, and a
//! `Time` connector that never fires. The text and JSON reports show `TimeProgress`
//! failing with its trace and why, the liveness properties failing beside it, and exit 1.

use crate::common::bip;

/// A worker that spins in `wait`; with `urgent`, `spin` is above the tick.
fn spinning(dir: &std::path::Path, urgent: bool) -> String {
    let priority = if urgent {
        r#"(low: "tick", high: "spin")"#
    } else {
        ""
    };
    let text = format!(
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
    );
    let p = dir.join(if urgent { "urgent.ron" } else { "lazy.ron" });
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

#[test]
fn a_timelock_fails_time_progress_and_the_liveness_properties_it_would_excuse() {
    let dir = tempfile::tempdir().unwrap();
    let model = spinning(dir.path(), true);
    let o = bip(&["verify", &model, "-j", "1"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{text}");
    assert!(text.contains("  DeadlockFree  holds"), "{text}");
    assert!(
        text.contains("  TimeProgress  FAILS         [explicit] time stops after 1 step: no run from there lets time pass (a cycle of 1 step without a tick repeats forever); `tick` is below `spin` (priority `tick < spin`), which can fire"),
        "{text}"
    );
    for p in ["answered", "in_three"] {
        assert!(
            text.lines().any(|l| l.starts_with(&format!("  {p} "))
                && l.contains("FAILS")
                && l.contains("time cannot pass on it")),
            "{p}: {text}"
        );
    }
    assert!(
        text.contains("TimeProgress (time progress), counterexample")
            && text.contains("the cycle: the steps below repeat forever"),
        "{text}"
    );
    assert!(text.contains("result: 3 of 5 properties fail"), "{text}");

    let o = bip(&["verify", &model, "-j", "1", "--format", "json"]);
    assert_eq!(o.status.code(), Some(1));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let props = json["properties"].as_array().unwrap();
    let names: Vec<&str> = props.iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "DeadlockFree",
            "answered",
            "in_three",
            "TimeProgress",
            "RangeErrors"
        ]
    );
    let tp = &props[3];
    assert_eq!(tp["kind"], "time_progress");
    assert_eq!(tp["verdict"], "fails");
    assert_eq!(tp["trace"]["loop_start"], 1);
    assert_eq!(tp["trace"]["verdict"]["Violation"], "TimeProgress");
}

#[test]
fn without_a_timelock_time_progress_holds_and_a_lazy_reply_fails_on_its_own() {
    let dir = tempfile::tempdir().unwrap();
    let o = bip(&["verify", &spinning(dir.path(), false), "-j", "1"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{text}");
    assert!(text.contains("  TimeProgress  holds"), "{text}");
    let answered = text.lines().find(|l| l.starts_with("  answered ")).unwrap();
    assert!(
        answered.contains("FAILS") && !answered.contains("time cannot pass"),
        "{text}"
    );
}

#[test]
fn a_model_without_time_has_no_time_progress_result() {
    let o = bip(&[
        "verify",
        &format!("{}/robots/philosophers.ron", env!("CARGO_MANIFEST_DIR")),
        "-j",
        "1",
    ]);
    assert!(!String::from_utf8_lossy(&o.stdout).contains("TimeProgress"));
}

#[test]
fn bip_replay_confirms_the_timelock_and_the_lasso_it_makes() {
    let dir = tempfile::tempdir().unwrap();
    let model = spinning(dir.path(), true);
    let traces = dir.path().join("traces");
    let traces = traces.to_str().unwrap();
    let o = bip(&[
        "verify",
        &model,
        "-j",
        "1",
        "--trace-dir",
        traces,
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let o = bip(&[
        "replay",
        &model,
        &format!("{traces}/TimeProgress.trace.ron"),
    ]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{text}");
    assert!(
        text.contains("time stops: after 1 step, the cycle of steps 2-2 repeats forever")
            && text.contains("result: TimeProgress fails"),
        "{text}"
    );
    let o = bip(&["replay", &model, &format!("{traces}/answered.trace.ron")]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{text}");
    assert!(text.contains("result: answered fails"), "{text}");
}
