//! The timed expansion explored by the verifier against the naive interpreter of the timed
//! semantics (`bip_random_systems::timed`, docs/model.md "Timed semantics") on random task
//! sets: the same tasks can miss their deadlines, and the same worst response per task,
//! misses or not, where its job never runs past a second release (two periods at least
//! where it does).

use bip_lang::load_str;
use bip_random_systems::timed::{self, TaskSet};
use bip_sched::show_micros;
use bip_verifier::{verify, CheckKind, Method, Options, PropertyResult, PropertyVerdict};
use proptest::prelude::*;

/// Sets the interpreter explores beyond this many states are left out, to keep the test
/// short; most sets have a few hundred.
const MAX_ORACLE_STATES: usize = 20_000;

/// The report's result named `{module}.{task}` and then `suffix`.
fn result_of<'a>(
    results: &'a [PropertyResult],
    set: &TaskSet,
    task: usize,
    suffix: &str,
) -> Result<&'a PropertyResult, TestCaseError> {
    let (module, name) = set.tasks[task].names(task);
    let prefix = format!("{module}.{name} {suffix}");
    results
        .iter()
        .find(|p| p.name.starts_with(&prefix))
        .ok_or_else(|| TestCaseError::fail(format!("no result named `{prefix}…`")))
}

fn check(seed: u64) -> Result<(), TestCaseError> {
    let set = timed::generate(seed);
    let oracle = timed::explore(&set);
    prop_assume!(oracle.states.len() <= MAX_ORACLE_STATES);
    let text = set.to_ron();
    let system = load_str("timed.ron", &text)
        .map_err(|e| TestCaseError::fail(format!("{}\n{text}", e.summary())))?;
    let options = Options {
        jobs: 1,
        ..Options::default()
    };
    let report = verify(&system, Method::Explicit, &options, &|_| {})
        .map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
    let results = &report.properties;
    for task in 0..set.tasks.len() {
        let deadline = result_of(results, &set, task, "meets its")?;
        prop_assert_eq!(
            deadline.verdict.fails(),
            oracle.can_miss[task],
            "{}: the verifier and the interpreter disagree\n{}",
            deadline.name,
            text
        );
        // misses or not, every task's worst response: exact where its job never runs
        // past a second release, two periods at least where it does
        let worst = result_of(results, &set, task, "worst response")?;
        prop_assert_eq!(worst.kind, CheckKind::WorstResponse);
        if oracle.coalesces[task] {
            let bound = 2 * set.period(task) * set.unit_us();
            prop_assert!(
                matches!(&worst.verdict, PropertyVerdict::Inconclusive { reason } if reason.starts_with("at least 2 periods")),
                "{}: {:?}\n{}",
                worst.name,
                worst.verdict,
                text
            );
            prop_assert_eq!(worst.worst_us, Some(bound), "{}\n{}", worst.name, text);
            continue;
        }
        prop_assert!(
            worst.verdict.holds(),
            "{}: {:?}\n{}",
            worst.name,
            worst.verdict,
            text
        );
        let expected = match oracle.worst_response[task] {
            Some(units) => show_micros(units * set.unit_us()),
            None => "no job of it ever ends".to_string(),
        };
        prop_assert_eq!(
            worst.note.as_deref(),
            Some(expected.as_str()),
            "{}\n{}",
            worst.name,
            text
        );
        prop_assert_eq!(
            worst.worst_us,
            oracle.worst_response[task].map(|units| units * set.unit_us())
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn the_expansion_explores_as_the_interpreter(seed in any::<u64>()) {
        check(seed)?;
    }
}

/// Not every generated set is left out: the property above compares something.
#[test]
fn most_sets_are_compared() {
    let compared = (0..40u64)
        .filter(|&seed| timed::explore(&timed::generate(seed)).states.len() <= MAX_ORACLE_STATES)
        .count();
    assert!(compared >= 20, "only {compared} of 40 sets compared");
}

/// A real-time miss between the units of the durations' gcd (docs/model.md, "Why whole
/// units are enough"): `hi` runs 2 ms from 8 ms, `lo` 4 ms from 10, and `hi`, released at
/// 12 ms, runs 4 ms from 14: past its 16 ms deadline. The durations' gcd, 4 ms, finds it
/// as the integer run in which `hi` runs 8 to 12 and `lo` takes the core at 12 before the
/// boundary's release there (past the deadline at 20 ms, the fifth unit); 2 ms finds the
/// real-time run itself (at 18 ms, the ninth).
#[test]
fn a_miss_between_the_gcds_units_is_found_at_the_gcd() {
    for (unit, units) in [("", 5), ("(unit: \"2ms\")", 9)] {
        let text = format!(
            r#"System(name: "between", tick_ms: 4, time: Exact{unit},
    cpus: [(name: "main", preemption: Job)],
    modules: [(name: "m", tasks: [
        (name: "hi", period: 1, priority: 2, codels: [
            (state: "start", yields: ["pause::start"], wcet: "4ms")]),
        (name: "lo", period: 2, priority: 1, codels: [
            (state: "start", yields: ["pause::start"], wcet: "4ms")])])])"#
        );
        let system = load_str("between.ron", &text).unwrap();
        let report = verify(&system, Method::Explicit, &Options::default(), &|_| {}).unwrap();
        let hi = report
            .properties
            .iter()
            .find(|p| p.name.starts_with("m.hi meets its"))
            .expect("hi's deadline");
        assert!(hi.verdict.fails(), "{unit}: {:?}", hi.verdict);
        let trace = hi.verdict.trace().expect("the miss's schedule");
        assert_eq!(crate::trace_units(&system, trace), units, "{unit}");
    }
}

/// The sets compared include some that miss with figures given (past a miss, for tasks
/// whose jobs end within two periods) and some where a task's job runs past a second
/// release.
#[test]
fn sets_that_miss_are_compared_too() {
    let (mut missing, mut coalescing) = (0, 0);
    for seed in 0..40u64 {
        let v = timed::explore(&timed::generate(seed));
        if v.states.len() > MAX_ORACLE_STATES || v.schedulable {
            continue;
        }
        missing += usize::from(v.coalesces.iter().any(|&c| !c));
        coalescing += usize::from(v.coalesces.iter().any(|&c| c));
    }
    assert!(
        missing >= 5 && coalescing >= 2,
        "{missing} missing sets with figures, {coalescing} coalescing"
    );
}
