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
            // the confirmation's memory budget counts this process's resident memory,
            // which the suite's other tests share: bound it by states alone
            confirm_memory: u64::MAX,
        },
        ..Options::default()
    }
}

fn compare(sys: &System, text: &str, explicit: &Report, sym: &Report) -> Result<(), TestCaseError> {
    // the worst responses are the explicit method's alone
    let verdicts: Vec<_> = explicit
        .properties
        .iter()
        .filter(|p| p.kind != CheckKind::WorstResponse)
        .collect();
    prop_assert_eq!(verdicts.len(), sym.properties.len());
    for (e, s) in verdicts.into_iter().zip(&sym.properties) {
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
                        bip_model::PropertyKind::Response { .. } => watch_fails(sys, p, &last),
                        _ => false,
                    });
                    prop_assert!(steps_fail || expr_fails, "{}\n{text}", s.name);
                }
                TraceVerdict::Violation(_) | TraceVerdict::Witness(_) => {}
                TraceVerdict::None => prop_assert!(false, "a trace without verdict"),
            }
            // counterexamples are shortest, as the explicit method's are, of their kind (a
            // response property's range error anywhere is the explicit verdict; the
            // symbolic one may be a shorter late trigger)
            if let Some(et) = e.verdict.trace() {
                let same_kind =
                    std::mem::discriminant(&et.verdict) == std::mem::discriminant(&t.verdict);
                if e.verdict.fails() == s.verdict.fails()
                    && s.kind != CheckKind::DeadlockFree
                    && same_kind
                {
                    prop_assert_eq!(et.steps.len(), t.steps.len(), "{}\n{}", s.name, text);
                }
            }
        }
    }
    Ok(())
}

/// Response property `p`'s trigger or response cannot be evaluated in `state` or on a
/// step out of it.
fn watch_fails(sys: &System, p: &bip_model::Property, state: &bip_model::State) -> bool {
    let Some(spec) = p.kind.response_spec() else {
        return false;
    };
    if sys.happenings_in(spec, state, "").is_err() {
        return true;
    }
    let Ok(next) = sys.successors(state) else {
        return false;
    };
    // on the step: an error in the state it leads to alone is that state's
    next.iter().any(|(step, after)| {
        sys.happenings_on(spec, state, step.as_step(), after, "")
            .is_err()
            && sys.happenings_in(spec, after, "").is_ok()
    })
}

fn check(seed: u64, with_roles: bool) -> Result<(), TestCaseError> {
    // with a `LeadsTo` and, with a tick, a bounded `Response`: their range errors are
    // failures in both methods
    let opts = bip_random_systems::Options {
        responses: true,
        advance: true,
        ..bip_random_systems::Options::verifier(with_roles)
    };
    let text = bip_random_systems::generate_with(seed, &opts).to_ron();
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
