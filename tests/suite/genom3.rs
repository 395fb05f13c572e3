//! GenoM3 `.gen` files end to end: a model that takes its modules from `.gen` files
//! verifies with the same verdicts and state counts as its RON equivalent and runs in the
//! engine, `bip graph` draws it as its RON equivalent, and `bip import` prints a model that
//! loads (docs/genom.md, "GenoM3 files").

use crate::common::bip;

/// The verdict lines and the explored states and transitions of `bip verify`.
fn verdicts(model: &str) -> (Option<i32>, Vec<String>) {
    let out = bip(&["verify", model, "--method", "explicit", "--jobs", "1"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let lines = stdout
        .lines()
        .filter(|l| l.contains("holds") || l.contains("FAILS") || l.contains(" states, "))
        .map(|l| match l.split_once(", depth") {
            // the counts, not the time
            Some((counts, _)) => counts.to_string(),
            None => l.to_string(),
        })
        .collect();
    (out.status.code(), lines)
}

#[test]
fn the_gen_rover_verifies_as_its_ron_equivalent() {
    let (code, from_gen) = verdicts("robots/genom3-rover.ron");
    let (written_code, written) = verdicts("robots/genom3-rover-written.ron");
    assert_eq!(code, Some(0), "{from_gen:?}");
    assert_eq!(written_code, Some(0));
    assert!(
        from_gen.iter().any(|l| l.contains(" states, ")),
        "{from_gen:?}"
    );
    assert_eq!(
        from_gen.len(),
        6,
        "five properties (time progress too) and the counts: {from_gen:?}"
    );
    assert_eq!(from_gen, written);
    // the engine runs it as read from the .gen files
    let out = bip(&[
        "simulate",
        "robots/genom3-rover.ron",
        "--steps",
        "500",
        "--seed",
        "1",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    assert!(stdout.contains("held at every step"), "{stdout}");
}

#[test]
fn bip_import_prints_a_model_that_loads() {
    let out = bip(&["import", "robots/genom3/nav.gen", "-I", "robots/genom3/idl"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let printed = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(printed.contains("tick_ms: 200"), "{printed}");
    assert!(
        printed.contains(
            r#"(state: "move", yields: ["pause::move", "ether"], throws: ["e_blocked"], uses: ["plan"])"#
        ),
        "{printed}"
    );
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join("nav.ron");
    std::fs::write(&path, printed).expect("writes");
    let check = bip(&["check", path.to_str().expect("utf-8")]);
    assert_eq!(
        check.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&check.stderr)
    );
}

#[test]
fn bip_import_wires_several_files_as_connect_says() {
    let gen: Vec<String> = ["rotorcraft", "pose", "flight", "maneuver", "mocap"]
        .iter()
        .map(|c| format!("robots/drone/{c}.gen"))
        .collect();
    let mut args: Vec<&str> = vec!["import"];
    args.extend(gen.iter().map(String::as_str));
    args.extend([
        "-I",
        "robots/drone/idl",
        "--connect",
        "flight.state=pose.frame",
    ]);
    let out = bip(&args);
    let printed = String::from_utf8_lossy(&out.stdout).to_string();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        printed.contains(
            "    connections: [\n        (port: \"flight.state\", reads: \"pose.frame\"),\n    ],"
        ),
        "{printed}"
    );
    assert!(printed.contains("name: \"layer\""), "{printed}");
    // what it prints is the layer, and loads
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join("layer.ron");
    std::fs::write(&path, &printed).expect("writes");
    let check = bip(&["check", path.to_str().expect("utf-8")]);
    assert_eq!(
        check.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&check.stderr)
    );
    // a malformed `--connect`, and one that names an out port as the in port
    for (connect, says) in [
        ("flight.state", "expected `module.in_port=module.out_port`"),
        (
            "pose.frame=flight.state",
            "`pose.frame` is an out port: a connection's `port` is an in port",
        ),
        (
            "flight.stat=pose.frame",
            "module `flight` has no in port `stat`",
        ),
    ] {
        let mut bad = args[..args.len() - 1].to_vec();
        bad.push(connect);
        let out = bip(&bad);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(says), "{connect}: {stderr}");
    }
}

#[test]
fn bip_import_shows_an_error_in_the_gen_file() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join("bad.gen");
    std::fs::write(&path, "component bad {\n  task t { period 10 ms };\n};\n").expect("writes");
    let out = bip(&["import", path.to_str().expect("utf-8")]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("expected `;`, found `}`"), "{stderr}");
    assert!(stderr.contains("bad.gen:2:25]"), "{stderr}");
    // in a model, and in JSON, the error names the .gen file
    let model = dir.path().join("m.ron");
    std::fs::write(
        &model,
        r#"System(name: "m", tick_ms: 10, modules: [Gen("bad.gen")])"#,
    )
    .expect("writes");
    let out = bip(&["verify", model.to_str().expect("utf-8"), "--format", "json"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(2), "{stdout}");
    let json: serde_json::Value = serde_json::from_str(&stdout).expect("a JSON document");
    let first = &json["errors"][0];
    assert!(
        first["file"]
            .as_str()
            .is_some_and(|f| f.ends_with("bad.gen")),
        "{json}"
    );
    assert_eq!(
        (first["line"].as_u64(), first["column"].as_u64()),
        (Some(2), Some(25)),
        "{json}"
    );
    // without the search path, an include is not found
    let out = bip(&["import", "robots/genom3/nav.gen"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("cannot find the included file `rover.idl`"),
        "{stderr}"
    );
}

/// `bip graph` of the model that reads `.gen` files: its stdout, after checking it succeeded.
fn graph(model: &str, args: &[&str]) -> String {
    let mut all = vec!["graph", model];
    all.extend_from_slice(args);
    let out = bip(&all);
    assert_eq!(
        out.status.code(),
        Some(0),
        "bip graph {model} {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).to_string()
}

#[test]
fn bip_graph_draws_the_gen_rover_as_its_ron_equivalent() {
    let levels: [&[&str]; 4] = [
        &["--format", "dot"],
        &["--level", "core", "--format", "dot"],
        &["--activity", "nav.GoTo", "--format", "dot"],
        &["--activity", "loco.Move"],
    ];
    for args in levels {
        let from_gen = graph("robots/genom3-rover.ron", args);
        let written = graph("robots/genom3-rover-written.ron", args);
        assert_eq!(from_gen, written, "bip graph {args:?}");
    }
    // the modules, their services and ports as the .gen files name them
    let genom = graph("robots/genom3-rover.ron", &["--format", "dot"]);
    for name in [
        "\"module loco\"",
        "\"module loc\"",
        "\"module nav\"",
        "\"port loc.pose\"",
        "\"port loc.landmarks\"",
        "Move (activity in motion), interrupts Move, after Init",
        "Cancel (function), interrupts GoTo",
    ] {
        assert!(genom.contains(name), "{name} in\n{genom}");
    }
    let core = graph(
        "robots/genom3-rover.ron",
        &["--level", "core", "--format", "dot"],
    );
    for name in [
        "\"nav_GoTo_move\"",
        "\"loc_Track_estimate\"",
        "\"loco_Init_request\"",
    ] {
        assert!(core.contains(name), "{name} in the core");
    }
    let goto = graph(
        "robots/genom3-rover.ron",
        &["--activity", "nav.GoTo", "--format", "dot"],
    );
    assert!(
        goto.contains(r#""codel start" -> "codel move" [label="pause::move""#),
        "{goto}"
    );
    assert!(goto.contains(r#"[label="e_blocked""#), "{goto}");
    let svg = graph("robots/genom3-rover.ron", &[]);
    assert!(svg.starts_with("<svg") && svg.contains(">nav</"), "{svg}");
}

#[test]
fn bip_graph_shows_an_error_in_a_gen_file() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    std::fs::write(
        dir.path().join("c.gen"),
        "component c {\n  task t { period 10 ms; };\n  activity A() { task t; codel<start> f() yield nowhere; };\n};\n",
    )
    .expect("writes");
    let model = dir.path().join("m.ron");
    std::fs::write(
        &model,
        r#"System(name: "m", tick_ms: 10, modules: [Gen("c.gen")])"#,
    )
    .expect("writes");
    let out = bip(&["graph", model.to_str().expect("utf-8")]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("c.gen:3:"), "{stderr}");
    assert!(stderr.contains("nowhere"), "{stderr}");
}

/// An async codel (docs/genom.md, "Async codels") in the pictures and traces: the
/// activity's picture marks it, and a trace names its start apart from the task, its
/// return, and then its outcome, with ticks between them; `bip replay` and `bip simulate`
/// run it through the engine.
#[test]
fn an_async_codel_shows_its_start_return_and_outcome() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let camera = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("robots/tests/genom3/camera.gen")
        .display()
        .to_string();
    let model = dir.path().join("camera.ron");
    std::fs::write(
        &model,
        format!(
            r#"System(name: "camera", tick_ms: 10, modules: [Gen({camera:?})],
            properties: [Invariant(name: "never_published", expr: "!camera.Capture@publish")])"#
        ),
    )
    .expect("writes");
    let model = model.display().to_string();
    let picture = graph(&model, &["--activity", "camera.Capture", "--format", "dot"]);
    assert!(
        picture.contains(r#"label="wait\nasync: runs apart from its task""#),
        "{picture}"
    );
    let traces = dir.path().join("traces");
    let traces_arg = traces.display().to_string();
    let out = bip(&["verify", &model, "--trace-dir", &traces_arg]);
    assert_eq!(out.status.code(), Some(1), "the invariant fails");
    let trace = traces
        .join("never_published.trace.ron")
        .display()
        .to_string();
    let out = bip(&["trace", "show", &model, &trace]);
    let shown = String::from_utf8_lossy(&out.stdout);
    let at = |what: &str| {
        shown
            .find(what)
            .unwrap_or_else(|| panic!("{what} in\n{shown}"))
    };
    let (start, ret, outcome) = (
        at("camera.Capture: wait starts apart"),
        at("camera.Capture: wait returns"),
        at("camera.Capture: wait → publish"),
    );
    assert!(start < ret && ret < outcome, "{shown}");
    assert!(shown[start..outcome].contains("tick"), "{shown}");
    // the engine runs it: the counterexample replays to its failure, and a simulation's
    // recording (starts, returns and outcomes of the grab among them) replays whole
    let out = bip(&["replay", &model, &trace]);
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    // (a model without the invariant, which a simulation would find failing)
    let plain = dir.path().join("plain.ron");
    std::fs::write(
        &plain,
        format!(r#"System(name: "camera", tick_ms: 10, modules: [Gen({camera:?})])"#),
    )
    .expect("writes");
    let model = plain.display().to_string();
    let run = dir.path().join("run.ron").display().to_string();
    let out = bip(&[
        "simulate", &model, "--steps", "3000", "--seed", "1", "--trace", &run,
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let recorded = std::fs::read_to_string(&run).expect("the recording");
    for step in [
        "camera_Capture_wait_start",
        "camera_Capture_wait_return",
        "camera_Capture_wait\"",
    ] {
        assert!(recorded.contains(step), "{step} in the recording");
    }
    let out = bip(&["replay", &model, &run]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
}
