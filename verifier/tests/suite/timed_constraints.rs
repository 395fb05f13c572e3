//! The GenoM layer's constraints in a timed model, where codels of different tasks run at
//! once on different cores: an activity whose `start` codel runs is starting, and counts
//! as active for `Exclusive` and `AtMost`.

use bip_lang::load_str;
use bip_verifier::{verify, Method, Options};

/// Two activities of two tasks on two cores, each `start` codel taking 1 to 2 ms, both
/// requested at any time, with a constraint between them; whether `both` (never both
/// active) holds.
fn both_never_active(constraint: &str) -> bool {
    let text = format!(
        r#"System(name: "ex", tick_ms: 1, time: Exact,
    cpus: [(name: "main", cores: 2, preemption: Job)],
    modules: [(name: "m",
        tasks: [(name: "a", period: 4, priority: 2), (name: "b", period: 4, priority: 1)],
        services: [
            (name: "A", kind: Activity, task: "a", codels: [
                (state: "start", yields: ["run"], bcet: "1ms", wcet: "2ms"),
                (state: "run", yields: ["pause::run", "ether"], wcet: "1ms")]),
            (name: "B", kind: Activity, task: "b", codels: [
                (state: "start", yields: ["run"], bcet: "1ms", wcet: "2ms"),
                (state: "run", yields: ["pause::run", "ether"], wcet: "1ms")]),
        ])],
    constraints: [{constraint}],
    properties: [Invariant(name: "both", expr: "!(active(m.A) && active(m.B))")],
)"#
    );
    let system = load_str("ex.ron", &text).unwrap_or_else(|e| panic!("{}", e.summary()));
    let report = verify(&system, Method::Explicit, &Options::default(), &|_| {}).unwrap();
    let both = report.properties.iter().find(|p| p.name == "both").unwrap();
    assert!(
        both.verdict.holds() || both.verdict.fails(),
        "{:?}",
        both.verdict
    );
    both.verdict.holds()
}

#[test]
fn a_starting_activity_counts_as_active() {
    assert!(both_never_active(r#"Exclusive(services: ["m.A", "m.B"])"#));
    assert!(both_never_active(
        r#"AtMost(max: 1, services: ["m.A", "m.B"])"#
    ));
    // without a constraint both run at once: the property can fail
    assert!(!both_never_active(
        r#"AtMost(max: 2, services: ["m.A", "m.B"])"#
    ));
}
