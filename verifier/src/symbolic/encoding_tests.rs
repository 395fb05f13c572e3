//! The z3 encoding against `bip-model`'s step relation, on random small systems.
//!
//! For random states (reachable ones along random walks, and arbitrary ones within the
//! slots' ranges), the encoding must agree exactly with `System::enabled_steps`,
//! `System::fire` and `System::has_progress`: the same states whose enabled steps cannot be
//! computed (a guard fails), the same set of successors, the same existence of a step
//! whose firing fails, the same "no progress step", and the same value (or failure) of
//! the properties' expressions.

use std::collections::BTreeSet;

use bip_lang::load_str;
use bip_model::{PropertyKind, State, Steps, System};
use proptest::prelude::*;

use super::encode::{Encoding, StepFilter, StepVars};
use super::term::{err_formula, lit, not};
use z3::ast::Bool;
use z3::{SatResult, Solver};

/// Decides a closed formula (over a concrete frame, it is usually a literal already).
fn decide(b: &Bool) -> bool {
    if let Some(v) = lit(b) {
        return v;
    }
    let s = Solver::new();
    s.assert(b);
    match s.check() {
        SatResult::Sat => true,
        SatResult::Unsat => false,
        SatResult::Unknown => panic!("unknown on a closed formula"),
    }
}

/// The explicit facts about one state.
struct Explicit {
    guard_error: bool,
    successors: BTreeSet<State>,
    fire_error: bool,
    no_progress: bool,
}

fn explicit(sys: &System, s: &State) -> Explicit {
    let mut steps = Steps::new();
    if sys.enabled_steps(s, &mut steps).is_err() {
        return Explicit {
            guard_error: true,
            successors: BTreeSet::new(),
            fire_error: false,
            no_progress: false,
        };
    }
    let mut successors = BTreeSet::new();
    let mut fire_error = false;
    let mut next = s.clone();
    for step in steps.iter() {
        match sys.fire(s, step, &mut next) {
            Ok(()) => {
                successors.insert(next.clone());
            }
            Err(_) => fire_error = true,
        }
    }
    Explicit {
        guard_error: false,
        successors,
        fire_error,
        no_progress: !sys.has_progress(&steps),
    }
}

fn check_state(sys: &System, enc: &Encoding<'_>, s: &State) -> Result<(), String> {
    let ex = explicit(sys, s);
    let f = enc.concrete_frame(s);
    let en = enc.enabling(&f);
    let gerr = decide(&en.guard_error);
    if gerr != ex.guard_error {
        return Err(format!(
            "guard error: symbolic {gerr}, explicit {}",
            ex.guard_error
        ));
    }
    for p in &sys.properties {
        let e = match &p.kind {
            PropertyKind::Invariant(e) | PropertyKind::Reachable(e) => e,
            PropertyKind::DeadlockFree { terminal: Some(e) } => e,
            PropertyKind::DeadlockFree { terminal: None } | PropertyKind::Response { .. } => {
                continue
            }
        };
        let v = enc.eval(e, &f);
        let failed = decide(&err_formula(&v.err));
        match sys.holds(e, s, "") {
            Err(_) if failed => {}
            Ok(b) if !failed && decide(&v.bool_term()) == b => {}
            other => {
                return Err(format!(
                    "property {}: explicit {other:?}, symbolic failed {failed}",
                    p.name
                ))
            }
        }
    }
    if ex.guard_error {
        return Ok(());
    }
    let np = decide(&enc.no_progress(&en));
    if np != ex.no_progress {
        return Err(format!(
            "no progress: symbolic {np}, explicit {}",
            ex.no_progress
        ));
    }
    // successors: every model of "a valid step that fires" projected on the next frame
    let solver = Solver::new();
    let v = StepVars::fresh(sys, "v");
    let step = enc.step(&f, &en, &v, &StepFilter::all(sys));
    let (g, domain) = enc.fresh_frame("g");
    for d in &domain {
        solver.assert(d);
    }
    solver.push();
    solver.assert(&step.valid);
    solver.assert(&step.fire_err);
    let ferr = solver.check() == SatResult::Sat;
    solver.pop(1);
    if ferr != ex.fire_error {
        return Err(format!(
            "fire error: symbolic {ferr}, explicit {}",
            ex.fire_error
        ));
    }
    solver.assert(enc.transition(&f, &en, &v, &StepFilter::all(sys), &g));
    let mut found = BTreeSet::new();
    loop {
        match solver.check() {
            SatResult::Unsat => break,
            SatResult::Unknown => return Err("unknown".into()),
            SatResult::Sat => {}
        }
        let m = solver.get_model().ok_or("no model")?;
        let next = enc.read_state(&m, &g).ok_or("no state")?;
        solver.assert(not(&enc.frame_is(&g, &next)));
        found.insert(next);
        if found.len() > ex.successors.len() + 5 {
            break;
        }
    }
    if found != ex.successors {
        return Err(format!(
            "successors differ:\n symbolic {:?}\n explicit {:?}",
            found, ex.successors
        ));
    }
    Ok(())
}

fn check_system(seed: u64) -> Result<usize, TestCaseError> {
    let text = bip_random_systems::model(seed, true);
    let sys = load_str("random.ron", &text)
        .map_err(|e| TestCaseError::fail(format!("{}\n{text}", e.summary())))?;
    let enc = Encoding::new(&sys);
    let mut rng = bip_random_systems::Rng(seed ^ 0x5eed);
    let mut states = vec![sys.initial_state()];
    // a random walk
    let mut s = sys.initial_state();
    for _ in 0..12 {
        let Ok(succ) = sys.successors(&s) else { break };
        if succ.is_empty() {
            break;
        }
        s = succ[rng.below(succ.len())].1.clone();
        states.push(s.clone());
    }
    // arbitrary states within the ranges
    for _ in 0..16 {
        let slots: Vec<i64> = sys
            .slot_ranges()
            .iter()
            .map(|&(lo, hi)| rng.range(lo, hi))
            .collect();
        states.push(State::from_slots(slots));
    }
    for s in &states {
        check_state(&sys, &enc, s)
            .map_err(|e| TestCaseError::fail(format!("{e}\nstate {:?}\n{text}", s.slots())))?;
    }
    Ok(states.len())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn the_encoding_agrees_with_the_step_relation(seed in any::<u64>()) {
        check_system(seed)?;
    }
}

/// The generated models cover what the encoding must handle.
#[test]
fn the_generator_covers_every_feature() {
    let mut seen = [false; 8];
    for seed in 0..300u64 {
        let text = bip_random_systems::model(seed, true);
        let Ok(sys) = load_str("random.ron", &text) else {
            continue;
        };
        seen[0] |= sys.interactions.iter().any(|i| i.trigger.is_some());
        seen[1] |= sys.interactions.iter().any(|i| i.guard.is_some());
        seen[2] |= sys.interactions.iter().any(|i| !i.action.is_empty());
        seen[3] |= !sys.priorities.is_empty();
        seen[4] |= sys.priorities.iter().any(|p| p.when.is_some());
        seen[5] |= sys.has_time();
        seen[6] |= sys
            .atoms
            .iter()
            .any(|a| a.transitions.iter().any(|t| t.port.is_none()));
        seen[7] |= text.contains(" / ") || text.contains(" % ");
    }
    assert!(seen.iter().all(|&b| b), "{seen:?}");
}

/// Guards are evaluated in `enabled_steps`'s order, and only when needed: a port's guards
/// once every required port before it has an enabled transition, a connector's guard once
/// all have, a priority's condition once a higher interaction is enabled. A guard that
/// would fail but is never evaluated is no range error; the encoding must agree.
#[test]
fn guards_fail_only_where_the_step_relation_evaluates_them() {
    let model = |first_guard: &str, conn_guard: &str, when: &str| {
        format!(
            r#"System(name: "order",
            atoms: {{ "A": Atom(locations: ["s"], initial: "s", ports: ["p"],
                               vars: [(name: "x", ty: Int(0, 2), init: 0)],
                               transitions: [(from: "s", port: "p", to: "s", guard: "{first_guard}")]),
                     "B": Atom(locations: ["s"], initial: "s", ports: ["p"],
                               vars: [(name: "y", ty: Int(0, 2), init: 0)],
                               transitions: [(from: "s", port: "p", to: "s", guard: "10 / y > 1")]),
                     "C": Atom(locations: ["s"], initial: "s", ports: ["p"],
                               vars: [(name: "x", ty: Int(0, 2), init: 0)],
                               transitions: [(from: "s", port: "p", to: "s")]) }},
            components: [(name: "a", atom: "A"), (name: "b", atom: "B"), (name: "c", atom: "C")],
            connectors: [(name: "k", ports: ["a.p", "b.p"]),
                         (name: "g", ports: ["c.p"], guard: "{conn_guard}"),
                         (name: "h", ports: ["c.p"])],
            priorities: [(low: "g", high: "h", when: "{when}")])"#
        )
    };
    // (a's guard, g's guard, the priority's condition, state [a, a.x, b, b.y, c, c.x],
    //  whether computing the enabled steps fails)
    let cases: &[(&str, &str, &str, [i64; 6], bool)] = &[
        // a's port is not enabled: b's failing guard is never evaluated
        ("x > 0", "true", "true", [0, 0, 0, 0, 0, 1], false),
        // a's port is enabled: b's guard divides by zero
        ("x == 0", "true", "true", [0, 0, 0, 0, 0, 1], true),
        // g's guard is evaluated (c's port is always enabled)
        ("false", "1 / c.x > 0", "true", [0, 0, 0, 1, 0, 0], true),
        ("false", "1 / c.x > 0", "true", [0, 0, 0, 1, 0, 1], false),
        // and only up to what decides it
        (
            "false",
            "c.x == 0 && 1 / c.x > 0",
            "true",
            [0, 0, 0, 1, 0, 1],
            false,
        ),
        (
            "false",
            "1 / (c.x - 1) > 0",
            "true",
            [0, 0, 0, 1, 0, 1],
            true,
        ),
        // the priority's condition is evaluated when g and h are both enabled
        (
            "false",
            "true",
            "1 / (c.x - 1) > 0",
            [0, 0, 0, 1, 0, 1],
            true,
        ),
        (
            "false",
            "c.x == 0",
            "1 / (c.x - 1) > 0",
            [0, 0, 0, 1, 0, 1],
            false,
        ),
    ];
    for (first, conn, when, slots, fails) in cases {
        let text = model(first, conn, when);
        let sys = load_str("order.ron", &text).unwrap();
        let s = State::from_slots(slots.to_vec());
        assert_eq!(
            explicit(&sys, &s).guard_error,
            *fails,
            "{first} / {conn} / {when}"
        );
        check_state(&sys, &Encoding::new(&sys), &s).unwrap();
    }
}

/// A priority's condition is evaluated where an enabled interaction leads to its low side
/// through priorities whose conditions hold (and interactions no plain path suppresses),
/// and its high side leads to an enabled interaction through any (bip-model's
/// `suppression.rs`): on a chain with conditions that fail, in every state, the encoding fails exactly where the relation does and allows the
/// same steps, with the priority masks and with the search alone.
#[test]
fn priority_conditions_fail_only_where_the_search_evaluates_them() {
    let text = r#"System(name: "chain",
        atoms: { "P": Atom(locations: ["l"], initial: "l", ports: ["a", "b", "c", "e"],
            vars: [(name: "on", ty: Int(0, 15)), (name: "d", ty: Int(0, 2))],
            transitions: [
                (from: "l", port: "a", to: "l", guard: "on % 2 == 1"),
                (from: "l", port: "b", to: "l", guard: "on / 2 % 2 == 1"),
                (from: "l", port: "c", to: "l", guard: "on / 4 % 2 == 1"),
                (from: "l", port: "e", to: "l", guard: "on / 8 == 1"),
            ]) },
        components: [(name: "p", atom: "P")],
        connectors: [(name: "a", ports: ["p.a"]), (name: "b", ports: ["p.b"]),
                     (name: "c", ports: ["p.c"]), (name: "e", ports: ["p.e"])],
        priorities: [(low: "e", high: "a", when: "2 / (p.d - 2) < 0"),
                     (low: "a", high: "b", when: "1 / p.d > 0"), (low: "b", high: "c"),
                     (low: "e", high: "c")])"#;
    let masked = load_str("chain.ron", text).unwrap();
    let mut searched = masked.clone();
    searched.drop_priority_masks();
    let mut failures = 0;
    for sys in [&masked, &searched] {
        let enc = Encoding::new(sys);
        for on in 0..16 {
            for d in 0..3 {
                let s = State::from_slots(vec![0, on, d]);
                failures += usize::from(explicit(sys, &s).guard_error);
                check_state(sys, &enc, &s).unwrap_or_else(|e| panic!("on {on}, d {d}: {e}"));
            }
        }
    }
    assert!(
        failures >= 8,
        "only {failures} states where a condition fails"
    );
}
