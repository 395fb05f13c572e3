//! Random requests, and C codels returning random outcomes (declared or not), one step at
//! a time: a fault only when the step codel was told to return something undeclared, an
//! exception only when told to throw its declared one, and every recording replays with
//! the step relation.

use bip_c_codels::hooks::{set_step_outcome, OUTCOME_LOCK};
use bip_engine::{Event, FaultKind, Outcome, Reply};
use proptest::prelude::*;

use crate::{engine, system};

fn run_case(seed: u64, plan: &[(u8, i32)]) -> Result<(), TestCaseError> {
    let _guard = OUTCOME_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let system = system();
    let (mut engine, _) = engine(&system, seed);
    for &(request, mode) in plan {
        match request {
            0 => {
                let _ = engine.request("counter", "Count", i64::from(mode) + 1);
            }
            1 => {
                let _ = engine.request("counter", "Idle", ());
            }
            _ => {}
        }
        set_step_outcome(mode);
        engine
            .step()
            .map_err(|e| TestCaseError::fail(e.to_string()))?;
        for ev in engine.events() {
            match ev {
                Event::Fault(f) => prop_assert!(
                    mode >= 2,
                    "a fault ({}) when the codel returned a declared outcome",
                    f.kind
                ),
                Event::Reply {
                    reply:
                        Reply::Done {
                            outcome: Outcome::Exception(e),
                            ..
                        },
                    ..
                } => prop_assert!(mode == 1 && &*e == "e_limit", "threw {e} in mode {mode}"),
                Event::Reply {
                    reply:
                        Reply::Done {
                            outcome: Outcome::Fault(f),
                            ..
                        },
                    ..
                } => prop_assert!(
                    matches!(
                        f.kind,
                        FaultKind::UndeclaredException(_)
                            | FaultKind::BadTransition(_)
                            | FaultKind::UndeclaredOutcome(_)
                    ),
                    "{}",
                    f.kind
                ),
                _ => {}
            }
        }
    }
    set_step_outcome(0);
    engine
        .record()
        .replay(&system)
        .map_err(|e| TestCaseError::fail(format!("not a path of the model: {e}")))?;
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn random_c_outcomes_take_only_model_steps(
        seed in any::<u64>(),
        plan in prop::collection::vec((0u8..4, 0i32..6), 1..120),
    ) {
        run_case(seed, &plan)?;
    }
}
