//! Connections between modules (docs/model.md, "Connections"): the fixture's meaning (a
//! connected in port stands for the out port it reads, in constraints, expressions and
//! the engine's map), `bip import` of several files with connections, and bad inputs
//! with their messages and positions.

use crate::gen3::TempDir;
use crate::support;
use support::errors::assert_error;

use bip_lang::{expand_str, import_gen_files, load_str};
use proptest::prelude::*;

const FIXTURE: &str = include_str!("../../../robots/tests/connections.ron");

fn with(from: &str, to: &str) -> String {
    assert!(FIXTURE.contains(from), "the fixture has `{from}`");
    FIXTURE.replacen(from, to, 1)
}

/// The model's core once expanded, as RON.
fn core(text: &str) -> String {
    expand_str("connections.ron", text)
        .unwrap_or_else(|e| panic!("{}", e.summary()))
        .to_ron()
        .expect("prints")
}

#[test]
fn a_connected_in_port_is_the_out_port_it_reads() {
    // naming the estimator's out port instead of the controller's in port, in the
    // constraint and the properties, gives the same core: the same guards on the same age
    let direct = FIXTURE
        .replace(
            r#"port: "controller.state", max_age"#,
            r#"port: "estimator.frame", max_age"#,
        )
        .replace("age(controller.state)", "age(estimator.frame)");
    assert_ne!(direct, FIXTURE);
    let normalise = |core: String| core.replace("controller.state", "estimator.frame");
    assert_eq!(normalise(core(FIXTURE)), normalise(core(&direct)));
    // the estimator's age is the one the guard reads
    assert!(core(FIXTURE).contains("estimator.age_frame <= 2"));
    // and the engine's map says which out port the in port reads
    let sys = load_str("connections.ron", FIXTURE).unwrap_or_else(|e| panic!("{}", e.summary()));
    let map = sys.genom.as_ref().expect("a map");
    let controller = map.module("controller").expect("controller");
    let estimator = map
        .modules
        .iter()
        .position(|m| m.name == "estimator")
        .expect("estimator");
    assert_eq!(controller.in_ports.len(), 1);
    assert_eq!(controller.in_ports[0].name, "state");
    assert_eq!(controller.in_ports[0].reads, Some((estimator as u32, 0)));
}

#[test]
fn an_unconnected_in_port_is_declared_but_cannot_be_read() {
    let unconnected = with(
        r#"(port: "controller.state", reads: "estimator.frame"),"#,
        "",
    );
    assert_error(
        &unconnected,
        "in port `controller.state` is connected to no out port",
        "state",
    );
    // without a reader, it loads and means nothing to the model
    let unread = unconnected
        .replace(
            r#"Fresh(name: "fresh_state", service: "controller.Servo", port: "controller.state", max_age: 2),"#,
            "",
        )
        .replace("age(controller.state)", "age(estimator.frame)");
    load_str("m.ron", &unread).unwrap_or_else(|e| panic!("{}", e.summary()));
}

#[test]
fn bad_connections_are_errors_at_their_place() {
    let conn = r#"(port: "controller.state", reads: "estimator.frame")"#;
    let bad = |to: &str| with(conn, to);
    assert_error(
        &bad(r#"(port: "estimator.frame", reads: "estimator.frame")"#),
        "`estimator.frame` is an out port: a connection's `port` is an in port",
        "frame",
    );
    assert_error(
        &bad(r#"(port: "controller.stat", reads: "estimator.frame")"#),
        "module `controller` has no in port `stat`",
        "stat",
    );
    assert_error(
        &bad(r#"(port: "controler.state", reads: "estimator.frame")"#),
        "unknown module `controler`",
        "controler",
    );
    assert_error(
        &bad(r#"(port: "controller.state", reads: "controller.state")"#),
        "`controller.state` is an in port: a connection reads an out port",
        "state",
    );
    assert_error(
        &bad(r#"(port: "controller.state", reads: "estimator.fram")"#),
        "module `estimator` has no out port `fram`",
        "fram",
    );
    assert_error(
        &bad(r#"(port: "controller", reads: "estimator.frame")"#),
        "expected `module.port`",
        "controller",
    );
    assert_error(
        &bad(&format!(
            "{conn}, (port: \"controller.state\", reads: \"estimator.frame\")"
        )),
        "in port `controller.state` is connected twice",
        "controller.state",
    );
    assert_error(
        &with(
            r#"in_ports: [(name: "state", ty: Record"#,
            r#"in_ports: [(name: "state", ty: Float), (name: "unused", ty: Record"#,
        ),
        "in port `controller.state` takes `Float`, and out port `estimator.frame` carries `Record(name: \"Frame\"",
        "estimator.frame",
    );
    assert_error(
        &with(
            r#"in_ports: [(name: "state""#,
            r#"in_ports: [(name: "command""#,
        ),
        "command",
        "command",
    );
    assert_error(
        &with(
            "(age(controller.state) <= 2) == ",
            "controller.state == 1 && (age(controller.state) <= 2) == ",
        ),
        "`controller.state` is a port, not a value",
        "state",
    );
    assert_error(
        &with("age(controller.state) <= 2)", "age(controller.stat) <= 2)"),
        "module `controller` has no port `stat`",
        "stat",
    );
}

#[test]
fn import_wires_several_files() {
    let dir = TempDir::new();
    let writer = dir.write(
        "est.gen",
        "component est {\n  port out double frame;\n  task filter { period 2 ms; };\n  activity Run() { task filter; codel<start> f(port out frame) yield pause::start; };\n};\n",
    );
    let reader = dir.write(
        "ctl.gen",
        "component ctl {\n  port in double state;\n  task main { period 1 ms; };\n  activity Go() { task main; codel<start> g(port in state) yield pause::start, ether; };\n};\n",
    );
    let conn = [("ctl.state".to_string(), "est.frame".to_string())];
    let def = import_gen_files(&[&writer, &reader], &[], &conn)
        .unwrap_or_else(|e| panic!("{}", e.summary()));
    assert_eq!(def.name.as_str(), "layer");
    let names: Vec<&str> = def.modules.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["est", "ctl"]);
    assert_eq!(def.modules[1].in_ports[0].name.as_str(), "state");
    let printed = def.to_ron().expect("prints");
    // a connection per line
    assert!(
        printed.contains(
            "    connections: [\n        (port: \"ctl.state\", reads: \"est.frame\"),\n    ],"
        ),
        "{printed}"
    );
    // the tick divides both files' periods, and what it prints loads back
    load_str("imported.ron", &printed).unwrap_or_else(|e| panic!("{}", e.summary()));
    // a connection that names no in port is refused, in the user's names
    let bad = [("ctl.frame".to_string(), "est.frame".to_string())];
    let e = import_gen_files(&[&writer, &reader], &[], &bad).expect_err("refused");
    assert!(
        e.summary().contains("module `ctl` has no in port `frame`"),
        "{}",
        e.summary()
    );
}

/// A random layer: per module a period and, per in port, the module whose out port it
/// reads (if connected) and the largest age a `Fresh` on it allows (if any).
#[derive(Clone, Debug)]
struct Wiring {
    periods: Vec<u8>,
    inputs: Vec<[(Option<usize>, Option<u8>); 2]>,
}

fn wiring() -> impl Strategy<Value = Wiring> {
    (2usize..=4).prop_flat_map(|n| {
        let input = (proptest::option::of(0..n), proptest::option::of(0u8..4));
        (
            proptest::collection::vec(1u8..=3, n),
            proptest::collection::vec([input.clone(), input], n),
        )
            .prop_map(|(periods, inputs)| Wiring { periods, inputs })
    })
}

/// The layer's text; with `direct`, what reads an in port names the out port it is
/// connected to instead (the naive reading of a connection), and nothing is connected.
fn wired(w: &Wiring, direct: bool) -> String {
    let mut modules = String::new();
    let mut connections = String::new();
    let mut constraints = String::new();
    let mut invariants = String::new();
    for (m, period) in w.periods.iter().enumerate() {
        modules.push_str(&format!(
            r#"(name: "m{m}", tasks: [(name: "t", period: {period})], ports: [(name: "o")],
                in_ports: [(name: "i0"), (name: "i1")],
                services: [(name: "S", kind: Activity, task: "t", codels: [
                    (state: "start", yields: ["pause::run"]),
                    (state: "run", yields: ["pause::run", "ether"], writes: ["o"]),
                ])]),
            "#
        ));
        for (k, (writer, fresh)) in w.inputs[m].iter().enumerate() {
            let Some(writer) = writer else { continue };
            let read = match direct {
                true => format!("m{writer}.o"),
                false => {
                    connections.push_str(&format!(r#"(port: "m{m}.i{k}", reads: "m{writer}.o"),"#));
                    format!("m{m}.i{k}")
                }
            };
            if let Some(age) = fresh {
                constraints.push_str(&format!(
                    r#"Fresh(service: "m{m}.S", port: "{read}", max_age: {age}),"#
                ));
                invariants.push_str(&format!(
                    r#"Invariant(name: "m{m}_i{k}", expr: "age({read}) <= {age} || !(m{m}.S@run)"),"#
                ));
            }
        }
    }
    format!(
        "System(name: \"wired\", modules: [{modules}], connections: [{connections}], \
         constraints: [{constraints}], properties: [{invariants}])"
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Whatever the wiring, a layer that reads its in ports expands to the core of the one
    /// that reads the out ports they are connected to.
    #[test]
    fn random_wirings_expand_as_their_writers_named(w in wiring()) {
        let connected = core(&wired(&w, false));
        let direct = core(&wired(&w, true));
        // the properties are kept as written: name the writers there too
        let mut renamed = connected;
        for (m, inputs) in w.inputs.iter().enumerate() {
            for (k, (writer, _)) in inputs.iter().enumerate() {
                if let Some(writer) = writer {
                    renamed = renamed.replace(&format!("m{m}.i{k}"), &format!("m{writer}.o"));
                }
            }
        }
        prop_assert_eq!(renamed, direct);
    }
}
