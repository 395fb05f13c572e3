//! Response properties in the language: `Response`, `LeadsTo`, and the GenoM layer's
//! `Replies`, `Terminates` and events (`request`, `reply`, `yield`). Bad input gets an
//! error at the offending text in the user's names; the expanded model prints the events
//! as the core's step forms and reloads with the same triggers and responses on every
//! reachable state and step.

use crate::support;
use support::errors::assert_error;

use std::collections::HashSet;

use bip_lang::{expand_str, load_str};
use bip_model::{Happens, State, System};

/// `sick` and `ndd` with a tick, and a slot for properties.
fn genom(properties: &str) -> String {
    format!(
        r#"System(
    name: "layer",
    modules: [
        (
            name: "sick",
            tasks: [(name: "acquire", period: 1)],
            services: [
                (name: "Scan", kind: Activity, task: "acquire",
                 codels: [
                     (state: "start", yields: ["pause::scan"]),
                     (state: "scan",  yields: ["pause::scan", "ether"]),
                 ]),
                (name: "Stop", kind: Function, interrupts: ["Scan"]),
            ],
        ),
        (
            name: "ndd",
            tasks: [(name: "nav", period: 2)],
            services: [
                (name: "GoTo", kind: Activity, task: "nav", interrupts: ["GoTo"],
                 codels: [
                     (state: "start", yields: ["move"]),
                     (state: "move",  yields: ["pause::move", "ether"]),
                     (state: "stop",  yields: ["ether"]),
                 ]),
            ],
        ),
    ],
    properties: [
        {properties}
    ],
)"#
    )
}

const GOOD: &str = r#"Replies(service: "ndd.GoTo"),
        Replies(service: "sick.Stop", within: 0),
        Replies(name: "goto_in_time", service: "ndd.GoTo", within: 6),
        Terminates(service: "sick.Scan"),
        Response(name: "moves", trigger: "request(ndd.GoTo) || request(sick.Scan)", response: "yield(ndd.GoTo.move, pause(move)) || reply(ndd.GoTo)", within: 4),
        LeadsTo(name: "scans", from: "pending(sick.Scan)", to: "yield(sick.Scan.scan, ether) || yield(sick.Scan.start)"),
        LeadsTo(name: "core_forms", from: "changes(true, active(ndd.GoTo))", to: "fires(tick) && changes(ndd.GoTo@move, true)"),"#;

#[test]
fn response_properties_load_with_their_names() {
    let sys = load_str("good.ron", &genom(GOOD)).unwrap_or_else(|e| panic!("{}", e.summary()));
    let names: Vec<&str> = sys.properties.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "Replies(ndd.GoTo)",
            "Replies(sick.Stop, within: 0)",
            "goto_in_time",
            "Terminates(sick.Scan)",
            "moves",
            "scans",
            "core_forms"
        ]
    );
    let spec = |k: usize| {
        sys.properties[k]
            .kind
            .response_spec()
            .expect("a response property")
    };
    assert_eq!(spec(0).within, None);
    assert_eq!(spec(2).within, Some(6));
    assert!(matches!(spec(0).trigger, Happens::Step(_)));
    assert!(matches!(spec(0).response, Happens::State(_)));
    assert!(matches!(spec(3).trigger, Happens::State(_)));
    assert!(matches!(spec(4).response, Happens::Step(p) if p.len() == 3));
}

fn reachable(sys: &System) -> HashSet<State> {
    let mut seen = HashSet::from([sys.initial_state()]);
    let mut todo = vec![sys.initial_state()];
    while let Some(s) = todo.pop() {
        for (_, next) in sys.successors(&s).expect("no range error") {
            if seen.insert(next.clone()) {
                todo.push(next);
            }
        }
    }
    seen
}

#[test]
fn the_expanded_model_reloads_with_the_same_triggers_and_responses() {
    let text = genom(GOOD);
    let sys = load_str("good.ron", &text).unwrap_or_else(|e| panic!("{}", e.summary()));
    let printed = expand_str("good.ron", &text)
        .expect("expands")
        .to_ron()
        .expect("prints");
    assert!(printed.contains("fires(ndd_GoTo_request)"), "{printed}");
    let again =
        load_str("expanded.ron", &printed).unwrap_or_else(|e| panic!("{}\n{printed}", e.summary()));
    let states = reachable(&sys);
    assert!(states.len() > 20);
    let mut seen = [0usize; 2];
    for (p, q) in sys.properties.iter().zip(&again.properties) {
        let (a, b) = (
            p.kind.response_spec().unwrap(),
            q.kind.response_spec().unwrap(),
        );
        assert_eq!(a.within, b.within);
        for s in &states {
            for (x, y) in [(a.trigger, b.trigger), (a.response, b.response)] {
                let here = sys.happens_in(x, s, "p").unwrap();
                assert_eq!(here, again.happens_in(y, s, "p").unwrap());
                for (step, next) in sys.successors(s).unwrap() {
                    let on = sys.happens_on(x, s, step.as_step(), &next, "p").unwrap();
                    assert_eq!(
                        on,
                        again.happens_on(y, s, step.as_step(), &next, "p").unwrap()
                    );
                    seen[usize::from(on)] += 1;
                }
            }
        }
    }
    assert!(
        seen[0] > 0 && seen[1] > 0,
        "steps both match and do not: {seen:?}"
    );
}

#[test]
fn genom_events_point_at_what_is_wrong() {
    let cases = [
        (
            r#"Replies(service: "ndd.Goto")"#,
            "module `ndd` has no service `Goto`",
            "Goto",
        ),
        (
            r#"Replies(service: "nd.GoTo")"#,
            "unknown module `nd`",
            "nd",
        ),
        (
            r#"Terminates(service: "sick.Stop")"#,
            "`sick.Stop` is not an activity",
            "sick.Stop",
        ),
        (
            r#"LeadsTo(name: "a", from: "request(ndd.Goto)", to: "true")"#,
            "module `ndd` has no service `Goto`",
            "Goto",
        ),
        (
            r#"LeadsTo(name: "a", from: "yield(ndd.GoTo.mvoe)", to: "true")"#,
            "activity `ndd.GoTo` has no codel `mvoe`",
            "mvoe",
        ),
        (
            r#"LeadsTo(name: "a", from: "yield(ndd.GoTo.start, ether)", to: "true")"#,
            "codel `start` of `GoTo` does not yield this",
            "ether",
        ),
        (
            r#"LeadsTo(name: "a", from: "yield(sick.Stop.start)", to: "true")"#,
            "`sick.Stop` is not an activity",
            "sick.Stop",
        ),
        (
            r#"LeadsTo(name: "a", from: "request(ndd.GoTo) || active(ndd.GoTo)", to: "true")"#,
            "mixes events and a state condition",
            "request(ndd.GoTo) || active(ndd.GoTo)",
        ),
        (
            r#"LeadsTo(name: "a", from: "reply(ndd)", to: "true")"#,
            "`reply` takes a service",
            "reply(ndd)",
        ),
        (
            r#"Response(name: "a", trigger: "active(ndd.GoTo)", response: "true", within: -1)"#,
            "`within` is -1",
            "-1",
        ),
        (
            r#"Replies(service: "ndd.GoTo", within: "2s")"#,
            "`within` is a duration, but the model has no `tick_ms` to count it in",
            "2s",
        ),
        (
            r#"LeadsTo(name: "a", from: "fires(tock)", to: "true")"#,
            "no connector `tock`",
            "tock",
        ),
        (
            r#"LeadsTo(name: "a", from: "changes(true)", to: "true")"#,
            "`changes` takes two conditions",
            "changes(true)",
        ),
        (
            r#"LeadsTo(name: "a", from: "active(ndd.GoTo)", to: "fires(tick) || ndd.GoTo@move")"#,
            "mixes steps and a state condition",
            "fires(tick) || ndd.GoTo@move",
        ),
        (
            r#"LeadsTo(name: "Replies(ndd.GoTo)", from: "true", to: "true"), Replies(service: "ndd.GoTo")"#,
            "duplicate property `Replies(ndd.GoTo)`",
            "ndd.GoTo",
        ),
    ];
    for (props, words, covered) in cases {
        assert_error(&genom(props), words, covered);
    }
}

/// A bound in real time counts ticks of `tick_ms`: `"600ms"` with a tick of 100 ms is
/// the bound of 6 ticks, reported as written; a duration that is not a whole number of
/// ticks is an error at it, with the nearest bound above.
#[test]
fn a_bound_in_real_time_counts_ticks() {
    let ticked = |props: &str| {
        genom(props).replacen("name: \"layer\",", "name: \"layer\", tick_ms: 100,", 1)
    };
    let bound = |text: &str| {
        let system = load_str("layer.ron", text).unwrap_or_else(|e| panic!("{}", e.summary()));
        let p = &system.properties[0];
        match p.kind {
            bip_model::PropertyKind::Response { within, .. } => (within, p.text.clone()),
            _ => panic!("a response property"),
        }
    };
    let (in_ticks, _) = bound(&ticked(r#"Replies(service: "ndd.GoTo", within: 6)"#));
    let (in_time, text) = bound(&ticked(r#"Replies(service: "ndd.GoTo", within: "600ms")"#));
    assert_eq!((in_ticks, in_time), (Some(6), Some(6)));
    assert_eq!(
        text,
        "every accepted request of ndd.GoTo is replied to within 600 ms"
    );
    let (_, text) = bound(&ticked(
        r#"Response(name: "r", trigger: "request(ndd.GoTo)", response: "reply(ndd.GoTo)", within: "1.2s")"#,
    ));
    assert_eq!(text, "request(ndd.GoTo) → reply(ndd.GoTo) within 1200 ms");
    assert_error(
        &ticked(r#"Replies(service: "ndd.GoTo", within: "650ms")"#),
        "`within` of 650 ms is not a whole number of a tick (`tick_ms`), 100 ms",
        "650ms",
    );
    assert_error(
        &ticked(r#"Replies(service: "ndd.GoTo", within: "2 hours")"#),
        "syntax error",
        "hours",
    );
}

#[test]
fn core_response_properties_point_at_what_is_wrong() {
    let core = |props: &str| {
        format!(
            r#"System(name: "core",
    atoms: {{ "A": Atom(locations: ["a", "b"], initial: "a", ports: ["p"], transitions: [(from: "a", port: "p", to: "b")]) }},
    components: [(name: "x", atom: "A")],
    connectors: [(name: "c", ports: ["x.p"])],
    properties: [{props}],
)"#
        )
    };
    load_str(
        "ok.ron",
        &core(r#"LeadsTo(name: "a", from: "x@a", to: "fires(c)")"#),
    )
    .unwrap_or_else(|e| panic!("{}", e.summary()));
    let cases = [
        (
            r#"Response(name: "a", trigger: "x@a", response: "x@b", within: 3)"#,
            "`within` counts ticks, but no connector has the role `Time`",
            "3",
        ),
        (
            r#"Replies(service: "m.S")"#,
            "`m.S` names a GenoM service, but the model has no modules",
            "m.S",
        ),
        (r#"LeadsTo(name: "a", from: "x@c", to: "x@b")"#, "`c`", "c"),
        (
            r#"LeadsTo(name: "a", from: "request(m.S)", to: "x@b")"#,
            "request",
            "request",
        ),
    ];
    for (props, words, covered) in cases {
        assert_error(&core(props), words, covered);
    }
}
