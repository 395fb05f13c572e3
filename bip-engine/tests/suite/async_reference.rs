//! The engine on random layers with async codels (`bip_random_systems::genom_async`, the
//! layers whose expansion bip-lang checks against the naive interpreter): codels with
//! random outcomes (a declared yield, or a fault, which takes the error path) and, for an
//! async codel, a random time before it returns; requests at random steps. Every
//! recording is a path of the step relation, each of its steps one the interpreter allows
//! from where it stands, and the engine replays it.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use bip_engine::{Engine, Next, Policy};
use bip_model::Rng;
use bip_random_systems::genom_async::{model, reference_successors, step_name, Layer, RefState};

use super::common::load_text;

/// How many steps of each kind the runs took, to show they were not vacuous.
#[derive(Default, Debug)]
struct Seen {
    starts: usize,
    returns: usize,
    outcomes_after_return: usize,
    fails: usize,
}

/// A layer drawn from `r`, as bip-lang's property test draws them.
fn draw(r: &mut Rng) -> Layer {
    Layer::new(
        r.below(4) as i64,
        r.below(2) == 1,
        r.below(2) == 1,
        r.below(2) == 1,
        r.below(3) as u8,
        r.below(2) == 1,
    )
}

/// Runs the engine on `l` for `steps` steps, with codels and requests drawn from `seed`,
/// and checks its recording against the interpreter, counting what it saw in `seen`.
fn run(l: &Layer, seed: u64, steps: usize, seen: &mut Seen) {
    let text = model(l);
    let system = load_text(&text);
    let rng = Arc::new(Mutex::new(Rng(seed)));
    let mut builder = Engine::builder(system.clone())
        .policy(Policy::Seeded(seed))
        .tick_us(200)
        .record(10 * steps);
    let genom = system.genom.as_ref().expect("a GenoM layer");
    for s in &genom.modules[0].services {
        for c in &s.codels {
            let yields: Vec<&'static str> = c
                .yields
                .iter()
                .map(|y| &*Box::leak(y.target.clone().into_boxed_str()))
                .collect();
            let apart = c.apart.is_some();
            let rng = rng.clone();
            builder = builder.codel(("m", &s.name, &c.state), move |_| {
                let (fault, pick, wait_us) = {
                    let mut r = rng.lock().unwrap_or_else(|e| e.into_inner());
                    let wait = if apart { r.below(400) as u64 } else { 0 };
                    (r.below(8) == 0, r.below(yields.len()), wait)
                };
                std::thread::sleep(Duration::from_micros(wait_us));
                if fault {
                    return Next::Yield("no_such_state");
                }
                Next::Yield(yields[pick])
            });
        }
    }
    let mut engine = builder.build().expect("builds");
    for k in 0..steps {
        let roll = rng.lock().unwrap_or_else(|e| e.into_inner()).below(12);
        // refusals come as replies: a request the model does not take now is no error
        if roll == 0 || k == 0 {
            engine.request("m", "A", ()).expect("queued");
        } else if roll == 1 {
            engine.request("m", "B", ()).expect("queued");
        }
        engine.step().expect("steps");
        let _ = engine.events().count();
    }
    let trace = engine.record();
    let path = trace
        .replay(&system)
        .unwrap_or_else(|e| panic!("not a path of the model: {e}\n{text}"));
    assert_eq!(
        RefState::of(&system, &system.initial_state()),
        RefState::FIRST
    );
    let mut at = RefState::FIRST;
    let mut returned = false;
    for (k, (step, state)) in path.iter().enumerate() {
        let name = step_name(&system, step.label);
        let next = RefState::of(&system, state);
        assert!(
            reference_successors(l, &at).contains(&(name.clone(), next)),
            "step {k}, {name}, from {at:?} to {next:?}: the interpreter does not allow it\n{text}"
        );
        if name.starts_with("A_") && name.ends_with("_start") && name != "A_start" {
            seen.starts += 1;
        } else if name.ends_with("_return") {
            seen.returns += 1;
            returned = true;
        } else if name.ends_with("_fail") {
            seen.fails += 1;
        }
        if at.returned && !next.returned && name.starts_with("A_") && !name.ends_with("_return") {
            seen.outcomes_after_return += usize::from(returned);
        }
        at = next;
    }
    let replay = bip_engine::replay::replay(system, &trace).expect("builds");
    assert!(
        replay.refused.is_none(),
        "refused: {:?}\n{text}",
        replay.refused.map(|r| r.step)
    );
    assert_eq!(replay.steps.len(), trace.steps.len());
}

#[test]
fn the_engine_on_random_async_layers_takes_only_steps_the_interpreter_allows() {
    let mut seen = Seen::default();
    let mut r = Rng(0x5eed_a5a7);
    for case in 0..32u64 {
        let l = draw(&mut r);
        run(&l, case, 150, &mut seen);
    }
    // the runs started async codels, took their returns and outcomes, and failed codels
    assert!(seen.starts > 0 && seen.returns > 0, "{seen:?}");
    assert!(seen.outcomes_after_return > 0, "{seen:?}");
    assert!(seen.fails > 0, "{seen:?}");
}
