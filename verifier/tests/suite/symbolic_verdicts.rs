//! The symbolic method never contradicts the explicit one, on random small systems: a
//! symbolic "holds" never meets an explicit counterexample, a symbolic counterexample is a
//! real run (it replays, and the explicit method fails the property too), and every
//! symbolic trace ends where its verdict says.

use bip_lang::load_str;
use bip_model::{System, Verdict as TraceVerdict};
use bip_verifier::{verify, CheckKind, Method, Options, Report, SymbolicOptions};
use proptest::prelude::*;

fn symbolic_options() -> Options {
    Options {
        jobs: 1,
        symbolic: SymbolicOptions {
            // deterministic budgets: the same verdicts on every machine
            solver_timeout: None,
            rlimit: Some(20_000_000),
            max_depth: 6,
            confirm_states: 2_000,
            ..SymbolicOptions::default()
        },
        ..Options::default()
    }
}

fn compare(sys: &System, text: &str, explicit: &Report, sym: &Report) -> Result<(), TestCaseError> {
    prop_assert_eq!(explicit.properties.len(), sym.properties.len());
    for (e, s) in explicit.properties.iter().zip(&sym.properties) {
        prop_assert_eq!(&e.name, &s.name);
        let contradiction =
            (s.verdict.holds() && e.verdict.fails()) || (s.verdict.fails() && e.verdict.holds());
        prop_assert!(
            !contradiction,
            "{}: symbolic {:?} but explicit {:?}\n{}",
            s.name,
            s.verdict,
            e.verdict,
            text
        );
        if let Some(t) = s.verdict.trace() {
            let path = t
                .replay(sys)
                .map_err(|err| TestCaseError::fail(format!("{}: {err}\n{text}", s.name)))?;
            let last = path
                .last()
                .map_or(sys.initial_state(), |(_, st)| st.clone());
            match &t.verdict {
                TraceVerdict::Deadlock => {
                    prop_assert_eq!(s.kind, CheckKind::DeadlockFree);
                    let mut steps = bip_model::Steps::new();
                    sys.enabled_steps(&last, &mut steps).unwrap();
                    let mut checker = bip_model::LivenessChecker::default();
                    prop_assert_eq!(
                        sys.liveness(&last, &steps, &mut checker).unwrap(),
                        bip_model::Liveness::Deadlock
                    );
                }
                TraceVerdict::RangeError(_) => {
                    // the last state's steps, a step's firing, or the property's expression
                    // fails there
                    let steps_fail = sys.successors(&last).is_err();
                    let expr_fails = sys.properties.iter().any(|p| match &p.kind {
                        bip_model::PropertyKind::Invariant(x)
                        | bip_model::PropertyKind::Reachable(x) => sys.holds(x, &last, "").is_err(),
                        _ => false,
                    });
                    prop_assert!(steps_fail || expr_fails, "{}\n{text}", s.name);
                }
                TraceVerdict::Violation(_) | TraceVerdict::Witness(_) => {}
                TraceVerdict::None => prop_assert!(false, "a trace without verdict"),
            }
            // counterexamples are shortest, as the explicit method's are
            if let Some(et) = e.verdict.trace() {
                if e.verdict.fails() == s.verdict.fails() && s.kind != CheckKind::DeadlockFree {
                    prop_assert_eq!(et.steps.len(), t.steps.len(), "{}\n{}", s.name, text);
                }
            }
        }
    }
    Ok(())
}

fn check(seed: u64, with_roles: bool) -> Result<(), TestCaseError> {
    let text = bip_random_systems::model(seed, with_roles);
    let sys = load_str("random.ron", &text)
        .map_err(|e| TestCaseError::fail(format!("{}\n{text}", e.summary())))?;
    let explicit = verify(
        &sys,
        Method::Explicit,
        &Options {
            jobs: 1,
            ..Options::default()
        },
        &|_| {},
    )
    .unwrap();
    let sym = verify(&sys, Method::Symbolic, &symbolic_options(), &|_| {}).unwrap();
    compare(&sys, &text, &explicit, &sym)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 120, ..ProptestConfig::default() })]

    #[test]
    fn symbolic_verdicts_never_contradict_explicit_ones(seed in any::<u64>()) {
        check(seed, false)?;
    }

    #[test]
    fn with_time_and_environment_roles_too(seed in any::<u64>()) {
        check(seed, true)?;
    }
}
