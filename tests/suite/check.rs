//! End-to-end tests of `bip check`: the examples load, bad input gets a diagnostic with
//! file, line, column and a caret, and exit code 2.

use std::path::{Path, PathBuf};

use crate::common::bip;

fn examples() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> =
        std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("robots"))
            .expect("robots/ exists")
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "ron"))
            .collect();
    v.sort();
    v
}

#[test]
fn every_example_checks() {
    let files = examples();
    assert!(files.len() >= 4, "examples: {files:?}");
    for f in files {
        let out = bip(&["check", f.to_str().expect("utf-8 path")]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}: {}",
            f.display(),
            String::from_utf8_lossy(&out.stderr)
        );
        for word in [
            "components",
            "interactions",
            "locations",
            "variables",
            "properties",
            "bits",
        ] {
            assert!(
                stdout.contains(word),
                "summary of {} lacks {word}:\n{stdout}",
                f.display()
            );
        }
    }
}

#[test]
fn summary_counts_the_philosophers() {
    let out = bip(&["check", "robots/philosophers.ron"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("components    10 (2 families of 2 atom types)"),
        "{stdout}"
    );
    assert!(
        stdout.contains("interactions  15 (3 connectors, 15 with step tables)"),
        "{stdout}"
    );
    assert!(stdout.contains("locations     25"), "{stdout}");
    assert!(stdout.contains("state         15 bits"), "{stdout}");
}

/// Writes a broken copy of the philosophers and checks the diagnostic.
fn check_bad(name: &str, replace: (&str, &str), expect: &[&str]) {
    let dir = tempfile::tempdir().expect("temp dir");
    let good = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/philosophers.ron"),
    )
    .expect("example");
    assert!(
        good.contains(replace.0),
        "{name}: pattern not in the example"
    );
    let path = dir.path().join(format!("{name}.ron"));
    std::fs::write(&path, good.replacen(replace.0, replace.1, 1)).expect("write");
    let out = bip(&["check", path.to_str().expect("utf-8")]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{name}: {stderr}");
    assert!(
        stderr.contains(&format!("{name}.ron:")),
        "{name}: no file name in\n{stderr}"
    );
    for e in expect {
        assert!(stderr.contains(e), "{name}: `{e}` not in\n{stderr}");
    }
    assert!(!stderr.contains("panicked"), "{name}: {stderr}");
}

#[test]
fn bad_inputs_get_positions_and_exit_2() {
    check_bad(
        "syntax",
        ("initial: \"free\",", "initial: \"free\""),
        &["Expected comma", ":20:13]"],
    );
    check_bad(
        "atom",
        ("atom: \"Fork\"", "atom: \"Frok\""),
        &["unknown atom `Frok`", ":29:31]", "───"],
    );
    check_bad(
        "port",
        ("\"fork[(i+1)%N].take\"", "\"fork[(i+1)%N].tak\""),
        &["has no port `tak`", "help: its ports are: take, release"],
    );
    check_bad(
        "location",
        ("phil[i]@eating &&", "phil[i]@eatin &&"),
        &["has no location `eatin`", ":40:54]"],
    );
    check_bad(
        "variable",
        ("phil[i]@eating &&", "phil[i].x > 0 &&"),
        &["has no variable `x`"],
    );
    check_bad(
        "constant",
        ("count: \"N\"", "count: \"M\""),
        &["unknown name `M`"],
    );
    check_bad(
        "duplicate",
        (
            "\"take_right\", \"release\"]",
            "\"take_right\", \"take_right\"]",
        ),
        &["duplicate port `take_right`", "first defined here"],
    );
    check_bad(
        "type",
        (
            "expr: \"exists i in 0..N: phil[i]@eating\"",
            "expr: \"exists i in 0..N: phil[i]@eating + 1\"",
        ),
        &["`+` needs an integer, but this is a boolean"],
    );
    check_bad(
        "count",
        ("count: \"N\"", "count: \"phil[0]@eating\""),
        &["components cannot be read here"],
    );
    check_bad(
        "twice",
        ("\"fork[(i+1)%N].release\"", "\"fork[(i+5)%N].release\""),
        &["appears twice in connector `release`"],
    );
    check_bad(
        "cycle",
        ("properties: [", "priorities: [(low: \"left\", high: \"right\"), (low: \"right\", high: \"left\")],\n    properties: ["),
        &["the priorities form a cycle: left < right, right < left"],
    );
}

#[test]
fn empty_and_missing_files_exit_2() {
    let dir = tempfile::tempdir().expect("temp dir");
    let empty = dir.path().join("empty.ron");
    std::fs::write(&empty, "").expect("write");
    let out = bip(&["check", empty.to_str().expect("utf-8")]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("the file is empty"));
    let out = bip(&["check", "no/such/model.ron"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read no/such/model.ron"));
}

#[test]
fn usage_errors_exit_2() {
    assert_eq!(bip(&["check"]).status.code(), Some(2));
    assert_eq!(bip(&["frobnicate"]).status.code(), Some(2));
}

/// A reader that goes away (`bip expand model | head -1`) ends bip quietly, as it ends
/// other Unix tools, not with a panic about a broken pipe.
#[test]
fn a_closed_pipe_is_no_panic() {
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_bip"))
        .args(["expand", "robots/rover.ron"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("bip runs");
    drop(child.stdout.take()); // the reader is gone before bip writes
    let out = child.wait_with_output().expect("bip ends");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_ne!(out.status.code(), Some(101), "{stderr}");
}

/// An error far into a long line (past miette's 65,535 columns) and a huge quantifier are
/// diagnostics with exit 2, not a panic or a hang.
#[test]
fn long_lines_and_huge_quantifiers_are_diagnostics() {
    let dir = std::env::temp_dir().join(format!("bip-check-long-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    let long = dir.join("long.ron");
    std::fs::write(
        &long,
        format!("System(name: \"m\",\n{}x)\n", " ".repeat(65_536)),
    )
    .expect("written");
    let quant = dir.join("quant.ron");
    std::fs::write(
        &quant,
        r#"System(name: "m", constants: {"Q": "forall i in 0..9223372036854775807: true"})"#,
    )
    .expect("written");
    for (file, at) in [(&long, "long.ron:2:65537"), (&quant, "quant.ron:1:37")] {
        let out = bip(&["check", file.to_str().expect("utf-8 path")]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(at), "{stderr}");
        assert!(stderr.lines().all(|l| l.chars().count() < 400), "{stderr}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
