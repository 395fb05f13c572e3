//! Bad input: every case gets an error that points at the offending text, never a panic.

use crate::support;
use support::errors::{assert_error, first_error};

use bip_lang::{load_file, load_str, LoadError};

/// A small valid model with `{ATOM}`-style holes filled by each test.
fn model(atoms: &str, components: &str, connectors: &str, extra: &str) -> String {
    format!(
        r#"System(
    name: "m",
    constants: {{ "N": 3 }},
    atoms: {{
{atoms}
    }},
    components: [{components}],
    connectors: [{connectors}],
    {extra}
)"#
    )
}

const FORK: &str = r#"        "Fork": Atom(
            locations: ["free", "taken"],
            initial: "free",
            ports: ["take", "release"],
            vars: [(name: "uses", ty: Int(0, 5), init: 0)],
            transitions: [
                (from: "free",  port: "take",    to: "taken", action: "uses = uses + 1"),
                (from: "taken", port: "release", to: "free"),
            ],
        ),"#;

fn ok_model() -> String {
    model(
        FORK,
        r#"(name: "fork", atom: "Fork", count: "N")"#,
        r#"(name: "pair", forall: "i in 0..N", ports: ["fork[i].take", "fork[(i+1)%N].take"])"#,
        "",
    )
}

#[test]
fn the_base_model_loads() {
    load_str("ok.ron", &ok_model()).unwrap_or_else(|e| panic!("{}", e.summary()));
}

#[test]
fn ron_syntax_error() {
    let text = ok_model().replace("initial: \"free\",", "initial: \"free\"");
    let (msg, _, (line, col)) = first_error(&text);
    assert!(msg.to_lowercase().contains("comma"), "{msg}");
    assert_eq!((line, col), (8, 13));
}

#[test]
fn unknown_field_is_not_ignored() {
    let text = ok_model().replace("initial: \"free\",", "initial: \"free\", gaurd: \"x\",");
    let (msg, _, (line, _)) = first_error(&text);
    assert!(msg.contains("gaurd"), "{msg}");
    assert_eq!(line, 7);
}

#[test]
fn unknown_atom() {
    let text = ok_model().replace(r#"atom: "Fork""#, r#"atom: "Frok""#);
    assert_error(&text, "unknown atom `Frok`", "Frok");
}

#[test]
fn unknown_component() {
    let text = ok_model().replace("\"fork[i].take\"", "\"frok[i].take\"");
    assert_error(&text, "unknown component family `frok`", "frok");
}

#[test]
fn unknown_port() {
    let text = ok_model().replace("\"fork[(i+1)%N].take\"", "\"fork[(i+1)%N].tak\"");
    assert_error(&text, "has no port `tak`", "tak");
}

#[test]
fn unknown_location() {
    let text = ok_model().replace(r#"to: "free")"#, r#"to: "fre")"#);
    assert_error(&text, "has no location `fre`", "fre");
    let text = model(
        FORK,
        r#"(name: "fork", atom: "Fork", count: "N")"#,
        "",
        r#"properties: [Invariant(name: "p", expr: "fork[0]@tken || true")]"#,
    );
    assert_error(&text, "has no location `tken`", "tken");
}

#[test]
fn unknown_variable() {
    let text = ok_model().replace("uses = uses + 1", "uses = usse + 1");
    assert_error(&text, "unknown name `usse`", "usse");
    let text = model(
        FORK,
        r#"(name: "fork", atom: "Fork", count: "N")"#,
        "",
        r#"properties: [Invariant(name: "p", expr: "fork[1].used < 5")]"#,
    );
    assert_error(&text, "has no variable `used`", "used");
}

#[test]
fn unknown_constant() {
    let text = ok_model().replace(r#"count: "N""#, r#"count: "M""#);
    assert_error(&text, "unknown name `M`", "M");
}

#[test]
fn duplicate_names() {
    let text = ok_model().replace(r#"["free", "taken"]"#, r#"["free", "taken", "free"]"#);
    assert_error(&text, "duplicate location `free`", "free");
    let text = ok_model().replace(r#"["take", "release"]"#, r#"["take", "take"]"#);
    assert_error(&text, "duplicate port `take`", "take");
    let text = ok_model().replace(
        r#"(name: "fork", atom: "Fork", count: "N")"#,
        r#"(name: "fork", atom: "Fork", count: "N"), (name: "fork", atom: "Fork")"#,
    );
    let (msg, covered, _) = first_error(&text);
    assert!(msg.contains("duplicate component `fork`"), "{msg}");
    assert_eq!(covered, "fork");
    let text = format!("{}\n", ok_model()).replace(
        r#"constants: { "N": 3 }"#,
        r#"constants: { "N": 3, "N": 4 }"#,
    );
    assert_error(&text, "duplicate constant `N`", "N");
    let atoms = format!("{FORK}\n{FORK}");
    let text = model(&atoms, r#"(name: "fork", atom: "Fork")"#, "", "");
    assert_error(&text, "duplicate atom `Fork`", "Fork");
    let text = ok_model().replace(
        r#"(name: "pair", forall"#,
        r#"(name: "pair", ports: ["fork[0].release"]), (name: "pair", forall"#,
    );
    assert_error(&text, "duplicate connector `pair`", "pair");
    let text = model(
        FORK,
        r#"(name: "fork", atom: "Fork")"#,
        "",
        r#"properties: [Invariant(name: "p", expr: "true"), Reachable(name: "p", expr: "true")]"#,
    );
    assert_error(&text, "duplicate property `p`", "p");
}

#[test]
fn type_errors() {
    // an integer where a boolean is needed
    let text = ok_model().replace("to: \"taken\",", "to: \"taken\", guard: \"uses + 1\",");
    assert_error(&text, "expected a boolean, found an integer", "uses + 1");
    // a boolean where an integer is needed
    let text = ok_model().replace("uses = uses + 1", "uses = uses + (uses > 2)");
    assert_error(
        &text,
        "`+` needs an integer, but this is a boolean",
        "(uses > 2)",
    );
    let text = ok_model().replace("uses = uses + 1", "uses = uses > 2");
    assert_error(&text, "expected an integer, found a boolean", "uses > 2");
    let text = ok_model().replace("uses = uses + 1", "uses = uses == true");
    assert_error(
        &text,
        "cannot compare an integer with a boolean",
        "uses == true",
    );
}

#[test]
fn constant_index_outside_its_family() {
    let text = ok_model().replace(r#""fork[(i+1)%N].take""#, r#""fork[N].take""#);
    assert_error(
        &text,
        "index 3 is outside `fork`, whose indices run from 0 to 2 (in instance i = 0)",
        "N",
    );
}

#[test]
fn init_outside_its_range() {
    let text = ok_model().replace("init: 0)", "init: 9)");
    assert_error(
        &text,
        "initial value 9 of `uses` is outside its range Int(0, 5)",
        "9",
    );
    let text = ok_model().replace(
        r#"(name: "fork", atom: "Fork", count: "N")"#,
        r#"(name: "fork", atom: "Fork", count: "N", vars_init: { "uses": "self_index * 3" })"#,
    );
    let (msg, covered, _) = first_error(&text);
    assert!(msg.contains("initial value 6 of `uses`"), "{msg}");
    assert_eq!(covered, "self_index * 3");
}

#[test]
fn non_constant_count_and_forall_bound() {
    let text = ok_model().replace(r#"count: "N""#, r#"count: "fork[0].uses""#);
    assert_error(&text, "components cannot be read here", "fork[0]");
    let text = ok_model().replace(r#""i in 0..N""#, r#""i in 0..fork[0].uses""#);
    assert_error(&text, "components cannot be read here", "fork[0]");
    let text = model(
        FORK,
        r#"(name: "fork", atom: "Fork", count: "N")"#,
        "",
        r#"properties: [Invariant(name: "p", expr: "forall i in 0..fork[0].uses: true")]"#,
    );
    assert_error(&text, "quantifier bounds must be constant", "fork[0].uses");
}

#[test]
fn component_twice_in_one_connector() {
    let text = ok_model().replace("\"fork[(i+1)%N].take\"", "\"fork[(i+3)%N].release\"");
    let (msg, covered, _) = first_error(&text);
    assert!(
        msg.contains("component `fork[0]` appears twice in connector `pair`"),
        "{msg}"
    );
    assert!(msg.contains("i = 0"), "names the instance: {msg}");
    assert_eq!(covered, "fork[(i+3)%N].release");
}

#[test]
fn priority_cycle_is_printed() {
    let text = model(
        FORK,
        r#"(name: "fork", atom: "Fork", count: "N")"#,
        r#"(name: "a", ports: ["fork[0].take"]), (name: "b", ports: ["fork[1].take"]),
           (name: "c", forall: "i in 0..N", ports: ["fork[i].release"])"#,
        r#"priorities: [(low: "a", high: "b"), (low: "b", high: "c[2]", when: "fork[0].uses > 1"),
                       (low: "c", high: "a")]"#,
    );
    let err = load_str("cycle.ron", &text).expect_err("a cycle");
    let e = &err.errors()[0];
    assert!(e.message.contains("cycle"), "{}", e.message);
    for p in ["a < b", "b < c[2]", "c < a"] {
        assert!(
            e.message.contains(p),
            "the cycle lists `{p}`: {}",
            e.message
        );
    }
    assert_eq!(e.notes.len(), 2, "the other two priorities are pointed at");
}

#[test]
fn empty_and_missing_files() {
    let (msg, _, _) = first_error("");
    assert!(msg.contains("empty"), "{msg}");
    let (msg, _, _) = first_error("  // just a comment\n /* and another */ \n");
    assert!(msg.contains("empty"), "{msg}");
    let err = load_file("/nonexistent/dir/model.ron").expect_err("missing");
    assert!(matches!(err, LoadError::Io { .. }));
    assert!(
        err.to_string().contains("/nonexistent/dir/model.ron"),
        "{err}"
    );
}

/// `main` returning a load error with `?` prints its `Debug`: the errors, one line each
/// with their positions, never the model's text.
#[test]
fn a_load_errors_debug_is_its_summary() {
    let text = ok_model().replace("uses = uses + 1", "uses = uses + * 1");
    let err = load_str("model.ron", &text).expect_err("a syntax error");
    let debug = format!("{err:?}");
    assert_eq!(debug, err.summary());
    assert!(debug.starts_with("model.ron:"), "{debug}");
    assert!(!debug.contains("uses = uses"), "no model text: {debug}");
    let err = load_file("/nonexistent/dir/model.ron").expect_err("missing");
    assert_eq!(format!("{err:?}"), err.to_string());
}

#[test]
fn expression_syntax_errors_point_inside_the_string() {
    let text = ok_model().replace("uses = uses + 1", "uses = uses + * 1");
    let (msg, covered, _) = first_error(&text);
    assert!(msg.starts_with("syntax error"), "{msg}");
    assert_eq!(covered, "*");
}

#[test]
fn invalid_and_reserved_names() {
    let text = ok_model().replace(r#"["take", "release"]"#, r#"["take-it", "release"]"#);
    assert_error(&text, "`take-it` is not a valid port name", "take-it");
    let text = ok_model().replace(r#"(name: "uses""#, r#"(name: "count""#);
    assert_error(&text, "reserved word", "count");
}

#[test]
fn several_errors_are_all_reported() {
    let text = ok_model()
        .replace(r#"to: "free")"#, r#"to: "fre")"#)
        .replace("\"fork[(i+1)%N].take\"", "\"fork[(i+1)%N].tak\"");
    let err = load_str("two.ron", &text).expect_err("fails");
    assert_eq!(err.errors().len(), 2, "{}", err.summary());
    let summary = err.summary();
    assert!(summary.contains("two.ron:12:"), "{summary}");
}

#[test]
fn pathological_nesting_is_an_error() {
    let deep = format!("{}true{}", "(".repeat(5000), ")".repeat(5000));
    let text = model(
        FORK,
        r#"(name: "fork", atom: "Fork")"#,
        "",
        &format!(r#"properties: [Invariant(name: "p", expr: "{deep}")]"#),
    );
    let (msg, _, _) = first_error(&text);
    assert!(msg.contains("nested"), "{msg}");
    let ron_deep = format!(
        "System(name: \"x\", components: {}{})",
        "[".repeat(10_000),
        "]".repeat(10_000)
    );
    let (msg, _, _) = first_error(&ron_deep);
    assert!(!msg.is_empty());
}

/// No quadratic blow-up: a model with 60,000 components and 60,000 connectors loads. (Not a
/// timed test: were the loader quadratic this would take hours, not a second.)
#[test]
fn huge_file_loads() {
    let n = 60_000;
    let mut components = String::new();
    let mut connectors = String::new();
    for i in 0..n {
        components.push_str(&format!("(name: \"f{i}\", atom: \"Fork\"),\n"));
        connectors.push_str(&format!(
            "(name: \"c{i}\", ports: [\"f{i}.take\", \"f{}.release\"]),\n",
            (i + 1) % n
        ));
    }
    let text = model(FORK, &components, &connectors, "");
    let sys = load_str("huge.ron", &text).unwrap_or_else(|e| panic!("{}", e.summary()));
    assert_eq!(sys.components.len(), n);
    assert_eq!(sys.interactions.len(), n);
    // and an error near the end of a huge file still has its position
    let bad = text.replace("\"f59999.take\"", "\"f59999.tak\"");
    let err = load_str("huge.ron", &bad).expect_err("fails");
    let (line, _) = err.positions()[0];
    assert!(line > 2 * n - 10, "line {line}");
}

#[test]
fn a_connector_that_fails_is_reported_once_not_again_by_its_priorities() {
    let text = model(
        FORK,
        r#"(name: "fork", atom: "Fork", count: "N")"#,
        r#"(name: "pair", forall: "i in 0..N", ports: ["fork[i].take", "fork[(i+1)%N].take"], guard: "fork[i].usse > 0"),
           (name: "back", ports: ["fork[0].release"])"#,
        r#"priorities: [(low: "back", high: "pair"), (low: "back", high: "pair[1]")],"#,
    );
    let err = load_str("bad.ron", &text).expect_err("rejected");
    assert_eq!(err.errors().len(), 1, "{}", err.summary());
    assert_error(&text, "has no variable `usse`", "usse");
}

#[test]
fn advance_of_time_steps() {
    let pair = r#"ports: ["fork[i].take", "fork[(i+1)%N].take"])"#;
    let with = |fields: &str| {
        let ports = pair.trim_end_matches(')');
        ok_model().replace(pair, &format!("{ports}, {fields})"))
    };
    let ok =
        with(r#"role: Time, advance: "fork[i].uses + 1", action: "fork[i].uses = advance % 5""#);
    load_str("ok.ron", &ok).unwrap_or_else(|e| panic!("{}", e.summary()));
    assert_error(
        &with(r#"advance: "2""#),
        "connector `pair` has an `advance` but is not a time step",
        "2",
    );
    assert_error(
        &with(r#"role: Time, advance: "i - 1""#),
        "`advance` is -1 (in instance i = 0); a time step stands for at least 1 unit",
        "i - 1",
    );
    assert_error(
        &with(r#"role: Time, advance: "fork[i]@free""#),
        "expected an integer",
        "fork[i]@free",
    );
    // only a time step's action reads its advance
    assert_error(
        &with(r#"action: "fork[i].uses = advance""#),
        "unknown name `advance`",
        "advance",
    );
}
