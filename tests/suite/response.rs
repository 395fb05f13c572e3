//! End-to-end tests of response properties: a lasso counterexample printed with its cycle
//! marked, saved with its loop start and replayed through the engine; a trace whose cycle
//! does not close refused; a truncated run inconclusive (exit 3); a vacuous property
//! warned about; late responses in a simulation and a replay; the rover's mission answered
//! in time, and not without its operator.

use crate::common::bip;

use std::path::Path;

/// Three philosophers, the last taking its right fork first: nobody deadlocks, but
/// philosopher 0 may starve.
fn philosophers(dir: &Path) -> String {
    let text = std::fs::read_to_string(format!(
        "{}/robots/philosophers-asymmetric.ron",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .replace("\"N\": 5", "\"N\": 3");
    let at = text.rfind("properties: [").unwrap();
    let text = format!(
        r#"{}properties: [
        LeadsTo(name: "phil0_eats", from: "phil[0]@hungry", to: "phil[0]@eating"),
        LeadsTo(name: "someone_eats", from: "exists i in 0..N: phil[i]@hungry", to: "exists i in 0..N: phil[i]@eating"),
        LeadsTo(name: "nobody_eats_twice", from: "phil[0]@eating && phil[1]@eating", to: "true"),
    ],
)
"#,
        &text[..at]
    );
    let path = dir.join("starving.ron");
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

fn out(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn a_lasso_is_printed_saved_and_replayed_with_its_cycle() {
    let dir = tempfile::tempdir().unwrap();
    let model = philosophers(dir.path());
    let traces = dir.path().join("traces");
    let o = bip(&["verify", &model, "--trace-dir", traces.to_str().unwrap()]);
    let text = out(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    assert!(
        text.contains("phil0_eats") && text.contains("FAILS"),
        "{text}"
    );
    assert!(
        text.contains("┌ the cycle: the steps below repeat forever"),
        "{text}"
    );
    assert!(text.contains("└ back to the state after step"), "{text}");
    let file = traces.join("phil0_eats.trace.ron");
    let saved = std::fs::read_to_string(&file).unwrap();
    assert!(saved.contains("loop_start: "), "{saved}");
    // the chart beside it and `bip trace show` mark the same cycle
    let chart = std::fs::read_to_string(traces.join("phil0_eats.svg")).unwrap();
    assert!(
        chart.contains(r#"<g class="loop"><title>the run repeats from here</title>"#),
        "{chart}"
    );
    let shown = out(&bip(&["trace", "show", &model, file.to_str().unwrap()]));
    let stem: usize = saved
        .split("loop_start: ")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .and_then(|n| n.trim().parse().ok())
        .unwrap();
    let lines: Vec<&str> = shown.lines().collect();
    let at = lines
        .iter()
        .position(|l| l.contains("┌ the cycle: the steps below repeat forever"))
        .unwrap_or_else(|| panic!("{shown}"));
    assert!(
        lines[at + 1]
            .trim_start()
            .starts_with(&format!("{} ", stem + 1)),
        "{shown}"
    );
    let o = bip(&["replay", &model, file.to_str().unwrap()]);
    let text = out(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    assert!(text.contains("forever"), "{text}");
    assert!(text.contains("result: phil0_eats fails"), "{text}");
    // the engine's replay names the cycle's steps, the first being step `stem + 1`
    let first = lines[at + 1].split_whitespace().nth(1).unwrap();
    assert!(text.contains(&format!("forever ({first}")), "{text}");
    // a cycle that does not close is not a lasso of the model
    let k: usize = saved
        .split("loop_start: ")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .and_then(|n| n.trim().parse().ok())
        .unwrap();
    let moved = saved.replace(
        &format!("loop_start: {k},"),
        &format!("loop_start: {},", k + 1),
    );
    assert_ne!(moved, saved);
    let bad = dir.path().join("moved.trace.ron");
    std::fs::write(&bad, moved).unwrap();
    let o = bip(&["replay", &model, bad.to_str().unwrap()]);
    let text = out(&o);
    assert_eq!(o.status.code(), Some(2), "{text}");
    assert!(
        text.contains("does not return to the state where the loop starts"),
        "{text}"
    );
}

#[test]
fn a_truncated_run_is_inconclusive_and_a_vacuous_property_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let model = philosophers(dir.path());
    let o = bip(&[
        "verify",
        &model,
        "--method",
        "explicit",
        "--max-states",
        "4",
    ]);
    let text = out(&o);
    assert_eq!(o.status.code(), Some(3), "{text}");
    assert!(text.contains("inconclusive"), "{text}");
    assert!(!text.contains("FAILS"), "{text}");
    let o = bip(&["verify", &model]);
    let text = out(&o);
    assert!(
        text.contains("warning: nobody_eats_twice holds vacuously: its trigger never happens"),
        "{text}"
    );
}

#[test]
fn a_simulation_reports_the_bounded_responses_that_are_late() {
    let model = format!("{}/robots/served.ron", env!("CARGO_MANIFEST_DIR"));
    let o = bip(&["simulate", &model, "--steps", "40", "--seed", "3"]);
    let text = out(&o);
    // a late response is reported, not a failed check of the simulation
    assert_eq!(o.status.code(), Some(0), "{text}");
    assert!(
        text.contains("2 bounded response properties watched at every step:"),
        "{text}"
    );
    let late: Vec<&str> = text.lines().filter(|l| l.contains("no response")).collect();
    assert!(!late.is_empty(), "{text}");
    for l in &late {
        assert!(
            l.contains(
                "answered_in_one: no response 2 ticks after its trigger, past its bound of 1"
            ),
            "{text}"
        );
    }
    assert!(!text.contains("answered_in_two:"), "{text}");
    assert!(
        text.contains(&format!("watched at every step: {} late", late.len())),
        "{text}"
    );
}

#[test]
fn a_bound_passed_replays_with_the_engine_monitor_reporting_it() {
    let dir = tempfile::tempdir().unwrap();
    let model = format!("{}/robots/served.ron", env!("CARGO_MANIFEST_DIR"));
    let traces = dir.path().join("traces");
    let o = bip(&["verify", &model, "--trace-dir", traces.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", out(&o));
    let file = traces.join("answered_in_one.trace.ron");
    let o = bip(&["replay", &model, file.to_str().unwrap()]);
    let text = out(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    // the counterexample's last step is the tick past the bound, and the engine sees it
    let n = text.lines().filter(|l| l.contains("allowed:")).count();
    assert!(
        text.contains(&format!(
            "after step {n}, the engine's monitor: response late: answered_in_one: no response 2 ticks after its trigger, past its bound of 1"
        )),
        "{text}"
    );
    assert_eq!(text.matches("the engine's monitor").count(), 1, "{text}");
    assert!(text.contains("result: answered_in_one fails"), "{text}");
}

/// robots/rover-mission.ron with only the GoTo replies among its properties (the verdicts
/// the README shows), and with its operator's bound on goals or without it.
fn rover_mission(dir: &Path, bounded_goals: bool) -> String {
    let text = std::fs::read_to_string(format!(
        "{}/robots/rover-mission.ron",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let operator =
        "        (name: \"ndd_GoTo_request\", ports: [\"operator.goal\"], role: Environment),\n";
    assert!(text.contains(operator), "the operator sends the goals");
    let text = if bounded_goals {
        text
    } else {
        text.replace(operator, "")
    };
    let at = text.rfind("properties: [").unwrap();
    let text = format!(
        r#"{}properties: [
        Replies(service: "ndd.GoTo"),
        Replies(service: "ndd.GoTo", within: 8),
        Replies(name: "goto_in_7", service: "ndd.GoTo", within: 7),
    ],
)
"#,
        &text[..at]
    );
    let path = dir.join(if bounded_goals {
        "mission.ron"
    } else {
        "unbounded.ron"
    });
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

#[test]
fn the_rover_mission_gets_its_replies_in_time_and_not_without_its_operator() {
    let dir = tempfile::tempdir().unwrap();
    let caps = [
        "--method",
        "explicit",
        "--max-states",
        "8000000",
        "--max-memory",
        "3G",
    ];
    let model = rover_mission(dir.path(), true);
    let o = bip(&[&["verify", &model][..], &caps].concat());
    let text = out(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    let verdict = |name: &str| {
        text.lines()
            .find(|l| l.trim_start().starts_with(name))
            .unwrap_or_else(|| panic!("no {name} in {text}"))
            .to_string()
    };
    assert!(verdict("Replies(ndd.GoTo) ").contains("holds"), "{text}");
    assert!(
        verdict("Replies(ndd.GoTo, within: 8)").contains("holds"),
        "{text}"
    );
    let tight = verdict("goto_in_7");
    assert!(
        tight.contains("FAILS") && tight.contains("the response does not come within 7 ticks"),
        "{text}"
    );
    assert!(text.contains("5813697 states"), "{text}");
    // without the operator, goals come for ever: the infinite-interrupt lasso
    let model = rover_mission(dir.path(), false);
    let o = bip(&[&["verify", &model][..], &caps].concat());
    let text = out(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    let goto = text
        .lines()
        .find(|l| l.trim_start().starts_with("Replies(ndd.GoTo) "))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(
        goto.contains("FAILS") && goto.contains("a cycle of 8 steps repeats forever"),
        "{text}"
    );
    let cycle = text
        .split("┌ the cycle: the steps below repeat forever")
        .nth(1)
        .and_then(|rest| rest.split("└ back to").next())
        .unwrap_or_else(|| panic!("{text}"));
    assert!(
        cycle.contains("ndd_GoTo_start") && cycle.contains("ndd_GoTo_request"),
        "a new goal interrupts the running one in the cycle: {text}"
    );
}

/// The satellite with response properties on its downlink, held by the `Guard` on the
/// ground station's visibility, and its camera, which pauses for its task's period.
fn held_satellite(dir: &Path) -> String {
    let text = std::fs::read_to_string(format!(
        "{}/robots/satellite.ron",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let at = text.rfind("properties: [").unwrap();
    let text = format!(
        r#"{}properties: [
        Replies(name: "sent_in_two", service: "downlink.Transmit", within: 2),
        Replies(name: "sent", service: "downlink.Transmit"),
        Replies(name: "imaged_in_one", service: "camera.Image", within: 1),
    ],
)
"#,
        &text[..at]
    );
    let path = dir.join("held.ron");
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

/// A response that does not come is explained as a deadlock is, where it fails to come:
/// the constraint (with its line) that holds the waiting service's codel, at the state
/// the bound is reached in and where the lasso's cycle starts, or that the codel only
/// waits for its task's period; in the text report, the JSON report and the chart.
#[test]
fn a_late_or_missing_reply_says_what_holds_the_service() {
    let dir = tempfile::tempdir().unwrap();
    let model = held_satellite(dir.path());
    let traces = dir.path().join("traces");
    let o = bip(&["verify", &model, "--trace-dir", traces.to_str().unwrap()]);
    let text = out(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    let guard = r#"line 72: Guard(service: "downlink.Transmit", when: "orbit@visible")"#;
    let why = |name: &str| {
        let at = text
            .find(&format!("\n{name} ("))
            .unwrap_or_else(|| panic!("{text}"));
        let rest = &text[at..];
        let end = rest[1..].find("\n\n").map_or(rest.len(), |e| e + 1);
        rest[..end].to_string()
    };
    let sent_in_two = why("sent_in_two");
    assert!(
        sent_in_two.contains("  why:\n    when the bound is reached (after step 14):\n      downlink.Transmit codel start is ready but held by\n        ")
            && sent_in_two.contains(guard),
        "{sent_in_two}"
    );
    let sent = why("sent");
    assert!(
        sent.contains("where the cycle starts (after step 14):") && sent.contains(guard),
        "{sent}"
    );
    let imaged = why("imaged_in_one");
    assert!(
        imaged.contains(
            "camera.Image codel expose is ready after 1 tick (its task's period); nothing holds it"
        ),
        "{imaged}"
    );
    let chart = std::fs::read_to_string(traces.join("sent.svg")).unwrap();
    assert!(
        chart.contains("where the cycle starts (after step 14):"),
        "{chart}"
    );
    let o = bip(&["verify", &model, "--format", "json"]);
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let props = json["properties"].as_array().unwrap();
    let sent = props.iter().find(|p| p["name"] == "sent").unwrap();
    let lines: Vec<&str> = sent["why"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_str().unwrap())
        .collect();
    assert_eq!(
        lines,
        [
            "where the cycle starts (after step 14):",
            "downlink.Transmit codel send is ready after 2 ticks but held by",
            guard
        ]
    );
}

/// A clock whose `k` goes 0, 1, 2, 0, … on its ticks, with a bounded response whose
/// response divides by zero on the tick into `k == 0` or one whose trigger divides by zero
/// where the response holds: both methods fail it with the same trace, and `bip replay`
/// confirms its range error. (One model each: the engine's monitor stops a replay at the
/// first range error of any bounded response property.)
#[test]
fn a_range_error_in_a_response_property_is_a_counterexample_that_replays() {
    let dir = tempfile::tempdir().unwrap();
    for (name, trigger, response, steps) in [
        ("on_step", "fires(never)", "changes(true, 1 / clk.k > 0)", 2),
        ("in_state", "1 / (clk.k - 1) > 0", "clk.k == 1", 1),
    ] {
        let model = dir.path().join(format!("{name}.ron"));
        std::fs::write(
            &model,
            format!(
                r#"System(
    name: "cycling",
    atoms: {{
        "Clk": Atom(
            locations: ["on"],
            initial: "on",
            ports: ["tick", "never"],
            vars: [(name: "k", ty: Int(0, 2))],
            transitions: [
                (from: "on", port: "tick", to: "on", action: "k = (k + 1) % 3"),
                (from: "on", port: "never", to: "on", guard: "false"),
            ],
        ),
    }},
    components: [(name: "clk", atom: "Clk")],
    connectors: [
        (name: "tick", ports: ["clk.tick"], role: Time),
        (name: "never", ports: ["clk.never"]),
    ],
    properties: [
        Response(name: "{name}", trigger: "{trigger}", response: "{response}", within: 0),
    ],
)"#
            ),
        )
        .unwrap();
        let model = model.to_str().unwrap();
        for method in ["explicit", "symbolic"] {
            let traces = dir.path().join(format!("{name}-{method}"));
            let o = bip(&[
                "verify",
                model,
                "--method",
                method,
                "--trace-dir",
                traces.to_str().unwrap(),
            ]);
            let text = out(&o);
            assert_eq!(o.status.code(), Some(1), "{text}");
            let s = if steps == 1 { "" } else { "s" };
            assert!(
                text.contains(&format!(
                    "{name} (bounded response), counterexample: range error: division by zero in the property {name} after {steps} step{s}"
                )),
                "{method}: {text}"
            );
            let file = traces.join(format!("{name}.trace.ron"));
            let o = bip(&["replay", model, file.to_str().unwrap()]);
            let replayed = out(&o);
            assert_eq!(o.status.code(), Some(1), "{method} {name}: {replayed}");
            assert!(
                replayed.contains(&format!(
                    "range error from the last state: division by zero in the property {name}"
                )),
                "{method} {name}: {replayed}"
            );
        }
    }
}

/// `text` with a bounded and an unbounded response from a component's location (a state
/// trigger) to the steps of a connector, which may enter it, chosen by `seed`.
fn with_entered(sys: &bip_model::System, text: &str, seed: u64) -> String {
    let n = sys.connectors.len() as u64;
    if n == 0 {
        return text.to_string();
    }
    let b = &sys.connectors[(seed / 7 % n) as usize].name;
    let comp = &sys.components[(seed / 11 % sys.components.len() as u64) as usize];
    let locations = &sys.atoms[comp.atom as usize].locations;
    let at = format!(
        "{}@{}",
        comp.name,
        locations[(seed / 13 % locations.len() as u64) as usize]
    );
    let mut property =
        format!(r#"LeadsTo(name: "entered_leads", from: "{at}", to: "fires({b})"),"#);
    if sys.has_time() {
        property += &format!(
            r#"Response(name: "entered", trigger: "{at}", response: "fires({b})", within: {}),"#,
            seed / 31 % 2
        );
    }
    match text.rfind("properties: [") {
        Some(at) => {
            let at = at + "properties: [".len();
            format!("{}{property}{}", &text[..at], &text[at..])
        }
        None => text.to_string(),
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 48, ..Default::default() })]

    /// On random systems with response properties (a random condition to another, a
    /// location to a connector's steps), every counterexample the verifier writes replays
    /// through the engine (`bip replay`) to its verdict, and a bounded response that
    /// holds implies its unbounded form.
    #[test]
    fn every_response_counterexample_replays_to_its_verdict(seed in proptest::prelude::any::<u64>(), roles in proptest::prelude::any::<bool>()) {
        use bip_verifier::{verify, Method, Options, PropertyVerdict};
        use proptest::prelude::*;
        let opts = bip_random_systems::Options {
            responses: true,
            ..bip_random_systems::Options::verifier(roles)
        };
        let text = bip_random_systems::generate_with(seed, &opts).to_ron();
        let sys = bip_lang::load_str("random.ron", &text)
            .map_err(|e| TestCaseError::fail(format!("{}\n{text}", e.summary())))?;
        let text = with_entered(&sys, &text, seed);
        let sys = bip_lang::load_str("random.ron", &text)
            .map_err(|e| TestCaseError::fail(format!("{}\n{text}", e.summary())))?;
        let options = Options { jobs: 1, ..Options::default() };
        let report = verify(&sys, Method::Explicit, &options, &|_| {}).unwrap();
        prop_assume!(report.stats.complete);
        let verdict = |name: &str| report.properties.iter().find(|p| p.name == name).map(|p| &p.verdict);
        for (bounded, unbounded) in [("bounded", "leads"), ("entered", "entered_leads")] {
            if let (Some(b), Some(u)) = (verdict(bounded), verdict(unbounded)) {
                prop_assert!(!b.holds() || u.holds(), "{bounded} holds, {unbounded}: {u:?}\n{text}");
            }
        }
        for p in &report.properties {
            let (true, PropertyVerdict::Fails { trace: Some(t), .. }) = (
                sys.properties.iter().any(|q| q.name == p.name && q.kind.response_spec().is_some()),
                &p.verdict,
            ) else {
                continue;
            };
            let replayed = bip_engine::replay::replay(sys.clone(), t).unwrap();
            prop_assert!(replayed.refused.is_none(), "{}: refused\n{text}", p.name);
            let end = replayed.end.unwrap();
            let confirmed = match (&t.verdict, &end) {
                (bip_model::Verdict::Violation(_), bip_engine::replay::End::Unanswered { property, loop_start }) => {
                    property == &p.name && *loop_start == t.loop_start
                }
                (bip_model::Verdict::RangeError(_), bip_engine::replay::End::RangeError { .. }) => true,
                _ => false,
            };
            prop_assert!(confirmed, "{}: {:?} replays as {end:?}\n{text}", p.name, t.verdict);
        }
    }
}
