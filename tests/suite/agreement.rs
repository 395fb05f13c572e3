//! Every trace `bip verify` and `bip simulate` write replays to its verdict: on random
//! models, each trace is written as a trace file, read back and replayed through the
//! engine (`bip replay`), which must take every step and show the verdict at the end.

use bip_engine::replay::{replay, End};
use bip_engine::simulate::{simulate, SimulationOptions};
use bip_engine::CodelTime;
use bip_lang::load_str;
use bip_model::{System, Trace, Verdict};
use bip_verifier::{verify, Method, Options};
use proptest::prelude::*;

/// Replays `trace` (through its file format) and says why it does not end in its verdict.
fn replays_to_its_verdict(system: &System, trace: &Trace) -> Result<(), String> {
    let text = bip_lang::trace_file::to_ron(trace);
    let read = bip_lang::trace_file::from_ron(&text).map_err(|e| format!("not a trace: {e}"))?;
    let result = replay(system.clone(), &read).map_err(|e| format!("no engine: {e}"))?;
    if let Some(r) = &result.refused {
        return Err(format!(
            "step {} ({}) NOT ALLOWED: {} {:?}\n{text}",
            r.step, r.name, r.message, r.reasons
        ));
    }
    let shown = match (&trace.verdict, &result.end) {
        (Verdict::None, Some(End::Recording)) => true,
        (Verdict::Deadlock, Some(End::Deadlock { .. })) => true,
        (Verdict::Violation(p), Some(End::Violation { property }))
        | (Verdict::Violation(p), Some(End::Unanswered { property, .. }))
        | (Verdict::Witness(p), Some(End::Witness { property })) => p == property,
        (Verdict::RangeError(_), Some(End::RangeError { .. })) => true,
        (Verdict::Violation(p), Some(End::Timelock { .. } | End::BusyLoop { .. })) => {
            p == "TimeProgress"
        }
        _ => false,
    };
    if shown {
        Ok(())
    } else {
        Err(format!(
            "verdict {:?}, replay ends {:?}\n{text}",
            trace.verdict, result.end
        ))
    }
}

fn check(seed: u64, roles: bool) -> Result<(), TestCaseError> {
    let opts = bip_random_systems::Options {
        responses: true,
        ..bip_random_systems::Options::verifier(roles)
    };
    let text = bip_random_systems::generate_with(seed, &opts).to_ron();
    let system = load_str("random.ron", &text)
        .map_err(|e| TestCaseError::fail(format!("{}\n{text}", e.summary())))?;
    let options = Options {
        jobs: 1,
        ..Options::default()
    };
    let report = verify(&system, Method::Explicit, &options, &|_| {})
        .map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
    for p in &report.properties {
        if let Some(trace) = p.verdict.trace() {
            // a worst response's witness names no property of the model, so the replay
            // has no verdict to show at its end: it replays, step by step
            if p.kind == bip_verifier::CheckKind::WorstResponse {
                let text = bip_lang::trace_file::to_ron(trace);
                let read = bip_lang::trace_file::from_ron(&text)
                    .map_err(|e| TestCaseError::fail(format!("not a trace: {e}")))?;
                let result = replay(system.clone(), &read)
                    .map_err(|e| TestCaseError::fail(format!("no engine: {e}")))?;
                prop_assert!(
                    result.refused.is_none(),
                    "{}: {:?}\n{text}",
                    p.name,
                    result.refused
                );
                continue;
            }
            replays_to_its_verdict(&system, trace).map_err(|e| {
                TestCaseError::fail(format!("verify's trace of {}: {e}\nmodel:\n{text}", p.name))
            })?;
        }
    }
    let sim = simulate(
        system.clone(),
        SimulationOptions {
            steps: 200,
            seed,
            codel_time: CodelTime::Zero,
        },
    );
    // a model whose initial state cannot even be built into an engine has nothing to
    // replay; verify reports its range error from the initial state
    if let Ok(sim) = sim {
        let window = &sim.last_steps;
        prop_assume!(window.skipped == 0);
        replays_to_its_verdict(&system, &window.trace)
            .map_err(|e| TestCaseError::fail(format!("simulate's trace: {e}\nmodel:\n{text}")))?;
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn every_trace_verify_and_simulate_write_replays_to_its_verdict(seed in any::<u64>()) {
        check(seed, false)?;
    }

    #[test]
    fn with_time_and_environment_roles_too(seed in any::<u64>()) {
        check(seed, true)?;
    }
}
