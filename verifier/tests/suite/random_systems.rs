//! Property test over random small systems: every worker count gives the same report
//! (verdicts, state counts, traces), the state count is that of a naive breadth-first
//! search over `System::successors`, and every trace replays and is as short as the
//! naive search says it can be.

use std::collections::{HashMap, VecDeque};

use bip_lang::load_str;
use bip_model::{State, System};
use bip_verifier::{verify, Method, Options, PropertyVerdict, Report, RANGE_ERRORS};
use proptest::prelude::*;

/// A random system in the model format: `atoms` atom types with 2-3 locations, a small
/// counter and random transitions; one component per atom; random rendezvous and broadcast
/// connectors; maybe a priority; an invariant and a reachability property on the counters.
#[derive(Clone, Debug)]
struct Spec {
    atoms: Vec<AtomSpec>,
    connectors: Vec<(Vec<(usize, usize)>, bool)>,
    priority: Option<(usize, usize)>,
    invariant_bound: i64,
    reach: (usize, i64),
}

#[derive(Clone, Debug)]
struct AtomSpec {
    locations: usize,
    hi: i64,
    transitions: Vec<TransitionSpec>,
}

/// (from, port or none, to, guard threshold or none, increment)
type TransitionSpec = (usize, Option<usize>, usize, Option<i64>, i64);

fn atom_spec() -> impl Strategy<Value = AtomSpec> {
    (2usize..4, 1i64..4).prop_flat_map(|(locations, hi)| {
        let t = (
            0..locations,
            prop::option::weighted(0.7, 0usize..2),
            0..locations,
            prop::option::of(0..=hi),
            -1i64..6,
        );
        prop::collection::vec(t, 1..5).prop_map(move |transitions| AtomSpec {
            locations,
            hi,
            transitions,
        })
    })
}

fn spec() -> impl Strategy<Value = Spec> {
    prop::collection::vec(atom_spec(), 2..5).prop_flat_map(|atoms| {
        let n = atoms.len();
        let conn = (
            prop::collection::vec((0..n, 0usize..2), 1..3),
            any::<bool>(),
        );
        (
            Just(atoms),
            prop::collection::vec(conn, 1..4),
            prop::option::of((0usize..4, 0usize..4)),
            0i64..6,
            (0..n, 0i64..4),
        )
            .prop_map(
                |(atoms, connectors, priority, invariant_bound, reach)| Spec {
                    atoms,
                    connectors,
                    priority,
                    invariant_bound,
                    reach,
                },
            )
    })
}

fn ron(spec: &Spec) -> String {
    let mut atoms = String::new();
    let mut components = String::new();
    for (k, a) in spec.atoms.iter().enumerate() {
        let locs: Vec<String> = (0..a.locations).map(|l| format!("\"l{l}\"")).collect();
        let mut ts = Vec::new();
        for (from, port, to, guard, inc) in &a.transitions {
            let mut t = format!("(from: \"l{from}\", to: \"l{to}\"");
            if let Some(p) = port {
                t += &format!(", port: \"p{p}\"");
            }
            if let Some(g) = guard {
                t += &format!(", guard: \"x <= {g}\"");
            }
            // mostly wrapping increments; a plain one now and then can leave the range
            match inc {
                0 => {}
                2 => t += ", action: \"x = x + 1\"",
                _ => t += &format!(", action: \"x = (x + {}) % {}\"", inc + 2, a.hi + 1),
            }
            ts.push(t + ")");
        }
        atoms += &format!(
            "\"A{k}\": Atom(locations: [{}], initial: \"l0\", ports: [\"p0\", \"p1\"], vars: [(name: \"x\", ty: Int(0, {}))], transitions: [{}]),\n",
            locs.join(", "),
            a.hi,
            ts.join(", ")
        );
        components += &format!("(name: \"c{k}\", atom: \"A{k}\"),\n");
    }
    let mut connectors = String::new();
    for (k, (ports, broadcast)) in spec.connectors.iter().enumerate() {
        let mut seen = Vec::new();
        let mut names = Vec::new();
        for &(c, p) in ports {
            if !seen.contains(&c) {
                seen.push(c);
                names.push(format!("\"c{c}.p{p}\""));
            }
        }
        let kind = if *broadcast && names.len() > 1 {
            format!(", kind: Broadcast(trigger: {})", names[0])
        } else {
            String::new()
        };
        connectors += &format!("(name: \"k{k}\", ports: [{}]{kind}),\n", names.join(", "));
    }
    let priorities = match spec.priority {
        Some((lo, hi)) if lo != hi && lo < spec.connectors.len() && hi < spec.connectors.len() => {
            format!("priorities: [(low: \"k{lo}\", high: \"k{hi}\")],")
        }
        _ => String::new(),
    };
    let sum: Vec<String> = (0..spec.atoms.len()).map(|k| format!("c{k}.x")).collect();
    format!(
        "System(name: \"random\", atoms: {{ {atoms} }}, components: [{components}], connectors: [{connectors}], {priorities}
         properties: [DeadlockFree, Invariant(name: \"small\", expr: \"{} < {}\"), Reachable(name: \"reach\", expr: \"c{}.x == {}\")])",
        sum.join(" + "),
        spec.invariant_bound,
        spec.reach.0,
        spec.reach.1
    )
}

/// Naive breadth-first search: depth of every reachable state (steps with range errors
/// have no successor; a state whose steps cannot be computed has none).
fn naive(sys: &System) -> HashMap<State, usize> {
    let init = sys.initial_state();
    let mut depth = HashMap::from([(init.clone(), 0)]);
    let mut queue = VecDeque::from([init]);
    let mut steps = bip_model::Steps::new();
    while let Some(s) = queue.pop_front() {
        let d = depth[&s];
        if sys.enabled_steps(&s, &mut steps).is_err() {
            continue;
        }
        for step in steps.iter() {
            let mut next = s.clone();
            if sys.fire(&s, step, &mut next).is_ok() && !depth.contains_key(&next) {
                depth.insert(next.clone(), d + 1);
                queue.push_back(next);
            }
        }
    }
    depth
}

fn without_timing(mut r: Report) -> Report {
    r.stats.seconds = 0.0;
    r.stats.states_per_second = 0.0;
    r.stats.store_bytes = 0;
    r.stats.jobs = 0;
    r.seconds = 0.0;
    r.peak_memory_bytes = None;
    r
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn workers_agree_and_match_a_naive_search(spec in spec()) {
        let text = ron(&spec);
        let sys = match load_str("random.ron", &text) {
            Ok(s) => s,
            Err(e) => return Err(TestCaseError::fail(format!("{}\n{text}", e.summary()))),
        };
        let run = |jobs| without_timing(verify(&sys, Method::Explicit, &Options { jobs, ..Options::default() }, &|_| {}).unwrap());
        let one = run(1);
        for jobs in [2, 3] {
            prop_assert_eq!(&run(jobs), &one);
        }
        let depth = naive(&sys);
        if one.stats.complete {
            prop_assert_eq!(one.stats.states, depth.len() as u64);
            prop_assert_eq!(u64::from(one.stats.depth), depth.values().copied().max().unwrap_or(0) as u64);
        } else {
            // stopped once every verdict was final
            prop_assert!(one.stopped.is_none());
            let all_final = one.properties.iter().all(|p| !matches!(p.verdict, PropertyVerdict::Inconclusive { .. }));
            prop_assert!(all_final);
            prop_assert!(one.stats.states <= depth.len() as u64);
        }
        let small = sys.properties.iter().find(|p| p.name == "small").unwrap();
        let bip_model::PropertyKind::Invariant(inv) = &small.kind else { unreachable!() };
        for p in &one.properties {
            if let Some(t) = p.verdict.trace() {
                let path = t.replay(&sys).map_err(|e| TestCaseError::fail(e.to_string()))?;
                let last = path.last().map_or(sys.initial_state(), |(_, s)| s.clone());
                prop_assert_eq!(depth[&last], t.steps.len());
            }
            if p.name == "small" {
                // shortest: no state nearer than the counterexample violates the invariant
                let nearest = depth
                    .iter()
                    .filter(|(s, _)| !sys.holds(inv, s, "").unwrap_or(false))
                    .map(|(_, &d)| d)
                    .min();
                match (&p.verdict, nearest) {
                    (PropertyVerdict::Fails { trace: Some(t), .. }, Some(d)) => prop_assert_eq!(t.steps.len(), d),
                    (PropertyVerdict::Holds { .. }, None) => {}
                    (v, n) => return Err(TestCaseError::fail(format!("{v:?} but the nearest violation is at {n:?}"))),
                }
            }
            if p.name == RANGE_ERRORS && p.verdict.holds() {
                // no reachable state has a step that fails
                for s in depth.keys() {
                    prop_assert!(sys.successors(s).is_ok());
                }
            }
        }
    }
}
