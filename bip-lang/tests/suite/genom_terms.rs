//! GenoM errors and reports in the user's terms: an error in a user's expression inside a
//! generated guard points at what the user wrote, numbers too large for what they set are
//! errors at the number, messages name modules and ids fields (not generated atoms), long
//! generated guards load, and constraints show with their names as written.

use crate::support;
use support::errors::{assert_error, first_error};

use bip_lang::{expand_str, load_str};

/// One module with an activity gated by a `Guard`, a function, an out port and ids.
const LAYER: &str = r#"System(
    name: "terms",
    modules: [
        (
            name: "arm",
            ids: [(name: "level", ty: Int(0, 3)), (name: "goal", ty: Int(0, 3))],
            tasks: [(name: "t", period: 1)],
            ports: [(name: "pose")],
            services: [
                (name: "Move", kind: Activity, task: "t",
                 codels: [
                     (state: "start", yields: ["pause::go"], writes: ["goal"]),
                     (state: "go",    yields: ["pause::go", "ether"], writes: ["pose"]),
                     (state: "stop",  yields: ["ether"]),
                 ]),
                (name: "Halt", kind: Function, interrupts: ["Move"]),
            ],
        ),
    ],
    constraints: [
        Guard(service: "arm.Move", when: "arm.level < 3"),
    ],
    properties: [DeadlockFree],
)"#;

fn with(from: &str, to: &str) -> String {
    assert!(LAYER.contains(from), "`{from}` is not in the model");
    LAYER.replacen(from, to, 1)
}

/// The (line, column) of the first occurrence of `needle` in `text`, as diagnostics count.
fn position(text: &str, needle: &str) -> (usize, usize) {
    let at = text.find(needle).expect("the needle is in the text");
    let line = text[..at].matches('\n').count() + 1;
    let col = at - text[..at].rfind('\n').map_or(0, |p| p + 1) + 1;
    (line, col)
}

#[test]
fn the_base_layer_loads() {
    load_str("terms.ron", LAYER).unwrap_or_else(|e| panic!("{}", e.summary()));
}

#[test]
fn an_error_in_a_guard_condition_points_into_it_once() {
    // `when` is placed inside the guard of every codel of Move (behind the stop path's
    // `arm_Move.stopping ||`) and in the engine's map: one error, where it was written
    let text = with("arm.level < 3", "arm.level < 3 && door@open");
    let err = load_str("bad.ron", &text).expect_err("an unknown component");
    assert_eq!(err.errors().len(), 1, "{}", err.summary());
    let (msg, covered, pos) = first_error(&text);
    assert!(msg.contains("unknown component `door`"), "{msg}");
    assert_eq!(covered, "door");
    assert_eq!(pos, position(&text, "door@open"));
    // a type error in it, too: the user's subexpression, not the generated `||`
    let text = with("arm.level < 3", "arm.level + 1");
    let (msg, covered, pos) = first_error(&text);
    assert!(
        msg.contains("expected a boolean, found an integer") || msg.contains("needs a boolean"),
        "{msg}"
    );
    assert_eq!(covered, "arm.level + 1");
    assert_eq!(pos, position(&text, "arm.level + 1"));
}

#[test]
fn an_unknown_ids_field_is_named_by_its_module() {
    let text = with(
        "properties: [DeadlockFree]",
        r#"properties: [Invariant(name: "i", expr: "arm.speed < 2")]"#,
    );
    let (msg, covered, _) = first_error(&text);
    assert_eq!(msg, "module `arm` has no ids field `speed`");
    assert_eq!(covered, "speed");
    let err = load_str("bad.ron", &text).expect_err("rejected");
    let help = err.errors()[0].help.clone().unwrap_or_default();
    assert_eq!(help, "its ids fields are: level, goal");
    // in a guard condition too, never `atom Module_arm`
    assert_error(
        &with("arm.level < 3", "arm.speed < 3"),
        "module `arm` has no ids field `speed`",
        "speed",
    );
}

#[test]
fn an_unknown_genom_field_points_to_the_genom_page() {
    let text = with(
        r#"(name: "Halt", kind: Function"#,
        r#"(name: "Halt", knd: Function"#,
    );
    let err = load_str("bad.ron", &text).expect_err("rejected");
    let e = &err.errors()[0];
    assert!(e.message.contains("knd"), "{}", e.message);
    assert_eq!(
        e.help.as_deref(),
        Some("see docs/model.md, \"The GenoM layer\" for the fields of each part of a model")
    );
    assert_eq!(err.positions()[0].0, position(&text, "knd").0);
    // a field of the core still points to the model page
    let text = with(r#"name: "terms","#, r#"name: "terms", atomz: {},"#);
    let err = load_str("bad.ron", &text).expect_err("rejected");
    assert_eq!(
        err.errors()[0].help.as_deref(),
        Some("see docs/model.md for the fields of each part of a model")
    );
}

#[test]
fn an_age_cap_that_does_not_fit_is_an_error_at_the_number() {
    // ages count to one more than the largest constant they are compared with
    let max = "9223372036854775807";
    let fresh = with(
        r#"Guard(service: "arm.Move", when: "arm.level < 3"),"#,
        &format!(r#"Fresh(service: "arm.Move", port: "arm.pose", max_age: {max}),"#),
    );
    let (msg, covered, pos) = first_error(&fresh);
    assert_eq!(msg, format!("an age cannot be compared with {max}"));
    assert_eq!(covered, max);
    assert_eq!(pos, position(&fresh, max));
    let compared = with("arm.level < 3", &format!("age(arm.pose) <= {max}"));
    let (msg, covered, _) = first_error(&compared);
    assert_eq!(msg, format!("an age cannot be compared with {max}"));
    assert_eq!(covered, max);
    // one less fits
    let fits = with(
        r#"Guard(service: "arm.Move", when: "arm.level < 3"),"#,
        r#"Fresh(service: "arm.Move", port: "arm.pose", max_age: 9223372036854775806),"#,
    );
    load_str("fits.ron", &fits).unwrap_or_else(|e| panic!("{}", e.summary()));
}

#[test]
fn a_codel_writing_a_full_64_bit_ids_field_is_refused() {
    // 2^64 values: counted without wrapping, so the 1,024-value limit holds
    let text = with(
        "Int(0, 3)), (name: \"goal\", ty: Int(0, 3))",
        "Int(0, 3)), (name: \"goal\", ty: Int(-9223372036854775808, 9223372036854775807))",
    );
    let (msg, covered, pos) = first_error(&text);
    assert_eq!(
        msg,
        "codel `start` may write 18446744073709551616 combinations of ids values; at most 1024"
    );
    assert_eq!(covered, "goal");
    let (line, col) = position(&text, r#"writes: ["goal"]"#);
    assert_eq!(pos, (line, col + r#"writes: [""#.len()));
}

/// `n` activities of one module, all in one `AtMost`.
fn many_activities(n: usize) -> String {
    let services: Vec<String> = (0..n)
        .map(|k| {
            format!(
                r#"(name: "S{k}", kind: Activity, task: "t", codels: [(state: "start", yields: ["ether"])])"#
            )
        })
        .collect();
    let names: Vec<String> = (0..n).map(|k| format!("\"m.S{k}\"")).collect();
    format!(
        r#"System(name: "wide", modules: [(name: "m", tasks: [(name: "t", period: 1)], services: [
{}
])],
constraints: [AtMost(max: 2, services: [{}])],
)"#,
        services.join(",\n"),
        names.join(", ")
    )
}

/// An activity that comes `after` `n` functions of its module.
fn long_after(n: usize) -> String {
    let functions: Vec<String> = (0..n)
        .map(|k| format!(r#"(name: "F{k}", kind: Function)"#))
        .collect();
    let after: Vec<String> = (0..n).map(|k| format!("\"F{k}\"")).collect();
    format!(
        r#"System(name: "after", modules: [(name: "m", tasks: [(name: "t", period: 1)], services: [
{},
(name: "S", kind: Activity, task: "t", after: [{}], codels: [(state: "start", yields: ["ether"])])
])],
properties: [DeadlockFree],
)"#,
        functions.join(",\n"),
        after.join(", ")
    )
}

#[test]
fn long_generated_guards_load_and_reload() {
    // the request of `S` is guarded by 250 `done` flags: generated chains are built
    // shallow, so neither the compiler nor the reader of the expanded model refuses them
    let text = long_after(250);
    let sys = load_str("after.ron", &text).unwrap_or_else(|e| panic!("{}", e.summary()));
    let refusals = sys
        .genom
        .as_ref()
        .and_then(|g| g.service("m", "S"))
        .map(|s| s.refusals.len());
    assert_eq!(refusals, Some(251), "250 `after`s and `already requested`");
    let expanded = expand_str("after.ron", &text).expect("expands");
    let printed = expanded.to_ron().expect("prints");
    let again = load_str("after-core.ron", &printed).unwrap_or_else(|e| panic!("{}", e.summary()));
    assert_eq!(again.slot_ranges(), sys.slot_ranges());
    assert_eq!(again.interactions.len(), sys.interactions.len());
}

#[test]
fn at_most_over_250_activities_guards_each_start_with_a_shallow_sum() {
    // the start of each activity counts the 249 others; (the core refuses this layer for
    // the number of priority rules its codels' declared order closes into, another limit)
    let text = many_activities(250);
    let def = bip_lang::parse_str("wide.ron", &text).expect("parses");
    let expansion = bip_lang::expand(&def).unwrap_or_else(|e| panic!("{e:?}"));
    let start = expansion
        .def
        .connectors
        .iter()
        .find(|c| c.name.as_str() == "m_S7_start")
        .and_then(|c| c.guard.as_ref())
        .expect("a guarded start")
        .to_string();
    assert!(start.ends_with(" < 2"), "{start}");
    assert_eq!(start.matches("@ether ? 0 : 1").count(), 249);
    let reread = bip_lang::expr::parse_expr(&start).expect("the printed guard reads back");
    assert_eq!(reread.to_string(), start);
}

#[test]
fn constraints_show_with_their_names_as_written() {
    let sys = load_str(
        "named.ron",
        &with(
            r#"Guard(service: "arm.Move", when: "arm.level < 3"),"#,
            r#"Guard(name: "charged", service: "arm.Move", when: "arm.level < 3"),"#,
        ),
    )
    .unwrap_or_else(|e| panic!("{}", e.summary()));
    let codel = sys
        .genom
        .as_ref()
        .and_then(|g| g.codel("arm", "Move", "go"))
        .expect("the codel");
    let shown: Vec<String> = codel.holds.iter().map(ToString::to_string).collect();
    assert_eq!(
        shown,
        [r#"charged (line 21): Guard(service: "arm.Move", when: "arm.level < 3")"#]
    );
    // without a name: its line and the constraint as written
    let sys = load_str("unnamed.ron", LAYER).expect("loads");
    let codel = sys
        .genom
        .as_ref()
        .and_then(|g| g.codel("arm", "Move", "go"))
        .expect("codel");
    assert_eq!(
        codel.holds[0].to_string(),
        r#"line 21: Guard(service: "arm.Move", when: "arm.level < 3")"#
    );
    // names are unique
    let twice = with(
        r#"Guard(service: "arm.Move", when: "arm.level < 3"),"#,
        r#"Guard(name: "charged", service: "arm.Move", when: "arm.level < 3"),
        Guard(name: "charged", service: "arm.Move", when: "arm.goal < 3"),"#,
    );
    let (msg, covered, pos) = first_error(&twice);
    assert_eq!(msg, "duplicate constraint name `charged`");
    assert_eq!(covered, "charged");
    assert_eq!(pos.0, 22);
}

#[test]
fn an_unknown_port_of_a_generated_component_is_named_by_its_activity() {
    // a connector that joins the tick with a misspelt port of the activity's component
    let text = with(
        "properties: [DeadlockFree]",
        r#"connectors: [(name: "tick", ports: ["arm_Move.tck"])],
    properties: [DeadlockFree]"#,
    );
    let (msg, covered, _) = first_error(&text);
    assert_eq!(msg, "activity `arm.Move` has no port `tck`");
    assert_eq!(covered, "tck");
    let err = load_str("bad.ron", &text).expect_err("rejected");
    let help = err.errors()[0].help.clone().unwrap_or_default();
    assert!(
        help.starts_with("its ports are: request, interrupt, abort, tick"),
        "{help}"
    );
    // and on a connector of its own
    let text = with(
        "properties: [DeadlockFree]",
        r#"connectors: [(name: "halt", ports: ["arm_Move.abrt"])],
    properties: [DeadlockFree]"#,
    );
    assert_error(&text, "activity `arm.Move` has no port `abrt`", "abrt");
}
