//! Wide models load within bounds: long chains of priorities (a functional layer of 99
//! modules, an `AtMost` over 300 activities) load in a few seconds, and a connector whose
//! steps in one state would be too many to list (28 ports, a broadcast to 40 receivers) is
//! refused with its place and its count. Each runs `bip check` in a child process capped
//! in memory and time: before these limits held, such models took the machine's memory.

use std::process::{Command, Output};

/// Virtual memory of each child, in KiB.
const MEMORY_KIB: u64 = 2_000_000;
/// Time of each child, in seconds: a guard against a hang, far above the load times.
const SECONDS: u64 = 120;

/// `bip ARGS` under the caps (`timeout` exits with 124 when the time runs out).
fn bip_capped(args: &[&str]) -> Output {
    Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v {MEMORY_KIB}; exec timeout {SECONDS} \"$0\" \"$@\""
        ))
        .arg(env!("CARGO_BIN_EXE_bip"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("sh runs")
}

fn check_text(name: &str, text: &str) -> (Option<i32>, String, String) {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join(name);
    std::fs::write(&path, text).expect("write");
    let out = bip_capped(&["check", path.to_str().expect("utf-8")]);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_layer_of_99_modules_loads() {
    // 11 copies of the rover's modules and constraints (bench/gen-rover-layer.py 11): its
    // priorities closed into more than 100,000 rules, and the model was refused
    let out = bip_capped(&["check", "robots/bench/rover-layer-11.ron"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("components    210"), "{stdout}");
    assert!(stdout.contains("priorities    2199 declared"), "{stdout}");
}

/// `modules` modules of `per` one-codel activities each, the first `at_most` of them under
/// one `AtMost(max: 1)`.
fn activities(modules: usize, per: usize, at_most: usize) -> String {
    let mut s = String::from("System(name: \"activities\", modules: [\n");
    for m in 0..modules {
        s += &format!("  (name: \"m{m}\", tasks: [(name: \"t\", period: 1)], services: [\n");
        for a in 0..per {
            s += &format!(
                "    (name: \"A{a}\", kind: Activity, task: \"t\", \
                 codels: [(state: \"start\", yields: [\"ether\"])]),\n"
            );
        }
        s += "  ]),\n";
    }
    let names: Vec<String> = (0..at_most)
        .map(|k| format!("\"m{}.A{}\"", k / per, k % per))
        .collect();
    s += &format!(
        "], constraints: [AtMost(max: 1, services: [{}])],\n properties: [DeadlockFree])\n",
        names.join(", ")
    );
    s
}

#[test]
fn at_most_over_300_activities_loads() {
    // 300 activities in a chain of priorities (each below the one declared before), and a
    // guard on each start over the 299 others
    let (code, stdout, stderr) = check_text("atmost.ron", &activities(30, 10, 300));
    assert_eq!(code, Some(0), "{stdout}{stderr}");
    assert!(
        stdout.contains("chains of up to 300 in their closure"),
        "{stdout}"
    );
}

/// `n` components of an atom with two transitions on its port that are enabled together,
/// in one connector: a rendezvous, or a broadcast from a clock.
fn choices(n: usize, broadcast: bool) -> String {
    let comps: Vec<String> = (0..n)
        .map(|k| format!("(name: \"c{k}\", atom: \"Two\")"))
        .collect();
    let ports: Vec<String> = (0..n).map(|k| format!("\"c{k}.p\"")).collect();
    let connector = if broadcast {
        format!(
            "(name: \"all\", ports: [\"clk.tick\", {}], kind: Broadcast(trigger: \"clk.tick\"))",
            ports.join(", ")
        )
    } else {
        format!("(name: \"all\", ports: [{}])", ports.join(", "))
    };
    format!(
        "System(name: \"wide\",\n\
         atoms: {{ \"Two\": Atom(locations: [\"a\"], initial: \"a\", ports: [\"p\"],\n\
                   vars: [(name: \"x\", ty: Bool)],\n\
                   transitions: [(from: \"a\", port: \"p\", to: \"a\", action: \"x = true\"),\n\
                                 (from: \"a\", port: \"p\", to: \"a\", action: \"x = false\")]),\n\
                  \"Clock\": Atom(locations: [\"on\"], initial: \"on\", ports: [\"tick\"],\n\
                   transitions: [(from: \"on\", port: \"tick\", to: \"on\")]) }},\n\
         components: [(name: \"clk\", atom: \"Clock\"), {}],\n\
         connectors: [\n{connector}])\n",
        comps.join(", ")
    )
}

#[test]
fn a_connector_of_28_ports_with_two_choices_each_is_refused() {
    let (code, stdout, stderr) = check_text("wide.ron", &choices(28, false));
    assert_eq!(code, Some(2), "{stdout}{stderr}");
    assert!(
        stderr.contains("connector `all` may have 268435456 steps in one state, more than 65536"),
        "{stderr}"
    );
    // where it is written: line 10, on its name
    assert!(stderr.contains("wide.ron:10:"), "{stderr}");
    assert!(stderr.contains("28 of its ports"), "{stderr}");
}

#[test]
fn a_broadcast_to_40_receivers_with_two_choices_each_is_refused() {
    let (code, stdout, stderr) = check_text("broadcast.ron", &choices(40, true));
    assert_eq!(code, Some(2), "{stdout}{stderr}");
    assert!(
        stderr.contains("connector `all` may have 1099511627776 steps in one state"),
        "{stderr}"
    );
}

#[test]
fn a_broadcast_to_40_receivers_with_exclusive_choices_loads() {
    // two transitions on each receiver's port, never enabled together: one step per state
    let text = choices(40, true)
        .replace(
            "action: \"x = true\")",
            "guard: \"!x\", action: \"x = true\")",
        )
        .replace(
            "action: \"x = false\")",
            "guard: \"x\", action: \"x = false\")",
        );
    let (code, stdout, stderr) = check_text("exclusive.ron", &text);
    assert_eq!(code, Some(0), "{stdout}{stderr}");
}

#[test]
fn priorities_that_meet_too_many_groups_are_refused() {
    // 2,048 priorities on single instances of `c` cut it into 2,048 groups; 2,048
    // priorities on the whole of `c` then meet every group
    let n = 2048;
    let mut s = String::from(
        "System(name: \"groups\",\n\
         atoms: { \"A\": Atom(locations: [\"l\"], initial: \"l\", ports: [\"p\"],\n\
                  transitions: [(from: \"l\", port: \"p\", to: \"l\")]) },\n\
         components: [(name: \"a\", atom: \"A\")],\n connectors: [\n",
    );
    s += &format!("  (name: \"c\", forall: \"i in 0..{n}\", ports: [\"a.p\"]),\n");
    for k in 0..n {
        s += &format!("  (name: \"b{k}\", ports: [\"a.p\"]),\n");
    }
    s += "], priorities: [\n";
    for k in 0..n {
        s += &format!("  (low: \"b0\", high: \"c[{k}]\"),\n");
    }
    for k in 1..n {
        s += &format!("  (low: \"b{k}\", high: \"c\"),\n");
    }
    s += "])\n";
    let (code, stdout, stderr) = check_text("groups.ron", &s);
    assert_eq!(code, Some(2), "{stdout}{stderr}");
    assert!(
        stderr.contains("the priorities meet groups of interactions"),
        "{stderr}"
    );
}
