//! Priorities decided by the masks against the same decided by the search of the priority
//! graph (`System::drop_priority_masks`, as for closures past the masks' budget): along
//! random walks on random systems (the generator of `reference.rs`, a quarter of them with
//! a long chain of priorities), `System::enabled_steps` gives the same steps in the same
//! order, and an `EnabledSet` of the searched system gives them too. And the rule for
//! when a priority's `when` is evaluated, on a chain.

use bip_lang::load_str;
use bip_model::{EnabledSet, OwnedStep, State, Steps, System};
use proptest::prelude::*;

use bip_random_systems::*;

fn steps(sys: &System, s: &State, buf: &mut Steps) -> Result<Vec<OwnedStep>, String> {
    sys.enabled_steps(s, buf).map_err(|e| e.to_string())?;
    Ok(buf.iter().map(|st| st.to_owned()).collect())
}

/// Random walks on one generated system; returns the number of states compared.
fn check_system(seed: u64) -> Result<usize, TestCaseError> {
    let g = generate(seed);
    let text = g.to_ron();
    let masked = load_str("generated.ron", &text)
        .map_err(|e| TestCaseError::fail(format!("does not load: {}\n{text}", e.summary())))?;
    let mut searched = masked.clone();
    searched.drop_priority_masks();
    let mut rng = Rng(seed ^ 0x3c3c);
    let (mut a, mut b) = (Steps::new(), Steps::new());
    let mut compared = 0;
    for _walk in 0..3 {
        let mut s = masked.initial_state();
        let mut set = EnabledSet::new(&searched, &s).ok();
        for _ in 0..30 {
            let want = steps(&masked, &s, &mut a);
            let got = steps(&searched, &s, &mut b);
            compared += 1;
            prop_assert_eq!(&got, &want, "in {:?}\n{}", s.slots(), text);
            let Ok(want) = want else { break };
            let Some(live) = &set else { break };
            let incremental: Vec<OwnedStep> = live.steps().map(|st| st.to_owned()).collect();
            prop_assert_eq!(&incremental, &want, "the set, in {:?}\n{}", s.slots(), text);
            if want.is_empty() {
                break;
            }
            let step = &want[rng.below(want.len())];
            let mut next = s.clone();
            if masked.fire(&s, step.as_step(), &mut next).is_err() {
                break;
            }
            if let Some(live) = &mut set {
                if live.update(&searched, &s, &next).is_err() {
                    set = None;
                }
            }
            s = next;
        }
    }
    Ok(compared)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    #[test]
    fn the_search_decides_like_the_masks(seed in any::<u64>()) {
        check_system(seed)?;
    }
}

/// The generator must give long chains, with `when`s on them, or the comparisons above and
/// in `reference.rs` prove little about the closure.
#[test]
fn the_generator_gives_long_chains() {
    let (mut long, mut with_when) = (0, 0);
    for seed in 0..400u64 {
        let g = generate(seed);
        let sys = load_str("g.ron", &g.to_ron()).expect("loads");
        if sys.summary().priority_depth >= 4 {
            long += 1;
            with_when += usize::from(sys.priorities.iter().any(|p| p.when.is_some()));
        }
    }
    assert!(
        long >= 50,
        "only {long} systems with a chain of 4 priorities"
    );
    assert!(with_when >= 20, "only {with_when} of them with a `when`");
}

/// `a < b` when a condition that divides by `p.d`, `b < c`, `a < e`: the condition is
/// evaluated only where `a` is enabled and not already suppressed by `e`, and `b` leads to
/// an enabled interaction (`c`, through `b < c`, though `b` itself is not enabled).
#[test]
fn a_when_is_evaluated_where_its_priority_can_matter() {
    let sys = load_str(
        "chain.ron",
        r#"System(name: "chain",
        atoms: { "P": Atom(locations: ["l"], initial: "l", ports: ["a", "b", "c", "e"],
            vars: [(name: "on", ty: Int(0, 15)), (name: "d", ty: Int(0, 1))],
            transitions: [
                (from: "l", port: "a", to: "l", guard: "on % 2 == 1"),
                (from: "l", port: "b", to: "l", guard: "on / 2 % 2 == 1"),
                (from: "l", port: "c", to: "l", guard: "on / 4 % 2 == 1"),
                (from: "l", port: "e", to: "l", guard: "on / 8 == 1"),
            ]) },
        components: [(name: "p", atom: "P")],
        connectors: [(name: "a", ports: ["p.a"]), (name: "b", ports: ["p.b"]),
                     (name: "c", ports: ["p.c"]), (name: "e", ports: ["p.e"])],
        priorities: [(low: "a", high: "b", when: "1 / p.d > 0"), (low: "b", high: "c"),
                     (low: "a", high: "e")])"#,
    )
    .expect("loads");
    let mut buf = Steps::new();
    // `on` says which of a, b, c, e are enabled (bits 1, 2, 4, 8); d = 0: the condition
    // fails
    let run = |on: i64, d: i64, buf: &mut Steps| {
        sys.enabled_steps(&State::from_slots(vec![0, on, d]), buf)
            .map(|()| {
                buf.iter()
                    .map(|s| sys.label_name(s.label))
                    .collect::<Vec<_>>()
            })
            .map_err(|e| e.to_string())
    };
    // a and c enabled: a leads to c through b, so the condition is evaluated
    let e = run(0b101, 0, &mut buf).expect_err("a range error");
    assert!(e.contains("division by zero in the priority a < b"), "{e}");
    // and where it holds, a is suppressed by c through b, which is not enabled
    assert_eq!(run(0b101, 1, &mut buf), Ok(vec!["c".to_string()]));
    // a enabled, nothing above it: not evaluated
    assert_eq!(run(0b001, 0, &mut buf), Ok(vec!["a".to_string()]));
    // b and c enabled, a not: not evaluated (nothing enabled leads to a)
    assert_eq!(run(0b110, 0, &mut buf), Ok(vec!["c".to_string()]));
    // a and b enabled: evaluated
    assert!(run(0b011, 0, &mut buf).is_err());
    // a, c and e enabled: a is suppressed by e whatever the condition, which is not
    // evaluated
    assert_eq!(
        run(0b1101, 0, &mut buf),
        Ok(vec!["c".to_string(), "e".to_string()])
    );
}
