//! What the end-to-end tests share.

#![allow(dead_code)]

use std::process::Command;

/// Runs the `bip` binary in the repository's root and waits for it.
pub fn bip(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_bip"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("bip runs")
}

/// True if `tool` is on PATH (the SPIN cross-checks run only where SPIN and gcc are).
pub fn have(tool: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {tool}")])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// True if the SPIN cross-checks can run (`spin` and `gcc` on PATH). Otherwise the skip is
/// written to the process's stderr directly, past the test harness's capture, so that it
/// shows in every run; with `BIP_REQUIRE_SPIN=1` (CI, which installs SPIN) a missing SPIN
/// fails the test instead.
pub fn spin_available(test: &str) -> bool {
    if have("spin") && have("gcc") {
        return true;
    }
    let required = std::env::var("BIP_REQUIRE_SPIN").is_ok_and(|v| v == "1");
    assert!(
        !required,
        "{test}: BIP_REQUIRE_SPIN=1 but spin or gcc is not on PATH (apt-get install spin gcc)"
    );
    use std::io::Write;
    let _ = writeln!(
        std::io::stderr().lock(),
        "SKIPPED {test}: spin or gcc is not on PATH, the SPIN cross-check did NOT run (apt-get install spin)"
    );
    false
}

/// What SPIN says of a Promela model: compiled with `spin -o2` (and `-D` each of
/// `defines`), searched exhaustively with `pan -c0` (every error counted, a depth limit of
/// ten million steps, checked not to cut the search). Returns the states stored and pan's
/// report.
pub fn spin(dir: &std::path::Path, pml: &str, defines: &[&str]) -> (u64, String) {
    let run = |cmd: &str| {
        let o = Command::new("sh")
            .arg("-c")
            .arg(cmd)
            .current_dir(dir)
            .output()
            .expect("sh runs");
        assert!(
            o.status.success(),
            "{cmd}: {}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let defines: String = defines.iter().map(|d| format!(" -D{d}")).collect();
    run(&format!(
        "spin -o2{defines} -a {pml} && gcc -O1 -DSAFETY -DNOREDUCE -o pan pan.c"
    ));
    // pan is bounded by the model, and capped all the same
    let pan = run("ulimit -v 4000000; ./pan -c0 -m10000000");
    assert!(
        !pan.contains("out of memory") && !pan.contains("max search depth too small"),
        "pan did not search every state:\n{pan}"
    );
    let stored = pan
        .lines()
        .find(|l| l.trim_end().ends_with("states, stored"))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("pan reports no states stored:\n{pan}"));
    (stored, pan)
}
