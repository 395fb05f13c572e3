//! A timed model's trace as the user sees it (docs/genom.md, "Timed models"): `bip trace
//! show` names the steps the expansion adds for time (a dispatch, a codel's start, a job
//! done, a yield, a preemption, a dropped outcome, the release, the time step) and the task
//! atoms in the user's names, in the text and in the sequence chart.

use bip_model::{OwnedStep, State, Steps, Trace, Verdict};

use crate::common::bip;

/// Two tasks on a CPU preempted between codels (`lo` yields to `hi`), two on a preemptive
/// one (`u` preempts `t`'s codels), and an activity of `t` that interrupts itself, so that
/// a request while `compute` runs drops its outcome.
const MODEL: &str = r#"System(name: "kinds", tick_ms: 1, time: Exact,
    cpus: [(name: "coop", preemption: Codel), (name: "pre", preemption: Preemptive)],
    modules: [(name: "m",
        tasks: [
            (name: "hi", cpu: "coop", period: 2, priority: 2, codels: [
                (state: "start", yields: ["pause::start"], wcet: "1ms")]),
            (name: "lo", cpu: "coop", period: 4, priority: 1, codels: [
                (state: "start", yields: ["next"], wcet: "1ms"),
                (state: "next", yields: ["pause::start"], wcet: "1ms")]),
            (name: "u", cpu: "pre", period: 2, priority: 2, codels: [
                (state: "start", yields: ["pause::start"], wcet: "1ms")]),
            (name: "t", cpu: "pre", period: 4, priority: 1),
        ],
        services: [
            (name: "Plan", kind: Activity, task: "t", interrupts: ["Plan"], codels: [
                (state: "start", yields: ["compute"], wcet: "1ms"),
                (state: "compute", yields: ["ether"], bcet: "1ms", wcet: "2ms")]),
        ])])"#;

/// Each kind of step the expansion adds, by its interaction's name (the expansion's),
/// and the label `bip trace show` must give it (its start).
const KINDS: [(&str, &str); 9] = [
    ("m_lo_dispatch", "dispatch m.lo"),
    ("m_Plan_compute_start", "m.Plan: compute starts"),
    ("m_Plan_compute", "m.Plan: compute → ether"),
    ("m_hi_done", "m.hi: job done"),
    ("m_lo_yield", "m.lo yields its core"),
    ("m_u_preempts_m_t", "m.u preempts m.t"),
    (
        "m_Plan_compute_dropped",
        "m.Plan: compute's outcome dropped",
    ),
    ("release", "release"),
    ("tick", "time passes "),
];

/// A random walk (a fixed seed) from the initial state until a step of every kind of
/// [`KINDS`] has fired. It takes no codel's error path: a task machine's would end it.
fn walk(system: &bip_model::System) -> Vec<(OwnedStep, State)> {
    let mut seed: u64 = 0x2545_f491_4f6c_dd1d;
    let mut state = system.initial_state();
    let mut path = Vec::new();
    let seen = |path: &[(OwnedStep, State)], name: &str| {
        path.iter()
            .any(|(s, _): &(OwnedStep, State)| system.label_name(s.label) == name)
    };
    while !KINDS.iter().all(|(name, _)| seen(&path, name)) {
        assert!(
            path.len() < 5_000,
            "the walk saw no {:?}",
            KINDS
                .iter()
                .filter(|(name, _)| !seen(&path, name))
                .collect::<Vec<_>>()
        );
        let mut steps = Steps::new();
        system
            .enabled_steps(&state, &mut steps)
            .expect("no range error");
        let enabled: Vec<OwnedStep> = steps
            .iter()
            .map(|s| s.to_owned())
            .filter(|s| !system.label_name(s.label).ends_with("_fail"))
            .collect();
        assert!(!enabled.is_empty(), "a deadlock after {} steps", path.len());
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        let step = enabled[(seed % enabled.len() as u64) as usize].clone();
        let mut next = state.clone();
        system
            .fire(&state, step.as_step(), &mut next)
            .expect("no range error");
        path.push((step, next.clone()));
        state = next;
    }
    path
}

#[test]
fn trace_show_names_a_timed_models_steps_and_tasks_in_the_users_terms() {
    let dir = tempfile::tempdir().expect("temp dir");
    let model = dir.path().join("kinds.ron");
    std::fs::write(&model, MODEL).expect("the model is written");
    let system = bip_lang::load_file(&model).expect("the model loads");
    let path = walk(&system);
    let trace = Trace::from_path(&system, Verdict::None, &path);
    let file = dir.path().join("kinds.trace.ron");
    std::fs::write(&file, bip_lang::trace_file::to_ron(&trace)).expect("the trace is written");
    let svg = dir.path().join("kinds.svg");
    let out = bip(&[
        "trace",
        "show",
        model.to_str().expect("utf-8"),
        file.to_str().expect("utf-8"),
        "--svg",
        svg.to_str().expect("utf-8"),
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).expect("utf-8");
    let lines: Vec<&str> = text.lines().skip(1).map(str::trim).collect();
    // every step of each kind, named as the user would
    for (k, (step, _)) in path.iter().enumerate() {
        let name = system.label_name(step.label);
        let Some((_, label)) = KINDS.iter().find(|(kind, _)| *kind == name) else {
            continue;
        };
        let line = lines[k]
            .strip_prefix(&format!("{} ", k + 1))
            .unwrap_or_else(|| panic!("step {} is not line {}: {text}", k + 1, k + 2))
            .trim_start();
        assert!(
            line.starts_with(label),
            "step {} ({name}) is not {label:?}: {line:?}",
            k + 1
        );
    }
    // the tasks' lifelines and their changes in the user's names, the steps' too
    let chart = std::fs::read_to_string(&svg).expect("the chart is drawn");
    let doc = roxmltree::Document::parse(&chart).expect("the chart parses as XML");
    // what the chart says: its texts and tooltips
    let said: Vec<&str> = doc
        .descendants()
        .filter(|n| n.has_tag_name("text") || n.has_tag_name("title"))
        .filter_map(|n| n.text())
        .collect();
    for name in ["m.hi", "m.lo", "m.u", "m.t"] {
        assert!(said.contains(&name), "no lifeline {name}: {chart}");
    }
    let chart = said.join("\n");
    assert!(text.contains("m.t ready"), "{text}");
    for expansion in [
        "_task",
        "_dispatch",
        "_start",
        "_done",
        "_yield",
        "_preempts_",
        "_dropped",
        "tick",
        "stage",
        "codel =",
    ] {
        assert!(!text.contains(expansion), "{expansion} in {text}");
        assert!(!chart.contains(expansion), "{expansion} in {chart}");
    }
}
