//! End-to-end tests of the GenoM layer through the `bip` command: `bip expand` prints core
//! that `bip check` reads back with the same sizes, and bad GenoM input gets a diagnostic
//! with its position and exit code 2.

use std::path::Path;
use std::process::{Command, Output};

fn bip(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_bip"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("bip runs")
}

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
        let direct = bip(&["check", model]);
        assert_eq!(summary(&again), summary(&direct), "{model}");
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
            "yield.ron:71:49]",
            "undeclared state",
        ],
    );
    expand_bad(
        "ether",
        (
            r#"(state: "scan",  yields: ["pause::scan", "ether"]"#,
            r#"(state: "scan",  yields: ["pause::scan"]"#,
        ),
        &[
            "no path from `start` to `ether` in activity `Scan`",
            "ether.ron:",
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
        (r#"(name: "nav", period: 1)"#, r#"(name: "nav", period: 0)"#),
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
