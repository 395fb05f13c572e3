//! The state cache against the step relation: along random walks that come back to the
//! initial state now and then (so that states recur), an `EnabledSet` moved by a
//! `StateCache` (a known step looked up, any other fired and updated) yields exactly the
//! steps of `System::enabled_steps` in every state, and a known step writes exactly the
//! state `System::fire` gives. On random systems (the generator of `reference.rs`) and on
//! the robot models, with caches too small to hold the walk, large ones, and none.

use bip_lang::load_str;
use bip_model::{
    EnabledSet, FirePlans, Label, OwnedStep, PlanId, State, StateCache, Steps, System,
};

use bip_random_systems::*;

fn full(sys: &System, s: &State, buf: &mut Steps) -> Option<Vec<OwnedStep>> {
    sys.enabled_steps(s, buf).ok()?;
    Some(buf.iter().map(|st| st.to_owned()).collect())
}

/// The plan of the `k`-th step of `set`, if it came from the pool.
fn plan_of(plans: &FirePlans, set: &EnabledSet, k: usize) -> Option<PlanId> {
    let st = set.steps().nth(k)?;
    let (Label::Interaction(i), Some(at)) = (st.label, set.pool_position(st.picks)) else {
        return None;
    };
    plans.plan_at(at, st.picks.len() as u32, i)
}

/// What a walk saw.
#[derive(Default)]
struct Seen {
    compared: usize,
    hits: u64,
    stats: bip_model::CacheStats,
}

/// `walks` random walks of up to `steps` steps from the initial state of `sys`, with one
/// cache of `capacity` states for them all. Panics where the set and the relation differ.
fn walk(name: &str, sys: &System, capacity: usize, walks: usize, steps: usize, seed: u64) -> Seen {
    walk_resting(name, sys, capacity, (4096, 1 << 16), (walks, steps), seed)
}

/// [`walk`] with the cache's `rest_policy`.
fn walk_resting(
    name: &str,
    sys: &System,
    capacity: usize,
    (window, rest): (u32, u32),
    (walks, steps): (usize, usize),
    seed: u64,
) -> Seen {
    // the relation computed from the state: a wrong step table would be on both sides
    let mut plain = sys.clone();
    plain.drop_step_tables(|_| true);
    let plans = sys.fire_plans();
    let init = sys.initial_state();
    let Ok(mut set) = EnabledSet::new(sys, &init) else {
        return Seen::default();
    };
    let effects = set.plan_effects(sys, &plans);
    let mut cache = StateCache::new(sys, capacity);
    cache.rest_policy(window, rest);
    cache.enter(&set, &init);
    let mut rng = Rng(seed);
    let mut buf = Steps::new();
    let mut seen = Seen::default();
    let mut written = Vec::new();
    for w in 0..walks {
        let mut s = init.clone();
        if w > 0 {
            // back to the start: as after any change the cache did not make
            cache.leave(&set);
            set.reset(sys, &s).expect("the initial state evaluates");
            cache.enter(&set, &s);
        }
        for _ in 0..steps {
            let want = full(&plain, &s, &mut buf).expect("a state the set evaluated");
            let got: Vec<OwnedStep> = set.steps().map(|st| st.to_owned()).collect();
            assert_eq!(got, want, "{name}: steps differ in {:?}", s.slots());
            seen.compared += 1;
            if want.is_empty() {
                break;
            }
            // a few choices only, so that the walk comes back to states it saw
            let k = rng.below(want.len().min(3));
            let mut reference = s.clone();
            if sys.fire(&s, want[k].as_step(), &mut reference).is_err()
                || full(&plain, &reference, &mut buf).is_none()
            {
                break;
            }
            let mut next = s.clone();
            match plan_of(&plans, &set, k) {
                Some(p) => {
                    if cache.take_known(p, &mut set, &mut next) {
                        seen.hits += 1;
                    } else {
                        sys.fire_planned(&plans, p, &mut next).expect("fires");
                        set.update_planned(sys, &effects, p, &s, &next)
                            .expect("evaluates");
                        cache.arrive(&set, &s, &next, plans.written(p));
                    }
                }
                None => {
                    cache.leave(&set);
                    written.clear();
                    sys.fire_in_place(want[k].as_step(), &mut next, &mut written)
                        .expect("fires");
                    set.update_written(sys, &s, &next, &written)
                        .expect("evaluates");
                    cache.arrive(&set, &s, &next, &written);
                }
            }
            assert_eq!(next, reference, "{name}: the step led elsewhere");
            s = next;
        }
    }
    let stats = cache.stats();
    assert!(stats.states <= capacity, "{name}: {stats:?}");
    assert_eq!(stats.hits, seen.hits, "{name}");
    seen.stats = stats;
    seen
}

#[test]
fn random_systems_agree_with_and_without_room() {
    let mut compared = 0;
    let mut hits = 0;
    for seed in 0..400u64 {
        let g = generate(seed);
        let text = g.to_ron();
        let Ok(mut sys) = load_str("generated.ron", &text) else {
            panic!("does not load\n{text}")
        };
        // steps from the step tables (which the cache remembers), some, or none
        match seed % 3 {
            0 => {}
            1 => sys.drop_step_tables(|i| i % 2 == 0),
            _ => sys.drop_step_tables(|_| true),
        }
        let capacity = [0, 2, 1000][(seed / 3 % 3) as usize];
        let seen = walk(&format!("seed {seed}"), &sys, capacity, 8, 20, seed);
        compared += seen.compared;
        hits += seen.hits;
    }
    assert!(compared > 10_000, "only {compared} states compared");
    assert!(hits > 500, "only {hits} steps taken from the cache");
}

#[test]
fn robot_models_agree_with_and_without_room() {
    for model in [
        "rover.ron",
        "satellite.ron",
        "philosophers-atomic.ron",
        "pipeline.ron",
    ] {
        let path = format!("{}/../robots/{model}", env!("CARGO_MANIFEST_DIR"));
        let sys = bip_lang::load_file(std::path::Path::new(&path)).expect("loads");
        for capacity in [16, 100_000] {
            let seen = walk(model, &sys, capacity, 20, 200, capacity as u64);
            assert!(seen.compared > 2_000, "{model}: {}", seen.compared);
            assert!(seen.hits > 500, "{model}, {capacity}: {} hits", seen.hits);
        }
    }
}

/// A full cache that seldom knows the step rests now and then, and knows the steps again
/// after a rest.
#[test]
fn a_full_cache_that_seldom_knows_rests() {
    let path = format!("{}/../robots/rover.ron", env!("CARGO_MANIFEST_DIR"));
    let sys = bip_lang::load_file(std::path::Path::new(&path)).expect("loads");
    let seen = walk_resting("rover", &sys, 2, (64, 200), (20, 300), 9);
    let s = seen.stats;
    assert!(s.rests >= 5, "{s:?}");
    assert!(s.hits > 0 && s.misses > 3000, "{s:?}");
    // never resting: more hits on the same walk
    let eager = walk_resting("rover", &sys, 2, (64, 0), (20, 300), 9).stats;
    assert_eq!(eager.rests, 0);
    assert!(eager.hits > s.hits, "{eager:?} against {s:?}");
}

/// A cache that is full learns nothing more, and its stats say what it holds.
#[test]
fn a_full_cache_stays_full() {
    let path = format!("{}/../robots/rover.ron", env!("CARGO_MANIFEST_DIR"));
    let sys = bip_lang::load_file(std::path::Path::new(&path)).expect("loads");
    let seen = walk("rover", &sys, 5, 10, 300, 9);
    assert_eq!(seen.stats.states, 5, "{:?}", seen.stats);
    assert!(
        seen.stats.misses > 1000 && seen.hits > 0,
        "{:?}",
        seen.stats
    );
    let mut cache = StateCache::new(&sys, 5);
    let s = sys.initial_state();
    let set = EnabledSet::new(&sys, &s).expect("evaluates");
    cache.enter(&set, &s);
    assert_eq!(cache.stats().states, 1);
    assert!(cache.bytes() > 0);
    // the same state again: found, not added
    cache.leave(&set);
    cache.enter(&set, &s);
    assert_eq!(cache.stats().states, 1);
    let mut none = StateCache::new(&sys, 0);
    none.enter(&set, &s);
    assert_eq!(none.stats().states, 0);
}

/// A known state is not entered while the set holds steps it computed outside the step
/// tables (they are not part of an evaluation): here `j`, which has no table, is
/// evaluated while enabled, then blocked by `h` without a slot it reads changing, so it
/// keeps computed steps; had the cache entered state [0, 0, 0] with them and later given
/// that evaluation back, `j` would show the steps computed last, in another state, once
/// `h` is off. (Found by review.)
#[test]
fn a_known_state_is_entered_only_with_an_evaluation_that_holds_all_the_set_knows() {
    let mut sys = load_str(
        "blocked.ron",
        r#"System(name: "blocked",
    atoms: {
        "L": Atom(
            locations: ["s"], initial: "s", ports: ["p", "s0", "s1", "s2"],
            vars: [(name: "x", ty: Int(0, 2), init: 2)],
            transitions: [
                (from: "s", port: "p", to: "s", guard: "x == 0"),
                (from: "s", port: "p", to: "s", guard: "x == 1"),
                (from: "s", port: "s0", to: "s", action: "x = 0"),
                (from: "s", port: "s1", to: "s", action: "x = 1"),
                (from: "s", port: "s2", to: "s", action: "x = 2"),
            ],
        ),
        "H": Atom(
            locations: ["off", "on"], initial: "off", ports: ["a", "b", "c"],
            transitions: [
                (from: "off", port: "a", to: "on"),
                (from: "on", port: "b", to: "off"),
                (from: "on", port: "c", to: "on"),
            ],
        ),
    },
    components: [(name: "l", atom: "L"), (name: "hh", atom: "H")],
    connectors: [
        (name: "j", ports: ["l.p"]),
        (name: "set0", ports: ["l.s0"]),
        (name: "set1", ports: ["l.s1"]),
        (name: "set2", ports: ["l.s2"]),
        (name: "hon", ports: ["hh.a"]),
        (name: "hoff", ports: ["hh.b"]),
        (name: "h", ports: ["hh.c"]),
    ],
    priorities: [(low: "j", high: "h")],
)"#,
    )
    .expect("loads");
    let j = sys.interactions.iter().position(|i| i.name == "j");
    let j = j.expect("j") as u32;
    sys.drop_step_tables(|i| i == j);
    let index = |name: &str| sys.interactions.iter().position(|i| i.name == name);
    let plans = sys.fire_plans();
    let mut s = sys.initial_state();
    let mut set = EnabledSet::new(&sys, &s).expect("evaluates");
    let effects = set.plan_effects(&sys, &plans);
    let mut cache = StateCache::new(&sys, 100);
    cache.enter(&set, &s);
    let mut buf = Steps::new();
    let path = [
        "hon", "set0", "hoff", "hon", "set1", "hoff", "hon", "set2", "set0", "hoff",
    ];
    for name in path {
        let want = full(&sys, &s, &mut buf).expect("evaluates");
        let got: Vec<OwnedStep> = set.steps().map(|st| st.to_owned()).collect();
        assert_eq!(got, want, "before {name}, in {:?}", s.slots());
        let i = index(name).expect(name) as u32;
        let k = set.steps().position(|st| st.label == Label::Interaction(i));
        let p = plan_of(&plans, &set, k.expect(name)).expect("a plan");
        let mut next = s.clone();
        if !cache.take_known(p, &mut set, &mut next) {
            sys.fire_planned(&plans, p, &mut next).expect("fires");
            set.update_planned(&sys, &effects, p, &s, &next)
                .expect("evaluates");
            cache.arrive(&set, &s, &next, plans.written(p));
        }
        s = next;
    }
    let want = full(&sys, &s, &mut buf).expect("evaluates");
    let got: Vec<OwnedStep> = set.steps().map(|st| st.to_owned()).collect();
    assert_eq!(got, want, "at the end, in {:?}", s.slots());
}
