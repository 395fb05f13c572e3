//! Traces as the user sees them, end to end: `bip trace show` prints a trace in the
//! model's names and draws it as a sequence chart, and `bip verify --trace-dir` draws the
//! chart beside each trace it saves. The charts are checked as XML, by structure: a
//! lifeline per participant, a group per step and per tick, the end and its why.

use crate::common::bip;

/// The chart's lifelines, the tooltip of each step and tick group, and its texts.
struct Chart {
    lifelines: Vec<String>,
    steps: Vec<String>,
    /// The tooltips of the marked steps, `failing` or `reached`.
    marked: Vec<(String, String)>,
    ticks: usize,
    end: Option<String>,
    texts: Vec<String>,
}

fn chart(path: &std::path::Path) -> Chart {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let doc = roxmltree::Document::parse(&text).expect("the chart parses as XML");
    let tooltip = |n: roxmltree::Node| {
        n.children()
            .find(|c| c.has_tag_name("title"))
            .and_then(|t| t.text())
            .unwrap_or_default()
            .to_string()
    };
    // a class and its variants (`step failing`)
    let groups = |class: &str| -> Vec<String> {
        doc.descendants()
            .filter(|n| {
                n.has_tag_name("g")
                    && n.attribute("class")
                        .is_some_and(|c| c.split(' ').next() == Some(class))
            })
            .map(tooltip)
            .collect()
    };
    let marked = doc
        .descendants()
        .filter_map(|n| {
            let mark = n.attribute("class")?.strip_prefix("step ")?;
            Some((mark.to_string(), tooltip(n)))
        })
        .collect();
    Chart {
        marked,
        lifelines: groups("lifeline"),
        steps: groups("step"),
        ticks: groups("tick").len(),
        end: groups("end").into_iter().next(),
        texts: doc
            .descendants()
            .filter(|n| n.has_tag_name("text"))
            .filter_map(|n| n.text().map(str::to_string))
            .collect(),
    }
}

#[test]
fn verify_draws_the_rover_deadlock_beside_its_trace_with_the_why() {
    let dir = tempfile::tempdir().expect("temp dir");
    let traces = dir.path().to_str().expect("utf-8");
    let out = bip(&[
        "verify",
        "robots/rover-deadlock.ron",
        "--method",
        "explicit",
        "--stop-at-first",
        "-q",
        "--trace-dir",
        traces,
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(dir.path().join("DeadlockFree.trace.ron").exists());
    let c = chart(&dir.path().join("DeadlockFree.svg"));
    // the requested module, and those the why names (Requires sick.Scan, Fresh pom.pose)
    assert_eq!(c.lifelines, ["sick", "pom", "ndd"]);
    assert_eq!(c.steps, ["step 1: request ndd.GoTo"]);
    assert_eq!(c.ticks, 0);
    assert_eq!(
        c.end.as_deref(),
        Some("deadlock: the system can make no progress")
    );
    for line in [
        "ndd.GoTo codel start is ready after 1 tick but held by",
        "navigate_with_laser (line 145): Requires(service: \"ndd.GoTo\", active: [\"sick.Scan\"])",
        "held",
    ] {
        assert!(c.texts.iter().any(|t| t == line), "{line}: {:?}", c.texts);
    }
    assert!(
        c.texts
            .iter()
            .any(|t| t.starts_with("taking no part: rflex")),
        "{:?}",
        c.texts
    );
}

#[test]
fn trace_show_names_a_run_in_the_models_terms_and_draws_every_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let trace = dir.path().join("run.trace.ron");
    let svg = dir.path().join("run.svg");
    let (trace_arg, svg_arg) = (trace.to_str().unwrap(), svg.to_str().unwrap());
    let model = "robots/tests/mini.ron";
    let out = bip(&[
        "simulate", model, "--steps", "30", "--seed", "1", "--trace", trace_arg,
    ]);
    assert_eq!(out.status.code(), Some(0));
    let out = bip(&["trace", "show", model, trace_arg, "--svg", svg_arg]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).expect("utf-8");
    assert!(
        text.starts_with("recording after 30 steps (mini_rover)"),
        "{text}"
    );
    for user in [
        "request rflex.TrackSpeed  ",
        "rflex.TrackSpeed: start → main",
        "antenna.Communicate: start → pause::send",
        "[antenna]",
    ] {
        assert!(text.contains(user), "{user}:\n{text}");
    }
    // none of the expansion's names: connectors, bookkeeping, the clock
    for generated in ["rflex_TrackSpeed", "_request", ".req", "paused", "clock.n"] {
        assert!(!text.contains(generated), "{generated}:\n{text}");
    }
    let steps: Vec<&str> = text.lines().skip(1).collect();
    assert_eq!(steps.len(), 30, "{text}");

    let c = chart(&svg);
    assert_eq!(c.lifelines, ["rflex", "antenna"]);
    let ticks = steps
        .iter()
        .filter(|l| l.trim_end().ends_with("tick"))
        .count();
    assert_eq!(c.ticks, ticks);
    assert_eq!(c.steps.len() + c.ticks, 30);
    for line in steps.iter().filter(|l| !l.trim_end().ends_with("tick")) {
        let mut words = line.split_whitespace();
        let number = words.next().expect("a number");
        let label = line
            .trim_start()
            .trim_start_matches(number)
            .trim_start()
            .split("  ")
            .next()
            .unwrap();
        let tooltip = format!("step {number}: {label}");
        assert!(c.steps.contains(&tooltip), "{tooltip}: {:?}", c.steps);
    }
    assert_eq!(c.end, None);
}

#[test]
fn a_core_models_chart_has_a_lifeline_per_component() {
    let dir = tempfile::tempdir().expect("temp dir");
    let traces = dir.path().to_str().expect("utf-8");
    let out = bip(&[
        "verify",
        "robots/philosophers.ron",
        "-q",
        "--trace-dir",
        traces,
    ]);
    assert_eq!(out.status.code(), Some(1));
    let c = chart(&dir.path().join("DeadlockFree.svg"));
    assert_eq!(c.lifelines.len(), 10, "{:?}", c.lifelines);
    assert_eq!(c.steps.len(), 5);
    assert!(
        c.steps.iter().all(|s| s.contains(": left[")),
        "{:?}",
        c.steps
    );
    assert!(c.marked.is_empty());
    let w = chart(&dir.path().join("someone_eats.svg"));
    assert_eq!(
        w.end.as_deref(),
        Some("someone_eats is reached after the last step")
    );
    assert_eq!(
        w.marked,
        [("reached".to_string(), "step 2: right[2]".to_string())]
    );
    assert!(
        w.texts.iter().any(|t| t == "phil[2]@eating, fork[3]@taken"),
        "{:?}",
        w.texts
    );
}

#[test]
fn a_violation_marks_its_last_step_and_shows_the_property() {
    let dir = tempfile::tempdir().expect("temp dir");
    let model = dir.path().join("cells.ron");
    let text = std::fs::read_to_string("robots/tests/graph-core.ron").expect("the model");
    assert!(text.contains("properties: [DeadlockFree]"));
    let text = text.replacen(
        "properties: [DeadlockFree]",
        "properties: [Invariant(name: \"first_empty\", expr: \"cell[0]@empty\")]",
        1,
    );
    std::fs::write(&model, text).unwrap();
    let traces = dir.path().to_str().expect("utf-8");
    let out = bip(&[
        "verify",
        model.to_str().unwrap(),
        "-q",
        "--trace-dir",
        traces,
    ]);
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    let c = chart(&dir.path().join("first_empty.svg"));
    assert_eq!(
        c.marked,
        [("failing".to_string(), "step 1: fill[0]".to_string())]
    );
    assert_eq!(
        c.end.as_deref(),
        Some("first_empty fails after the last step")
    );
    assert!(
        c.texts.iter().any(|t| t == "cell[0]@empty"),
        "{:?}",
        c.texts
    );
}

#[test]
fn a_trace_that_is_not_one_or_does_not_fit_is_an_error() {
    let dir = tempfile::tempdir().expect("temp dir");
    let bad = dir.path().join("bad.ron");
    std::fs::write(
        &bad,
        "Trace(system: \"x\", steps: [(step: \"nope\", state: {})], verdict: Deadlock)",
    )
    .unwrap();
    let out = bip(&[
        "trace",
        "show",
        "robots/philosophers.ron",
        bad.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("does not fit the model") && err.contains("nope"),
        "{err}"
    );
    std::fs::write(&bad, "not a trace").unwrap();
    let out = bip(&[
        "trace",
        "show",
        "robots/philosophers.ron",
        bad.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a trace"));
}

#[test]
fn simulate_draws_its_run_as_a_timeline_with_a_lane_per_activity() {
    let dir = tempfile::tempdir().expect("temp dir");
    let trace = dir.path().join("run.trace.ron");
    let svg = dir.path().join("run.svg");
    let (trace_arg, svg_arg) = (trace.to_str().unwrap(), svg.to_str().unwrap());
    let model = "robots/tests/mini.ron";
    let out = bip(&[
        "simulate", model, "--steps", "30", "--seed", "1", "--trace", trace_arg, "--svg", svg_arg,
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&svg).expect("the timeline");
    let doc = roxmltree::Document::parse(&text).expect("the timeline parses as XML");
    let class = |n: &roxmltree::Node| n.attribute("class").unwrap_or_default().to_string();
    let lanes: Vec<String> = doc
        .descendants()
        .filter(|n| class(n) == "lane")
        .filter_map(|n| {
            n.children()
                .find(|c| c.has_tag_name("title"))?
                .text()
                .map(str::to_string)
        })
        .collect();
    assert_eq!(lanes, ["rflex.TrackSpeed", "antenna.Communicate"]);
    // the same run as text: each request of an activity is a mark, each tick a rule
    let shown = bip(&["trace", "show", model, trace_arg]);
    let shown = String::from_utf8(shown.stdout).expect("utf-8");
    let requests = shown
        .lines()
        .filter(|l| {
            l.contains("request rflex.TrackSpeed") || l.contains("request antenna.Communicate")
        })
        .count();
    let ticks = shown
        .lines()
        .filter(|l| l.trim_end().ends_with("tick"))
        .count();
    let count = |c: &str| doc.descendants().filter(|n| class(n) == c).count();
    assert!(requests > 0 && ticks > 0, "{shown}");
    assert_eq!(count("event request"), requests, "{shown}");
    assert_eq!(count("tick"), ticks);
    assert!(
        count("segment paused") > 0 && count("event done") > 0,
        "{text}"
    );

    // a timeline is of activities, and drawn from the run's trace
    let out = bip(&["simulate", model, "--svg", svg_arg]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--trace"));
    let out = bip(&[
        "simulate",
        "robots/philosophers.ron",
        "--steps",
        "5",
        "--trace",
        trace_arg,
        "--svg",
        svg_arg,
    ]);
    assert_ne!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no GenoM layer"));
}

#[test]
fn a_time_step_shows_the_units_it_stands_for() {
    let dir = tempfile::tempdir().expect("temp dir");
    let model = dir.path().join("stepper.ron");
    std::fs::write(
        &model,
        r#"System(
    name: "stepper",
    atoms: {
        "S": Atom(locations: ["s"], initial: "s", ports: ["tick"],
            vars: [(name: "k", ty: Int(0, 4), init: 0)],
            transitions: [(from: "s", port: "tick", to: "s", action: "k = (k + 1) % 5")]),
    },
    components: [(name: "c", atom: "S")],
    connectors: [(name: "tick", ports: ["c.tick"], role: Time, advance: "c.k + 1")],
    properties: [Invariant(name: "below_three", expr: "c.k < 3")],
)"#,
    )
    .unwrap();
    let (model, traces) = (model.to_str().unwrap(), dir.path().to_str().unwrap());
    let out = bip(&["verify", model, "-q", "--trace-dir", traces]);
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let trace = dir.path().join("below_three.trace.ron");
    let out = bip(&["trace", "show", model, trace.to_str().unwrap()]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).expect("utf-8");
    let steps: Vec<&str> = text.lines().skip(1).map(str::trim).collect();
    assert_eq!(
        steps[..3],
        [
            "1  tick +1  [c]  c.k = 1",
            "2  tick +2  [c]  c.k = 2",
            "3  tick +3  [c]  c.k = 3"
        ],
        "{text}"
    );
}

/// The groups of an SVG picture whose class starts with `class`, by their tooltips.
fn groups(path: &std::path::Path, class: &str) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let doc = roxmltree::Document::parse(&text).expect("the picture parses as XML");
    doc.descendants()
        .filter(|n| n.has_tag_name("g") && n.attribute("class").is_some_and(|c| c == class))
        .map(|n| {
            n.children()
                .find(|c| c.has_tag_name("title"))
                .and_then(|t| t.text())
                .unwrap_or_default()
                .to_string()
        })
        .collect()
}

/// A timed model's miss drawn as a schedule beside its trace (docs/model.md, "Why whole
/// units are enough", its example): in units of 4 ms, `hi` runs [1, 2) and [2, 3), `lo`
/// takes the core at 3 before `hi`'s release there, `hi` waits [3, 4), runs [4, 5) and is
/// past its deadline at 5.
#[test]
fn a_timed_miss_is_drawn_as_a_schedule() {
    let dir = tempfile::tempdir().expect("temp dir");
    let model = dir.path().join("between.ron");
    std::fs::write(
        &model,
        r#"System(name: "between", tick_ms: 4, time: Exact,
    cpus: [(name: "main", preemption: Job)],
    modules: [(name: "m", tasks: [
        (name: "hi", period: 1, priority: 2, codels: [
            (state: "start", yields: ["pause::start"], wcet: "4ms")]),
        (name: "lo", period: 2, priority: 1, codels: [
            (state: "start", yields: ["pause::start"], wcet: "4ms")])])])"#,
    )
    .expect("the model is written");
    let traces = dir.path().join("traces");
    let out = bip(&[
        "verify",
        model.to_str().expect("utf-8"),
        "-q",
        "--trace-dir",
        traces.to_str().expect("utf-8"),
    ]);
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let picture = traces.join("m_hi_meets_its_4_ms_deadline.schedule.svg");
    assert_eq!(groups(&picture, "lane"), ["core 0", "m.hi", "m.lo"]);
    assert_eq!(
        groups(&picture, "segment running"),
        [
            "m.hi: hi.start, from 1 to 2",
            "m.hi: hi.start, from 2 to 3",
            "m.hi: hi.start, from 4 to 5",
            "m.lo: lo.start, from 3 to 4",
        ]
    );
    assert_eq!(
        groups(&picture, "segment job"),
        [
            "core 0: m.hi, from 1 to 2",
            "core 0: m.hi, from 2 to 3",
            "core 0: m.lo, from 3 to 4",
            "core 0: m.hi, from 4 to 5",
        ]
    );
    assert!(groups(&picture, "segment ready")
        .contains(&"m.hi: waits for a core, from 3 to 4".to_string()));
    assert_eq!(
        groups(&picture, "event miss"),
        ["at 5: m.hi misses its deadline"]
    );
    // `bip trace show --schedule` draws the same
    let again = dir.path().join("again.svg");
    let out = bip(&[
        "trace",
        "show",
        model.to_str().expect("utf-8"),
        traces
            .join("m_hi_meets_its_4_ms_deadline.trace.ron")
            .to_str()
            .expect("utf-8"),
        "--schedule",
        again.to_str().expect("utf-8"),
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read_to_string(&again).expect("drawn"),
        std::fs::read_to_string(&picture).expect("drawn")
    );
    // the end says the miss in the user's terms, not as the expansion's invariant: `hi`'s
    // job, released at 3, is unfinished at 5 (two units of 4 ms)
    let text = String::from_utf8(out.stdout).expect("utf-8");
    let end: Vec<&str> = text.lines().rev().take(2).collect();
    assert_eq!(
        end,
        [
            "  m.hi's job is unfinished 8 ms after its release, past its 4 ms deadline",
            "m.hi meets its 4 ms deadline fails after the last step",
        ],
        "{text}"
    );
}
