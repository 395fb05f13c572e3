//! The incremental enabled set against the full step relation: along random walks on random
//! systems (the generator of `reference.rs`), `EnabledSet` updated step by step yields
//! exactly the steps of `System::enabled_steps`, in the same order, and fails to evaluate
//! exactly where the full relation does. Every other walk moves as the engine does: the
//! step is fired in place (`System::fire_in_place`, checked against `System::fire`) and
//! the set is told which slots it wrote (`EnabledSet::update_written`). A step the set
//! found in the step tables' pool is also fired by its plan (`System::fire_planned`),
//! which must write the same state and list the same slots; on every third walk the set
//! is then updated by the plan's effects (`EnabledSet::update_planned`), as the engine
//! does.

use bip_lang::load_str;
use bip_model::{
    EnabledSet, FirePlans, Label, OwnedStep, PlanId, RangeError, State, Steps, System,
};
use proptest::prelude::*;

use bip_random_systems::*;

fn full(sys: &System, s: &State, buf: &mut Steps) -> Result<Vec<OwnedStep>, ()> {
    sys.enabled_steps(s, buf).map_err(|_| ())?;
    Ok(buf.iter().map(|st| st.to_owned()).collect())
}

fn incremental(set: &EnabledSet) -> Vec<OwnedStep> {
    set.steps().map(|s| s.to_owned()).collect()
}

/// Fires the `k`-th step of `set` by its plan, if it is a pooled step, and compares it
/// with firing it in place (`fired`: the state and the slots written, or the error);
/// its plan if it was compared.
fn check_plan(
    sys: &System,
    plans: &FirePlans,
    set: &EnabledSet,
    s: &State,
    k: usize,
    fired: Result<(&State, &[u32]), &RangeError>,
) -> Result<Option<PlanId>, TestCaseError> {
    let Some(st) = set.steps().nth(k) else {
        return Ok(None);
    };
    let (Label::Interaction(i), Some(at)) = (st.label, set.pool_position(st.picks)) else {
        return Ok(None);
    };
    let width = st.picks.len() as u32;
    let Some(p) = plans.plan_at(at, width, i) else {
        return Err(TestCaseError::fail("a pooled step without a plan"));
    };
    // another width at that position, or another interaction, is not this plan
    prop_assert!(plans.plan_at(at, width + 1, i).is_none());
    prop_assert!(plans.plan_at(at, width - 1, i).is_none());
    prop_assert!(plans.plan_at(at, width, i + 1).is_none());
    let mut planned = s.clone();
    let r = sys.fire_planned(plans, p, &mut planned);
    match (r, fired) {
        (Ok(()), Ok((next, written))) => {
            prop_assert_eq!(&planned, next);
            prop_assert_eq!(plans.written(p), written);
        }
        (Err(e), Err(want)) => prop_assert_eq!(&e, want),
        (r, f) => {
            return Err(TestCaseError::fail(format!(
                "the plan gives {r:?}, firing in place {:?}",
                f.map(|_| ())
            )))
        }
    }
    Ok(Some(p))
}

/// Random walks on one generated system; returns the number of states compared, of
/// steps fired by their plans, and of updates by a plan's effects.
fn check_system(seed: u64) -> Result<(usize, usize, usize), TestCaseError> {
    let g = generate(seed);
    let text = g.to_ron();
    let mut sys = load_str("generated.ron", &text)
        .map_err(|e| TestCaseError::fail(format!("does not load: {}\n{text}", e.summary())))?;
    // the relation computed from the state, against a set that reads the step tables of
    // every interaction, of every other one, or of none
    let mut plain = sys.clone();
    plain.drop_step_tables(|_| true);
    match seed % 3 {
        0 => {}
        1 => sys.drop_step_tables(|i| i % 2 == 0),
        _ => sys.drop_step_tables(|_| true),
    }
    let mut rng = Rng(seed ^ 0xa5a5);
    let mut buf = Steps::new();
    let mut copy = Steps::new();
    let mut compared = 0;
    let mut planned = 0;
    let mut by_effects = 0;
    let plans = sys.fire_plans();
    for walk in 0..3 {
        let in_place = walk % 2 == 1;
        let by_plan = walk == 2;
        let mut s = sys.initial_state();
        let mut set = match EnabledSet::new(&sys, &s) {
            Ok(set) => set,
            Err(_) => {
                prop_assert!(
                    full(&plain, &s, &mut buf).is_err(),
                    "only the set fails\n{text}"
                );
                break;
            }
        };
        let effects = set.plan_effects(&sys, &plans);
        for _ in 0..40 {
            let expected = full(&plain, &s, &mut buf);
            let Ok(expected) = expected else {
                return Err(TestCaseError::fail(format!(
                    "the set evaluated a state where the relation fails\n{text}"
                )));
            };
            let got = incremental(&set);
            prop_assert_eq!(&got, &expected, "steps differ in {:?}\n{}", s.slots(), text);
            set.copy_to(&mut copy);
            prop_assert_eq!(copy.len(), expected.len());
            for (k, st) in copy.iter().enumerate() {
                prop_assert_eq!(&st.to_owned(), &expected[k]);
                let i = match st.label {
                    bip_model::Label::Interaction(i) => i,
                    bip_model::Label::Internal { .. } => continue,
                };
                prop_assert!(set.is_enabled(i));
            }
            prop_assert_eq!(set.is_empty(), expected.is_empty());
            // a mask selects exactly the enabled interactions it names
            let n = sys.interactions.len();
            let mut masks = bip_model::Rng::new(compared as u64);
            let mask: Vec<u64> = (0..n.div_ceil(64)).map(|_| masks.next_u64()).collect();
            let named = |i: &u32| mask[*i as usize / 64] >> (i % 64) & 1 == 1;
            let among: Vec<u32> = set.interactions_in(&mask).collect();
            let filtered: Vec<u32> = set.interactions().filter(named).collect();
            prop_assert_eq!(among, filtered);
            compared += 1;
            // fire a random step that does not fail
            let mut order: Vec<usize> = (0..expected.len()).collect();
            for k in (1..order.len()).rev() {
                order.swap(k, rng.below(k + 1));
            }
            let mut next = s.clone();
            let mut moved = false;
            let mut written = Vec::new();
            let mut plan = None;
            for k in order {
                let step = expected[k].as_step();
                let fired = sys.fire(&s, step, &mut next);
                let mut here = s.clone();
                written.clear();
                let here_fired = sys.fire_in_place(step, &mut here, &mut written);
                prop_assert_eq!(fired.is_ok(), here_fired.is_ok(), "in place\n{}", text);
                let done = match &here_fired {
                    Ok(()) => Ok((&next, &written[..])),
                    Err(e) => Err(e),
                };
                plan = check_plan(&sys, &plans, &set, &s, k, done)?;
                planned += usize::from(plan.is_some());
                if fired.is_ok() {
                    prop_assert_eq!(&here, &next, "fired in place\n{}", text);
                    for (slot, (a, b)) in s.slots().iter().zip(next.slots()).enumerate() {
                        prop_assert!(a == b || written.contains(&(slot as u32)));
                    }
                    moved = true;
                    break;
                }
            }
            if !moved {
                break;
            }
            let updated = match plan {
                Some(p) if by_plan => {
                    by_effects += 1;
                    set.update_planned(&sys, &effects, p, &s, &next)
                }
                _ if in_place => set.update_written(&sys, &s, &next, &written),
                _ => set.update(&sys, &s, &next),
            };
            let reference = full(&plain, &next, &mut buf);
            match (updated, reference) {
                (Ok(()), Ok(_)) => {}
                (Err(_), Err(())) => {
                    prop_assert!(!set.is_valid());
                    break;
                }
                (u, r) => {
                    return Err(TestCaseError::fail(format!(
                        "one side fails to evaluate: set {:?}, relation {:?}\n{text}",
                        u.is_ok(),
                        r.is_ok()
                    )))
                }
            }
            s = next;
        }
    }
    Ok((compared, planned, by_effects))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1500, ..ProptestConfig::default() })]

    #[test]
    fn incremental_enabled_set_matches_the_step_relation(seed in any::<u64>()) {
        check_system(seed)?;
    }
}

/// The walks must see priorities and guarded priorities change their verdict, or the
/// comparison proves little about the incremental priority bookkeeping.
#[test]
fn walks_compare_many_states_with_priorities() {
    let mut compared = 0;
    let mut planned = 0;
    let mut by_effects = 0;
    let mut with_when = 0;
    for seed in 0..300u64 {
        let g = generate(seed);
        if g.prios.iter().any(|p| p.when.is_some()) {
            with_when += 1;
        }
        let (c, p, e) = check_system(seed).expect("agrees");
        compared += c;
        planned += p;
        by_effects += e;
    }
    assert!(planned > 2_000, "only {planned} steps fired by their plans");
    assert!(
        by_effects > 500,
        "only {by_effects} updates by a plan's effects"
    );
    assert!(
        with_when >= 50,
        "only {with_when} systems with guarded priorities"
    );
    assert!(compared > 10_000, "only {compared} states compared");
}

#[test]
fn reset_jumps_to_any_state() {
    let g = generate(7);
    let sys = load_str("g.ron", &g.to_ron()).expect("loads");
    let init = sys.initial_state();
    let mut set = EnabledSet::new(&sys, &init).expect("evaluates");
    let mut buf = Steps::new();
    sys.enabled_steps(&init, &mut buf).expect("evaluates");
    let first = buf.iter().next().map(|s| s.to_owned());
    if let Some(st) = first {
        let mut next = init.clone();
        if sys.fire(&init, st.as_step(), &mut next).is_ok()
            && sys.enabled_steps(&next, &mut buf).is_ok()
        {
            set.reset(&sys, &next).expect("evaluates");
            let want: Vec<OwnedStep> = buf.iter().map(|s| s.to_owned()).collect();
            assert_eq!(incremental(&set), want);
        }
    }
}

/// The GenoM models: long chains of priorities without `when`, broadcast ticks, guards that
/// read other components. Random walks of a few thousand steps.
#[test]
fn robot_models_agree_along_random_walks() {
    for model in [
        "rover.ron",
        "rover-deadlock.ron",
        "satellite.ron",
        "tests/mini.ron",
    ] {
        let path = format!("{}/../robots/{model}", env!("CARGO_MANIFEST_DIR"));
        let sys = bip_lang::load_file(std::path::Path::new(&path)).expect("loads");
        let (pooled, planned) = walk_agrees(model, &sys, 3000);
        assert!(pooled > 1000, "{model}: {pooled} pooled steps looked at");
        assert!(
            planned > 1000,
            "{model}: {planned} steps fired by their plans"
        );
    }
}

/// A random walk of `steps` steps on `sys`, the set against the relation at each state;
/// a pooled step is fired by its plan, and two times in three the set is updated by the
/// plan's effects. Returns how many pooled steps the set showed and how many steps were
/// fired by their plans.
fn walk_agrees(model: &str, sys: &System, steps: usize) -> (usize, usize) {
    // the relation computed from the state: a wrong step table would be on both sides
    let mut plain = sys.clone();
    plain.drop_step_tables(|_| true);
    let mut rng = Rng(model.len() as u64);
    let mut s = sys.initial_state();
    let mut set = EnabledSet::new(sys, &s).expect("evaluates");
    let mut buf = Steps::new();
    let mut next = s.clone();
    let mut pooled = 0;
    let mut planned = 0;
    let plans = sys.fire_plans();
    let effects = set.plan_effects(sys, &plans);
    let mut written = Vec::new();
    for n in 0..steps {
        let want = full(&plain, &s, &mut buf).expect("evaluates");
        assert_eq!(incremental(&set), want, "{model}");
        // where the set says an interaction's steps are in the pool, they are there
        for i in 0..sys.interactions.len() as u32 {
            let steps: Vec<_> = set.steps_of(i).map(|st| st.picks.to_vec()).collect();
            if let Some((start, width, n)) = set.pooled_steps(i) {
                assert_eq!(n as usize, steps.len(), "{model}: {i}");
                let at = start as usize;
                let len = steps.len() * width as usize;
                let in_pool = set.pool()[at..at + len].chunks(width as usize);
                assert!(in_pool.eq(steps.iter().map(|p| &p[..])), "{model}: {i}");
                // each pooled step finds its plan by its place, of its interaction and
                // width and with its picks; no place inside a step names a plan
                for k in 0..n {
                    let at = start + k * width;
                    let Some(p) = plans.plan_at(at, width, i) else {
                        panic!("{model}: no plan for the step of interaction {i} at {at}")
                    };
                    let (pi, pat, pwidth) = plans.step(p);
                    assert_eq!((pi, pwidth), (i, width), "{model}");
                    let picks = |a: u32| &set.pool()[a as usize..(a + width) as usize];
                    assert_eq!(picks(pat), picks(at), "{model}");
                    for inside in 1..width {
                        assert!(plans.plan_at(at + inside, width, i).is_none(), "{model}");
                    }
                }
            }
            pooled += usize::from(set.pooled_steps(i).is_some());
        }
        if want.is_empty() {
            break;
        }
        let k = rng.below(want.len());
        sys.fire(&s, want[k].as_step(), &mut next).expect("fires");
        let mut here = s.clone();
        written.clear();
        sys.fire_in_place(want[k].as_step(), &mut here, &mut written)
            .expect("fires");
        let p = check_plan(sys, &plans, &set, &s, k, Ok((&next, &written)));
        let p = p.expect("the plan fires the step");
        planned += usize::from(p.is_some());
        // as the engine updates after a pooled step, and as anything else may
        match p {
            Some(p) if n % 3 != 0 => set.update_planned(sys, &effects, p, &s, &next),
            _ => set.update(sys, &s, &next),
        }
        .expect("evaluates");
        std::mem::swap(&mut s, &mut next);
    }
    (pooled, planned)
}

/// A plan's effects know what an interaction finds after the step only from the values
/// the step leaves for certain: the last write of a slot counts (here a connector's
/// constant that the transition's action then overwrites from the state), and so does a
/// constant among an action's computed assignments.
#[test]
fn plan_effects_know_only_the_last_write_of_a_slot() {
    let sys = load_str(
        "writes.ron",
        r#"System(name: "writes",
        atoms: { "A": Atom(locations: ["s"], initial: "s",
            ports: ["set", "mix", "clear", "read", "read_x"],
            vars: [(name: "x", ty: Int(0, 1)), (name: "y", ty: Int(0, 1))],
            transitions: [
                (from: "s", port: "set", to: "s", action: "x = 1 - x"),
                (from: "s", port: "mix", to: "s", action: "y = x; x = 1"),
                (from: "s", port: "clear", to: "s", action: "x = 0; y = 0"),
                (from: "s", port: "read", to: "s", guard: "x == 1 && y == 0"),
                (from: "s", port: "read_x", to: "s", guard: "x == 1"),
            ]) },
        components: [(name: "a", atom: "A")],
        connectors: [
            (name: "set", ports: ["a.set"], action: "a.x = 1"),
            (name: "mix", ports: ["a.mix"]),
            (name: "clear", ports: ["a.clear"]),
            (name: "read", ports: ["a.read"]),
            (name: "read_x", ports: ["a.read_x"]),
        ])"#,
    )
    .expect("loads");
    let set = EnabledSet::new(&sys, &sys.initial_state()).expect("evaluates");
    let effects = set.plan_effects(&sys, &sys.fire_plans());
    // `read` and `read_x` after `clear`, `read_x` after `mix`
    assert_eq!(effects.known_evaluations(), 3);
    let (_, planned) = walk_agrees("writes", &sys, 300);
    assert!(planned > 250, "{planned} steps fired by their plans");
}

/// Dependencies are per slot: a step that changes only a variable (no location moves)
/// must re-evaluate the interactions whose atom guards (on that port) or connector guards
/// read it, and may skip the others. Each step here flips one flag and nothing else.
#[test]
fn variable_only_steps_reach_the_guards_that_read_them() {
    let sys = load_str(
        "flags.ron",
        r#"System(name: "flags",
        atoms: { "A": Atom(locations: ["s"], initial: "s", ports: ["p", "flip", "bump"],
            vars: [(name: "f", ty: Bool), (name: "n", ty: Int(0, 1))],
            transitions: [
                (from: "s", port: "p", to: "s", guard: "f"),
                (from: "s", port: "flip", to: "s", action: "f = !f"),
                (from: "s", port: "bump", to: "s", action: "n = 1 - n"),
            ]) },
        components: [(name: "a", atom: "A"), (name: "b", atom: "A")],
        connectors: [
            (name: "own_guard", ports: ["a.p"]),
            (name: "flip_a", ports: ["a.flip"]),
            (name: "bump_a", ports: ["a.bump"]),
            (name: "flip_b", ports: ["b.flip"]),
            (name: "watch", ports: ["b.bump"], guard: "a.n == 1"),
        ],
    )"#,
    )
    .expect("loads");
    let mut s = sys.initial_state();
    let mut set = EnabledSet::new(&sys, &s).expect("evaluates");
    let mut buf = Steps::new();
    let mut next = s.clone();
    let names = |set: &EnabledSet| -> Vec<String> {
        set.steps().map(|st| sys.label_name(st.label)).collect()
    };
    assert!(!names(&set).contains(&"own_guard".to_string()));
    assert!(!names(&set).contains(&"watch".to_string()));
    for (take, own_guard, watch) in [
        ("flip_a", true, false),
        ("bump_a", true, true),
        ("flip_b", true, true),
        ("flip_a", false, true),
        ("bump_a", false, false),
    ] {
        let want = full(&sys, &s, &mut buf).expect("evaluates");
        let step = want
            .iter()
            .find(|st| sys.label_name(st.label) == take)
            .expect("enabled");
        sys.fire(&s, step.as_step(), &mut next).expect("fires");
        set.update(&sys, &s, &next).expect("evaluates");
        std::mem::swap(&mut s, &mut next);
        assert_eq!(incremental(&set), full(&sys, &s, &mut buf).expect("ok"));
        let got = names(&set);
        assert_eq!(
            got.contains(&"own_guard".to_string()),
            own_guard,
            "after {take}"
        );
        assert_eq!(got.contains(&"watch".to_string()), watch, "after {take}");
    }
}

/// A plan keeps the order of an action's assignments: a later assignment of the same
/// variable wins, and an assignment reads the ones before it.
#[test]
fn plans_keep_the_order_of_an_actions_assignments() {
    let sys = load_str(
        "order.ron",
        r#"System(name: "order",
        atoms: { "A": Atom(locations: ["s", "t"], initial: "s", ports: ["go", "back"],
            vars: [(name: "x", ty: Int(0, 3)), (name: "y", ty: Int(0, 3))],
            transitions: [
                (from: "s", port: "go", to: "t", action: "x = 1; x = 2; y = 3"),
                (from: "t", port: "back", to: "s", action: "x = 0; y = x + 1; x = 3"),
            ]) },
        components: [(name: "a", atom: "A")],
        connectors: [(name: "go", ports: ["a.go"]), (name: "back", ports: ["a.back"])],
    )"#,
    )
    .expect("loads");
    let plans = sys.fire_plans();
    let mut s = sys.initial_state();
    let mut set = EnabledSet::new(&sys, &s).expect("evaluates");
    let slot = |name: &str| {
        (0..sys.slot_count() as u32)
            .find(|&k| sys.slot_name(k) == name)
            .expect("a slot") as usize
    };
    let (x, y) = (slot("a.x"), slot("a.y"));
    for (step, want_x, want_y) in [("go", 2, 3), ("back", 3, 1), ("go", 2, 3)] {
        let st = set.steps().next().expect("one step");
        assert_eq!(sys.label_name(st.label), step);
        let Label::Interaction(i) = st.label else {
            panic!("an interaction")
        };
        let at = set.pool_position(st.picks).expect("a pooled step");
        let p = plans.plan_at(at, st.picks.len() as u32, i).expect("a plan");
        let mut planned = s.clone();
        sys.fire_planned(&plans, p, &mut planned).expect("fires");
        let mut next = s.clone();
        sys.fire(&s, st, &mut next).expect("fires");
        assert_eq!(planned, next, "{step}");
        assert_eq!(
            (planned.slots()[x], planned.slots()[y]),
            (want_x, want_y),
            "{step}"
        );
        set.update(&sys, &s, &planned).expect("evaluates");
        s = planned;
    }
}
