//! `bip graph` end to end: the DOT of small models against golden files (rewrite them
//! with `BIP_BLESS=1` after a deliberate change, and read the diff), SVGs that parse as
//! XML and name every module, service, port, component and connector, and the errors.

use crate::common::bip;

const GENOM: &str = "robots/tests/graph.ron";
const CORE: &str = "robots/tests/graph-core.ron";

/// `bip graph` with `args`, which must succeed; its stdout.
fn graph(args: &[&str]) -> String {
    let mut all = vec!["graph"];
    all.extend_from_slice(args);
    let out = bip(&all);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8")
}

fn golden(name: &str, actual: &str) {
    let path = format!("{}/tests/golden/graph/{name}", env!("CARGO_MANIFEST_DIR"));
    if std::env::var("BIP_BLESS").is_ok_and(|v| v == "1") {
        std::fs::write(&path, actual).expect("write the golden file");
    }
    let expected = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    assert!(
        expected == actual,
        "{name} differs from its golden file (BIP_BLESS=1 rewrites it):\n{actual}"
    );
}

#[test]
fn the_dot_of_each_level_is_its_golden_file() {
    golden("genom.dot", &graph(&[GENOM, "--format", "dot"]));
    golden("core.dot", &graph(&[CORE, "--format", "dot"]));
    golden(
        "activity.dot",
        &graph(&[GENOM, "--activity", "arm.Move", "--format", "dot"]),
    );
    // without --level, a model with modules is drawn at the GenoM level, one without at core
    assert_eq!(
        graph(&[GENOM, "--format", "dot"]),
        graph(&[GENOM, "--format", "dot", "--level", "genom"])
    );
    assert_eq!(
        graph(&[CORE, "--format", "dot"]),
        graph(&[CORE, "--format", "dot", "--level", "core"])
    );
}

/// The texts of an SVG document, which must parse as XML, and its groups' classes.
fn svg_parts(svg: &str) -> (Vec<String>, Vec<String>) {
    let doc = roxmltree::Document::parse(svg).expect("the SVG parses as XML");
    assert_eq!(doc.root_element().tag_name().name(), "svg");
    let texts = doc
        .descendants()
        .filter(|n| n.has_tag_name("text"))
        .filter_map(|n| n.text().map(str::to_string))
        .collect();
    let classes = doc
        .descendants()
        .filter(|n| n.has_tag_name("g"))
        .filter_map(|n| n.attribute("class").map(str::to_string))
        .collect();
    (texts, classes)
}

fn count(classes: &[String], prefix: &str) -> usize {
    classes.iter().filter(|c| c.starts_with(prefix)).count()
}

#[test]
fn the_svg_of_the_genom_level_names_every_module_service_and_port() {
    let (texts, classes) = svg_parts(&graph(&[GENOM]));
    for name in ["arm", "eye", "arm.joints", "power", "clock tick"] {
        assert!(texts.iter().any(|t| t == name), "{name}: {texts:?}");
    }
    for service in [
        "Init (function)",
        "Move (activity in servo), after Init",
        "Look (activity in grab)",
    ] {
        assert!(texts.iter().any(|t| t == service), "{service}: {texts:?}");
    }
    for label in [
        "still: exclusive",
        "requires",
        "seen: age ≤ 3",
        "guard: power.on",
        "at most 1",
    ] {
        assert!(texts.iter().any(|t| t == label), "{label}: {texts:?}");
    }
    assert_eq!(count(&classes, "node module"), 2);
    assert_eq!(count(&classes, "node port"), 1);
    assert_eq!(count(&classes, "edge constraint"), 5);
    assert_eq!(count(&classes, "edge writes"), 1);
    // the abort connector: a dot taking eye.Look's abort, reading arm.Move and arm.joints
    assert!(texts.iter().any(|t| t == "abort_blind"), "{texts:?}");
    assert!(texts.iter().any(|t| t == "abort"), "{texts:?}");
    assert_eq!(count(&classes, "edge reads"), 2);
    // in the user's names only: nothing of the expansion
    assert!(
        !texts
            .iter()
            .any(|t| t.contains("arm_Move") && t != "arm_Move_track"),
        "{texts:?}"
    );
}

#[test]
fn the_svg_of_the_core_level_has_every_component_and_connector() {
    let (texts, classes) = svg_parts(&graph(&[CORE, "-o", "/dev/stdout"]));
    for name in [
        "clock", "cell[0]", "cell[1]", "tick", "move", "fill[0]", "fill[1]", "trigger",
    ] {
        assert!(texts.iter().any(|t| t == name), "{name}: {texts:?}");
    }
    assert_eq!(count(&classes, "node component"), 3);
    assert_eq!(count(&classes, "node connector"), 4);
    assert_eq!(count(&classes, "node connector broadcast"), 1);
    assert_eq!(count(&classes, "edge priority"), 2);
}

#[test]
fn an_activity_shows_its_codels_yields_exceptions_and_stop_path() {
    let (texts, classes) = svg_parts(&graph(&[GENOM, "--activity", "arm.Move"]));
    for label in [
        "ether",
        "start",
        "track",
        "stop",
        "pause::track",
        "ether (done)",
        "e_limit",
        "stop path (ungated)",
        "writes joints",
    ] {
        assert!(texts.iter().any(|t| t == label), "{label}: {texts:?}");
    }
    assert_eq!(count(&classes, "node codel"), 3);
    assert_eq!(count(&classes, "edge throw"), 2);
}

#[test]
fn a_task_machine_is_drawn_from_the_start_without_interrupts() {
    let machine = "robots/tests/task-machine.ron";
    let (texts, classes) = svg_parts(&graph(&[machine, "--activity", "flight.main"]));
    for label in [
        "ether",
        "start",
        "init",
        "control",
        "emergency",
        "stop",
        "at the first period",
        "pause::control",
        "at shutdown: never in the model",
    ] {
        assert!(texts.iter().any(|t| t == label), "{label}: {texts:?}");
    }
    assert!(!texts.iter().any(|t| t.contains("request")), "{texts:?}");
    assert!(
        !texts.iter().any(|t| t.contains("interrupt")),
        "nothing interrupts a machine: {texts:?}"
    );
    assert_eq!(count(&classes, "node codel"), 5);
    // the activity of the same task is drawn as before
    let (texts, _) = svg_parts(&graph(&[machine, "--activity", "flight.Calibrate"]));
    assert!(
        texts.iter().any(|t| t == "request, at a period"),
        "{texts:?}"
    );
    // a wrong name lists the machines too
    let out = bip(&["graph", machine, "--activity", "flight.mai"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("its activities are flight.main (a task's machine), flight.Calibrate"),
        "{err}"
    );
}

#[test]
fn the_rover_is_drawn_at_every_level_and_for_every_activity() {
    let (texts, _) = svg_parts(&graph(&["robots/rover.ron"]));
    for module in [
        "rflex", "sick", "pom", "ndd", "aspect", "antenna", "battery", "heating", "camera",
    ] {
        assert!(texts.iter().any(|t| t == module), "{module}");
    }
    svg_parts(&graph(&["robots/rover.ron", "--level", "core"]));
    svg_parts(&graph(&["robots/rover.ron", "--activity", "ndd.GoTo"]));
}

#[test]
fn a_wrong_request_is_an_error_with_help() {
    let out = bip(&["graph", GENOM, "--activity", "arm.Mov"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no activity `arm.Mov`"), "{err}");
    assert!(
        err.contains("its activities are arm.Move, eye.Look, eye.Watch"),
        "{err}"
    );

    let out = bip(&["graph", CORE, "--level", "genom"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--level core"));

    let out = bip(&["graph", "robots/tests/no-such-model.ron"]);
    assert_eq!(out.status.code(), Some(2));
}

/// Where graphviz is installed, it reads every golden DOT file without a warning; where it
/// is not, the skip is said on stderr (graphviz is never needed by bip itself).
#[test]
fn graphviz_reads_the_dot_where_it_is_installed() {
    if !crate::common::have("dot") {
        use std::io::Write;
        let _ = writeln!(
            std::io::stderr().lock(),
            "SKIPPED graphviz_reads_the_dot_where_it_is_installed: `dot` is not on PATH (apt-get install graphviz)"
        );
        return;
    }
    for name in ["genom.dot", "core.dot", "activity.dot"] {
        let path = format!("{}/tests/golden/graph/{name}", env!("CARGO_MANIFEST_DIR"));
        let out = std::process::Command::new("dot")
            .args(["-Tsvg", &path])
            .output()
            .expect("dot runs");
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            out.stderr.is_empty(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// The data flow crosses components: the estimator's machine writes its out port, which
/// the connection takes to the controller's in port, which the controller reads and its
/// freshness constraint names.
#[test]
fn a_connection_is_drawn_from_the_out_port_to_the_in_port() {
    let dot = graph(&["robots/tests/connections.ron", "--format", "dot"]);
    for edge in [
        r##""module estimator":r0 -> "port estimator.frame" [color="#1d5e8c" class="writes"];"##,
        r##""port estimator.frame" -> "port controller.state" [label="connected" color="#1d5e8c" class="connection"];"##,
        r##""port controller.state" -> "module controller" [color="#1d5e8c" class="reads"];"##,
        r##""port controller.state" -> "module controller":r1 [label="fresh_state: age ≤ 2""##,
    ] {
        assert!(dot.contains(edge), "{edge} in {dot}");
    }
    let (texts, classes) = svg_parts(&graph(&["robots/drone/drone.ron"]));
    assert_eq!(count(&classes, "edge connection"), 6, "{classes:?}");
    assert_eq!(count(&classes, "node in-port"), 6, "{classes:?}");
    for name in ["flight.state", "pose.frame", "rotorcraft.rotor_input"] {
        assert!(texts.iter().any(|t| t == name), "{name}: {texts:?}");
    }
}
