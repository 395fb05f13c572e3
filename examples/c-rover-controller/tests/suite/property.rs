//! Random supervisor requests, and C codels whose outcomes the test hook picks at random
//! among those each declares (or, in the second mode, now and then one it does not): the
//! recording always replays with the step relation and every invariant holds along it; a
//! fault happens exactly when a codel returned an undeclared event, and takes the
//! activity's error path as the engine's `UndeclaredOutcome`.

use bip_c_rover_controller::hooks::{self, Outcomes};
use bip_c_rover_controller::rover_c::{nav, rover};
use bip_c_rover_controller::supervisor::{check_recording, engine, system};
use bip_c_rover_controller::world::{self, World};
use bip_engine::{Engine, Event, FaultKind, Outcome, Reply, Until};
use proptest::prelude::*;

fn request(engine: &mut Engine, what: u8) {
    // a refused request is an answer of the model too: the result is not asked for
    let _ = match what % 7 {
        0 => engine.request("loc", "Track", ()),
        1 => engine.request("loco", "Init", ()),
        2 => engine.request("loco", "Move", rover::speed { v: 0.4, w: 0.1 }),
        3 => engine.request("loco", "Stop", ()),
        4 | 5 => engine.request(
            "nav",
            "GoTo",
            nav::GoTo_input {
                goal: rover::pose {
                    x: f64::from(what % 3),
                    y: f64::from(what % 2) * 3.0,
                    ..Default::default()
                },
                tolerance: 0.3,
            },
        ),
        _ => engine.request("nav", "Cancel", ()),
    };
}

/// Runs `plan` with the hook's outcomes; the faults and the exceptions the run met.
fn run_case(seed: u32, undeclared: bool, plan: &[(u8, u8)]) -> Result<(u64, u64), TestCaseError> {
    let _world = world::lock(World {
        obstacles: vec![(1.0, 1.5, 0.5)],
        ..World::default()
    });
    hooks::set(
        if undeclared {
            Outcomes::Undeclared
        } else {
            Outcomes::Declared
        },
        seed,
    );
    let system = system().map_err(TestCaseError::fail)?;
    let (mut engine, _) = engine(&system, u64::from(seed)).map_err(TestCaseError::fail)?;
    let (mut faults, mut exceptions) = (0u64, 0u64);
    for &(what, ticks) in plan {
        request(&mut engine, what);
        engine
            .run_until(Until::Ticks(u64::from(ticks % 4) + 1))
            .map_err(|e| TestCaseError::fail(e.to_string()))?;
        for ev in engine.events() {
            match ev {
                Event::Fault(f) => {
                    prop_assert_eq!(&f.kind, &FaultKind::UndeclaredOutcome(u16::MAX), "{}", f);
                    faults += 1;
                }
                Event::Reply {
                    reply:
                        Reply::Done {
                            outcome: Outcome::Exception(_),
                            ..
                        },
                    ..
                } => exceptions += 1,
                _ => {}
            }
        }
    }
    let returned = hooks::undeclared();
    hooks::set(Outcomes::Own, 1);
    prop_assert_eq!(faults, returned, "one fault per undeclared event returned");
    if !undeclared {
        prop_assert_eq!(faults, 0);
    }
    check_recording(&system, &engine.record()).map_err(TestCaseError::fail)?;
    Ok((faults, exceptions))
}

/// The same, written out: Track, Init, Move and GoTo, then time for the codels.
const PLAN: [(u8, u8); 8] = [
    (0, 1),
    (1, 1),
    (2, 1),
    (4, 3),
    (0, 3),
    (5, 3),
    (2, 3),
    (4, 3),
];

#[test]
fn the_hook_gives_declared_exceptions_and_undeclared_events() {
    let (mut exceptions, mut faults) = (0, 0);
    for seed in 1..=16 {
        let (f, e) = run_case(seed, false, &PLAN).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(f, 0);
        exceptions += e;
        faults += run_case(seed, true, &PLAN)
            .unwrap_or_else(|e| panic!("{e}"))
            .0;
    }
    assert!(exceptions > 0, "no declared exception picked");
    assert!(faults > 0, "no undeclared event picked");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    #[test]
    fn random_requests_and_outcomes_stay_on_the_models_paths(
        seed in any::<u32>(),
        undeclared in any::<bool>(),
        plan in prop::collection::vec((any::<u8>(), any::<u8>()), 1..16),
    ) {
        run_case(seed, undeclared, &plan)?;
    }
}
