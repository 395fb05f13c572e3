//! Inputs that once crashed, hung or were wrongly refused, each reduced to a small
//! reproducer with a time bound: long lines, long chains of operators, deep nesting, huge
//! quantifiers, extreme integers, huge families, old line endings and a byte-order mark.

use std::sync::mpsc;
use std::time::Duration;

use bip_lang::{load_str, LoadError};
use bip_model::eval::Env;
use bip_model::{PropertyKind, System};
use miette::{GraphicalReportHandler, GraphicalTheme};

/// Runs `f` on its own thread (with the default stack a test thread has) and fails if it
/// takes longer than `secs`: a hang is a failure, not a stuck test run.
pub fn within<T: Send + 'static>(secs: u64, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    match rx.recv_timeout(Duration::from_secs(secs)) {
        Ok(v) => v,
        Err(mpsc::RecvTimeoutError::Timeout) => panic!("did not finish within {secs} s"),
        Err(mpsc::RecvTimeoutError::Disconnected) => panic!("panicked"),
    }
}

/// Renders a load error as the command line does.
pub fn render(e: &LoadError) -> String {
    let handler = GraphicalReportHandler::new_themed(GraphicalTheme::unicode_nocolor())
        .with_context_lines(1)
        .with_width(100);
    let mut out = String::new();
    handler
        .render_report(&mut out, &e.diagnostic())
        .expect("renders");
    out
}

fn load(text: String) -> Result<System, LoadError> {
    within(120, move || load_str("m.ron", &text))
}

fn error(text: String) -> (String, (usize, usize), String) {
    match load(text) {
        Ok(_) => panic!("expected an error"),
        Err(e) => {
            let first = e.errors()[0].message.clone();
            (first, e.positions()[0], render(&e))
        }
    }
}

/// `n` components `p[i]` with a boolean `b` (true) and an integer `x` in 0..=3 (1), and
/// `extra` fields (properties, constants…).
fn model(n: usize, constants: &str, guard: &str, action: &str, extra: &str) -> String {
    format!(
        r#"System(
    name: "m",
    constants: {{ {constants} }},
    atoms: {{
        "P": Atom(
            locations: ["s"],
            initial: "s",
            ports: ["go"],
            vars: [(name: "b", ty: Bool, init: true), (name: "x", ty: Int(-9223372036854775808, 3), init: 1)],
            transitions: [(from: "s", port: "go", to: "s", guard: "{guard}", action: "{action}")],
        ),
    }},
    components: [(name: "p", atom: "P", count: {n})],
    connectors: [(name: "c", forall: "i in 0..{n}", ports: ["p[i].go"])],
    {extra}
)"#
    )
}

fn invariant(n: usize, expr: &str) -> String {
    model(
        n,
        "",
        "true",
        "",
        &format!(r#"properties: [Invariant(name: "inv", expr: "{expr}")],"#),
    )
}

/// The first property's expression evaluated in the initial state.
fn initially(sys: &System) -> i64 {
    let state = sys.initial_state();
    invariant_of(sys)
        .eval(&mut Env::new(state.slots(), 0))
        .expect("evaluates")
}

fn invariant_of(sys: &System) -> &bip_model::eval::Expr {
    match &sys.properties[0].kind {
        PropertyKind::Invariant(e) => e,
        other => panic!("expected an invariant, got {other:?}"),
    }
}

#[test]
fn an_error_past_column_65535_prints_an_excerpt_of_its_line() {
    let text = format!("System(name: \"m\",\n{}x)\n", " ".repeat(65_536));
    let (_, (line, col), out) = error(text);
    assert_eq!((line, col), (2, 65_537));
    assert!(out.contains("m.ron:2:65537"), "{out}");
    assert!(out.contains('x') && out.contains('…'), "{out}");
    assert!(out.lines().all(|l| l.chars().count() < 400), "{out}");
}

#[test]
fn a_label_longer_than_65535_characters_prints() {
    let name = "a".repeat(70_000);
    let text = model(1, "", "true", "", "").replace(r#"atom: "P""#, &format!(r#"atom: "{name}""#));
    let (msg, (line, _), out) = error(text);
    assert!(msg.contains("unknown atom"), "{msg}");
    assert_eq!(line, 13);
    assert!(
        out.contains("unknown atom") && out.contains("m.ron:13:"),
        "{out}"
    );
    assert!(out.len() < 200_000, "{}", out.len());
}

#[test]
fn a_flat_chain_of_100000_operands_is_not_nesting() {
    let n = 100_000;
    for (op, term, want) in [
        ("&&", "p[K].b", 1),
        ("||", "!p[K].b", 0),
        ("+", "p[K].x", n as i64),
    ] {
        let terms: Vec<String> = (0..n).map(|k| term.replace('K', &k.to_string())).collect();
        let expr = if op == "+" {
            format!("{} == {want}", terms.join(" + "))
        } else {
            terms.join(&format!(" {op} "))
        };
        let sys = load(invariant(n, &expr)).unwrap_or_else(|e| panic!("{}", e.summary()));
        let v = within(60, move || initially(&sys));
        assert_eq!(v, if op == "+" { 1 } else { want }, "{op}");
    }
}

#[test]
fn a_long_arithmetic_chain_overflows_where_its_left_to_right_reading_does() {
    let sys = load(model(1, "", "true", "", r#"properties: [Invariant(name: "inv", expr: "p[0].x + 9223372036854775807 - 1 - 1 - 1 - 1 - 1 - 1 - 1 - 1 > 0")],"#))
        .unwrap_or_else(|e| panic!("{}", e.summary()));
    let state = sys.initial_state();
    assert!(invariant_of(&sys)
        .eval(&mut Env::new(state.slots(), 0))
        .is_err());
}

#[test]
fn nesting_is_limited_just_at_the_limit() {
    let depth = bip_lang::expr::MAX_DEPTH;
    // the index inside `p[0].b` is one level more
    let nest = |d: usize| "(".repeat(d) + "p[0].b" + &")".repeat(d);
    load(invariant(1, &nest(depth - 2))).unwrap_or_else(|e| panic!("{}", e.summary()));
    let (msg, (line, _), _) = error(invariant(1, &nest(depth + 1)));
    assert!(msg.contains("nested more than"), "{msg}");
    assert_eq!(line, 15);
    let not = |d: usize| "!".repeat(d) + "p[0].b";
    load(invariant(1, &not(depth - 4))).unwrap_or_else(|e| panic!("{}", e.summary()));
    assert!(error(invariant(1, &not(depth + 1))).0.contains("nested"));
    let cond = |d: usize| "p[0].b ? true : ".repeat(d) + "false";
    load(invariant(1, &cond(depth - 4))).unwrap_or_else(|e| panic!("{}", e.summary()));
    assert!(error(invariant(1, &cond(depth + 1))).0.contains("nested"));
    let index = |d: usize| "p[".repeat(d) + "0" + &"].x".repeat(d) + " >= 0";
    assert!(error(invariant(1, &index(depth + 1))).0.contains("nested"));
}

#[test]
fn a_quantifier_over_a_huge_range_is_refused_at_its_span() {
    let q = "forall i in 0..9223372036854775807: true";
    for text in [
        model(1, &format!(r#""Q": "{q}""#), "true", "", ""),
        model(1, "", q, "", ""),
        invariant(1, q),
        invariant(1, "(sum i in 0..1000000000000: i) > 0"),
        invariant(
            1,
            "forall i in 0..10000: forall j in 0..10000: i != j || i == j",
        ),
    ] {
        let (msg, _, out) = error(text);
        assert!(msg.contains("at most 10000000 times"), "{msg}");
        assert!(out.contains("m.ron:"), "{out}");
    }
    let (_, (line, col), _) = error(invariant(1, q));
    assert_eq!((line, col), (15, 48));
    // within the limit, it loads and evaluates
    let sys = load(invariant(1, "(sum i in 0..1000000: i) == 499999500000"))
        .unwrap_or_else(|e| panic!("{}", e.summary()));
    assert_eq!(initially(&sys), 1);
}

#[test]
fn the_minus_belongs_to_the_literal_in_actions_too() {
    let sys = load(model(1, "", "true", "x = -9223372036854775808", ""))
        .unwrap_or_else(|e| panic!("{}", e.summary()));
    assert_eq!(sys.atoms[0].transitions.len(), 1);
    let (msg, _, _) = error(model(1, "", "true", "x = 9223372036854775808", ""));
    assert!(msg.contains("64 bits"), "{msg}");
}

#[test]
fn extreme_bounds_are_errors_not_overflows() {
    let (msg, _, _) = error(model(1, "", "true", "", "").replace(
        r#"forall: "i in 0..1""#,
        r#"forall: "i in -9223372036854775808..9223372036854775807""#,
    ));
    assert!(msg.contains("at most 10000000"), "{msg}");
    let (msg, _, _) = error(model(
        1,
        r#""M": "-9223372036854775808 - 1""#,
        "true",
        "",
        "",
    ));
    assert!(msg.contains("overflow"), "{msg}");
}

#[test]
fn families_together_are_limited_before_they_are_built() {
    let comps: Vec<String> = (0..6)
        .map(|k| format!(r#"(name: "f{k}", atom: "P", count: 10000000)"#))
        .collect();
    let text = model(1, "", "true", "", "").replace(
        r#"(name: "p", atom: "P", count: 1)"#,
        &format!(r#"(name: "p", atom: "P", count: 1), {}"#, comps.join(", ")),
    );
    let (msg, (line, _), _) = error(text);
    assert!(msg.contains("at most 10000000 are allowed in all"), "{msg}");
    assert_eq!(line, 13);
    // fewer components, but with many variables each
    let vars: Vec<String> = (0..20)
        .map(|k| format!(r#"(name: "v{k}", ty: Bool)"#))
        .collect();
    let text = model(1, "", "true", "", "")
        .replace(
            r#"vars: [(name: "b""#,
            &format!(r#"vars: [{}, (name: "b""#, vars.join(", ")),
        )
        .replace(
            "count: 1)",
            r#"count: 1), (name: "q", atom: "P", count: 5000000)"#,
        );
    let (msg, (line, _), _) = error(text);
    assert!(msg.contains("locations and variables"), "{msg}");
    assert_eq!(line, 13);
}

#[test]
fn old_mac_line_endings_and_a_byte_order_mark_load() {
    let text = model(1, "", "true", "", "");
    let cr = format!("// a comment\n{text}").replace('\n', "\r");
    load(cr.clone()).unwrap_or_else(|e| panic!("{}", e.summary()));
    load(format!("\u{feff}{text}")).unwrap_or_else(|e| panic!("{}", e.summary()));
    load(format!("\u{feff}{}", cr)).unwrap_or_else(|e| panic!("{}", e.summary()));
    // positions count lines and columns as an editor shows them
    let bad = cr.replace(r#"atom: "P""#, r#"atom: "Q""#);
    let (_, pos, out) = error(bad.clone());
    assert_eq!(pos, (14, 37));
    assert!(out.contains("m.ron:14:37"), "{out}");
    let (_, pos, _) = error(format!("\u{feff}{bad}"));
    assert_eq!(pos, (14, 37));
}
