//! `bip verify`'s worst response of each response property in a timed layer: the figure
//! in the text and the JSON report, and the run that waits it saved as a trace.

use std::process::Command;

/// `robots/tests/timed.ron` with two services' replies: `Log` (task `log`, period 8 ms, 1
/// to 2 ms on a core it never waits for) replies at most 10 ms after its request, a
/// request just after a release waiting for the next one; `Plan`, which a new request
/// interrupts, can be interrupted for ever.
fn fixture() -> String {
    include_str!("../../robots/tests/timed.ron").replacen(
        "    ],\n)",
        "    ],\n    properties: [Replies(service: \"nav.Log\"), Replies(service: \"nav.Plan\")],\n)",
        1,
    )
}

#[test]
fn a_services_worst_response_is_printed_saved_and_in_json() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("timed.ron");
    std::fs::write(&model, fixture()).unwrap();
    let traces = dir.path().join("traces");
    let run = |extra: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_bip"))
            .args(["verify", model.to_str().unwrap(), "--method", "explicit"])
            .args(extra)
            .output()
            .unwrap();
        // Plan's replies fail
        assert_eq!(
            o.status.code(),
            Some(1),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let text = run(&["--trace-dir", traces.to_str().unwrap()]);
    let line = |name: &str| {
        text.lines()
            .find(|l| l.trim_start().starts_with(name))
            .unwrap_or_else(|| panic!("no line `{name}`:\n{text}"))
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
    };
    assert!(
        line("Replies(nav.Log) worst response")
            .starts_with("Replies(nav.Log) worst response holds 10 ms, reached after"),
        "{text}"
    );
    assert!(
        line("Replies(nav.Plan) worst response")
            .starts_with("Replies(nav.Plan) worst response FAILS unbounded"),
        "{text}"
    );
    // the run that waits longest, saved, replays, and spans the 10 ms of the wait: the
    // request is its first step, the reply its last
    let system = bip_lang::load_file(&model).unwrap();
    let saved = std::fs::read_to_string(traces.join("Replies_nav_Log__worst_response.trace.ron"))
        .unwrap_or_else(|e| panic!("{e}:\n{text}"));
    let trace = bip_lang::trace_file::from_ron(&saved).unwrap();
    assert_eq!(
        trace.verdict,
        bip_model::Verdict::Witness("Replies(nav.Log) worst response".into())
    );
    let path = trace.replay(&system).expect("the saved run replays");
    let mut before = system.initial_state();
    let mut units = 0;
    for (step, after) in &path {
        units += system.time_advance(&before, step.as_step()).unwrap();
        before = after.clone();
    }
    let unit_us = system.genom.as_ref().and_then(|g| g.time_unit_us).unwrap();
    assert_eq!(units * unit_us, 10_000);
    assert_eq!(
        trace.steps.first().map(|s| s.step.as_str()),
        Some("nav_Log_request")
    );

    let json: serde_json::Value = serde_json::from_str(&run(&["--format", "json"])).unwrap();
    let row = |name: &str| {
        json["properties"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == name)
            .unwrap_or_else(|| panic!("no `{name}` in {json}"))
            .clone()
    };
    let log = row("Replies(nav.Log) worst response");
    assert_eq!(
        (
            &log["kind"],
            &log["verdict"],
            &log["worst_us"],
            &log["note"]
        ),
        (
            &"worst_response".into(),
            &"holds".into(),
            &10_000.into(),
            &"10 ms".into()
        )
    );
    assert_eq!(
        log["witness"]["steps"].as_array().map(Vec::len),
        Some(trace.steps.len())
    );
    let plan = row("Replies(nav.Plan) worst response");
    assert_eq!(plan["verdict"], "fails");
    assert!(plan["worst_us"].is_null(), "{plan}");
}
