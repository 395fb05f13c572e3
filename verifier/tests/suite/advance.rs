//! Time steps that stand for several units (`advance`): bounded response counts units in
//! both methods, and an advance below 1 is a range error in both.

use bip_lang::load_str;
use bip_model::{System, Verdict as TraceVerdict};
use bip_verifier::{verify, Method, Options, PropertyVerdict, Report, RANGE_ERRORS};

/// A clock whose tick from `k` stands for `advance` units and counts `k` round 0..5,
/// recording the advance in `last`.
pub(super) fn stepper(advance: &str, properties: &str) -> System {
    let text = format!(
        r#"
System(
    name: "stepper",
    atoms: {{
        "S": Atom(locations: ["s"], initial: "s", ports: ["tick"],
            vars: [(name: "k", ty: Int(0, 4), init: 0), (name: "last", ty: Int(0, 5), init: 5)],
            transitions: [(from: "s", port: "tick", to: "s")]),
    }},
    components: [(name: "c", atom: "S")],
    connectors: [(name: "tick", ports: ["c.tick"], role: Time, advance: "{advance}",
                  action: "c.k = (c.k + 1) % 5; c.last = advance")],
    properties: [{properties}],
)
"#
    );
    load_str("stepper.ron", &text).unwrap_or_else(|e| panic!("{}", e.summary()))
}

fn both(sys: &System) -> [Report; 2] {
    [Method::Explicit, Method::Symbolic]
        .map(|m| verify(sys, m, &Options::default(), &|_| {}).unwrap())
}

/// The trigger comes with the tick into `k == 1`; the ticks from 1 and 2 stand for 2 and
/// 3 units: the response `k == 3` comes 5 units later.
const WITHIN: &str = r#"
    Response(name: "in_five", trigger: "c.k == 1", response: "c.k == 3", within: 5),
    Response(name: "in_four", trigger: "c.k == 1", response: "c.k == 3", within: 4),
    Invariant(name: "last", expr: "c.last == (c.k == 0 ? 5 : c.k)")"#;

#[test]
fn bounded_response_counts_the_units_of_each_tick() {
    let sys = stepper("c.k + 1", WITHIN);
    for r in both(&sys) {
        let method = &r.method;
        let p = |name: &str| &r.property(name).unwrap().verdict;
        assert!(p("in_five").holds(), "{method}: {:?}", p("in_five"));
        // the action read the advance of the state the tick left
        assert!(p("last").holds(), "{method}: {:?}", p("last"));
        let PropertyVerdict::Fails { trace: Some(t), .. } = p("in_four") else {
            panic!("{method}: in_four should fail: {:?}", p("in_four"));
        };
        // the tick from k = 2 (3 units) takes the wait to 5
        assert_eq!(t.steps.len(), 3, "{method}");
        t.replay(&sys).unwrap();
    }
    // one unit a tick: the response comes 2 later
    let one = stepper("1", WITHIN.replace("within: 4", "within: 1").as_str());
    for r in both(&one) {
        assert!(!r.property("in_four").unwrap().verdict.holds());
        assert!(r.property("in_five").unwrap().verdict.holds());
    }
}

#[test]
fn an_advance_below_one_is_a_range_error_in_both_methods() {
    // from k = 3 the tick would stand for 0 units
    let sys = stepper("3 - c.k", r#"Invariant(name: "any", expr: "true")"#);
    for r in both(&sys) {
        let method = &r.method;
        let PropertyVerdict::Fails {
            trace: Some(t),
            reason,
        } = &r.property(RANGE_ERRORS).unwrap().verdict
        else {
            panic!("{method}: {:?}", r.property(RANGE_ERRORS));
        };
        assert!(
            reason.contains("advance = 0 is below 1"),
            "{method}: {reason}"
        );
        assert!(
            matches!(&t.verdict, TraceVerdict::RangeError(_)),
            "{method}"
        );
        // three ticks to k = 3, where the fourth fails
        assert_eq!(t.steps.len(), 3, "{method}");
    }
}
