//! The gate against the step relation: along random walks that come back to the initial
//! state now and then (so that states recur), a `Gate` yields exactly the steps of
//! `System::enabled_steps` in every state, and every commit leads to the state
//! `System::fire` gives, from which `Gate::previous` is the state before. On random
//! systems (the generator of `reference.rs`) and on the robot models; with the state
//! cache off, too small for the walk, and large; with steps committed by their place in
//! the pool (fired by their plan) and by their picks (fired as the relation says).

use bip_lang::load_str;
use bip_model::{Gate, GateStep, Label, OwnedStep, State, Steps, System};

use bip_random_systems::*;

fn full(sys: &System, s: &State, buf: &mut Steps) -> Option<Vec<OwnedStep>> {
    sys.enabled_steps(s, buf).ok()?;
    Some(buf.iter().map(|st| st.to_owned()).collect())
}

/// What a walk saw.
#[derive(Default)]
struct Seen {
    compared: usize,
    planned: usize,
    known: u64,
}

/// `walks` random walks of up to `steps` steps from the initial state, through one gate
/// with a cache of `capacity` states. With `plans`, pooled steps are committed by their
/// place (their plan); otherwise every step by its picks. Panics where the gate and the
/// relation differ.
fn walk(
    name: &str,
    sys: &System,
    capacity: usize,
    plans: bool,
    (walks, steps): (usize, usize),
    seed: u64,
) -> Seen {
    // the relation computed from the state: a wrong step table would be on both sides
    let mut plain = sys.clone();
    plain.drop_step_tables(|_| true);
    let init = sys.initial_state();
    let Ok(mut gate) = Gate::new(sys.clone(), capacity) else {
        return Seen::default();
    };
    let mut rng = Rng(seed);
    let mut buf = Steps::new();
    let mut seen = Seen::default();
    for w in 0..walks {
        let mut s = init.clone();
        if w > 0 {
            gate.reset().expect("the initial state evaluates");
        }
        for _ in 0..steps {
            assert_eq!(gate.state(), &s, "{name}");
            let want = full(&plain, &s, &mut buf).expect("a state the gate evaluated");
            let got: Vec<OwnedStep> = gate.enabled().steps().map(|st| st.to_owned()).collect();
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
            let set = gate.enabled();
            let pooled = match set.steps().nth(k) {
                Some(st) => match (st.label, set.pool_position(st.picks)) {
                    (Label::Interaction(interaction), Some(at)) if plans => {
                        Some(GateStep::Pooled {
                            interaction,
                            at,
                            width: st.picks.len() as u32,
                        })
                    }
                    _ => None,
                },
                None => None,
            };
            let step = pooled.unwrap_or(GateStep::Given(want[k].as_step()));
            let committed = gate.commit(step).expect("commits");
            if committed.plan.is_some() {
                seen.planned += 1;
            }
            if committed.known {
                seen.known += 1;
            }
            assert_eq!(gate.state(), &reference, "{name}: the step led elsewhere");
            assert_eq!(gate.previous(), &s, "{name}: the state before is lost");
            for (slot, (a, b)) in s.slots().iter().zip(reference.slots()).enumerate() {
                if a != b {
                    assert!(
                        gate.written().contains(&(slot as u32)),
                        "{name}: slot {slot} changed unlisted"
                    );
                }
            }
            s = reference;
        }
    }
    let stats = gate.cache_stats();
    assert!(stats.states <= capacity, "{name}: {stats:?}");
    assert_eq!(stats.hits, seen.known, "{name}");
    if !plans {
        assert_eq!(seen.planned, 0, "{name}: a step by its picks has no plan");
    }
    seen
}

#[test]
fn random_systems_agree_with_and_without_cache_and_plans() {
    let (compared, planned, known) = walk_random_systems(0..300, generate);
    assert!(compared > 5_000, "only {compared} states compared");
    assert!(planned > 500, "only {planned} steps fired by their plan");
    assert!(known > 100, "only {known} steps taken from the cache");
}

/// Time steps with an `advance`, which their plans must evaluate and check as firing does.
#[test]
fn random_systems_with_advances_agree_with_and_without_cache_and_plans() {
    let options = Options {
        roles: true,
        advance: true,
        ..Options::default()
    };
    let (compared, planned, _) = walk_random_systems(0..300, |seed| generate_with(seed, &options));
    assert!(compared > 5_000, "only {compared} states compared");
    assert!(planned > 500, "only {planned} steps fired by their plan");
}

/// Walks each generated system with and without cache and plans: the states compared,
/// the steps fired by their plan, the steps taken from the cache.
fn walk_random_systems(
    seeds: std::ops::Range<u64>,
    generate: impl Fn(u64) -> Gen,
) -> (usize, usize, u64) {
    let mut compared = 0;
    let mut planned = 0;
    let mut known = 0;
    for seed in seeds {
        let g = generate(seed);
        let text = g.to_ron();
        let Ok(mut sys) = load_str("generated.ron", &text) else {
            panic!("does not load\n{text}")
        };
        // steps from the step tables (which have plans), some, or none
        match seed % 3 {
            0 => {}
            1 => sys.drop_step_tables(|i| i % 2 == 0),
            _ => sys.drop_step_tables(|_| true),
        }
        let capacity = [0, 2, 1000][(seed / 3 % 3) as usize];
        let plans = seed / 9 % 2 == 0;
        let seen = walk(
            &format!("seed {seed}"),
            &sys,
            capacity,
            plans,
            (8, 20),
            seed,
        );
        compared += seen.compared;
        planned += seen.planned;
        known += seen.known;
    }
    (compared, planned, known)
}

#[test]
fn robot_models_agree_with_and_without_cache_and_plans() {
    for model in [
        "rover.ron",
        "satellite.ron",
        "philosophers-atomic.ron",
        "pipeline.ron",
    ] {
        let path = format!("{}/../robots/{model}", env!("CARGO_MANIFEST_DIR"));
        let sys = bip_lang::load_file(std::path::Path::new(&path)).expect("loads");
        for (capacity, plans) in [(0, true), (16, true), (100_000, true), (100_000, false)] {
            let seen = walk(model, &sys, capacity, plans, (10, 200), capacity as u64);
            assert!(seen.compared > 1_000, "{model}: {}", seen.compared);
            if plans {
                assert!(seen.planned > 500, "{model}: {} planned", seen.planned);
            }
            if plans && capacity > 0 {
                assert!(
                    seen.known > 200,
                    "{model}, {capacity}: {} known",
                    seen.known
                );
            }
        }
    }
}

/// Setting the gate to a state met on the way gives that state's steps, and the walk
/// goes on from there as from any state.
#[test]
fn set_state_jumps_anywhere() {
    let path = format!("{}/../robots/rover.ron", env!("CARGO_MANIFEST_DIR"));
    let sys = bip_lang::load_file(std::path::Path::new(&path)).expect("loads");
    let mut gate = Gate::new(sys.clone(), 64).expect("evaluates");
    let mut rng = Rng(3);
    let mut met = vec![gate.state().clone()];
    let mut buf = Steps::new();
    for _ in 0..400 {
        if rng.below(10) == 0 {
            let s = met[rng.below(met.len())].clone();
            gate.set_state(&s).expect("evaluates");
        }
        let want = full(&sys, gate.state(), &mut buf).expect("evaluates");
        let got: Vec<OwnedStep> = gate.enabled().steps().map(|st| st.to_owned()).collect();
        assert_eq!(got, want);
        if want.is_empty() {
            gate.reset().expect("evaluates");
            continue;
        }
        let k = rng.below(want.len());
        let mut reference = gate.state().clone();
        sys.fire(gate.state(), want[k].as_step(), &mut reference)
            .expect("fires");
        gate.commit(GateStep::Given(want[k].as_step()))
            .expect("commits");
        assert_eq!(gate.state(), &reference);
        met.push(reference);
    }
    assert!(gate.cache_bytes() > 0);
}
