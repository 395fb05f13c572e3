//! The timed expansion on small task sets whose schedules are worked out by hand: every
//! reachable state of the expanded system is explored, and each task's response times
//! (its elapsed time at its job's end) and deadline misses are read from the generated
//! task atoms, with the elapsed time derived as docs/genom.md says
//! (`late · period + (n − delay) mod period`, plus a period while the instant's boundary
//! is due). Every codel may also end on its error
//! path, which ends its machine: the figures include the runs where a task stops.

use std::collections::{BTreeMap, BTreeSet, HashSet, VecDeque};

use bip_lang::load_str;
use bip_model::{Label, State, System};

/// A task of the set, in units: (module, task, period, delay, deadline).
struct Task {
    module: &'static str,
    name: &'static str,
    period: i64,
    delay: i64,
    deadline: i64,
}

/// What the exploration finds of each task: the response times of its job ends, and
/// whether a state with its job active past its deadline is reachable.
#[derive(Debug, Default, PartialEq, Eq)]
struct Found {
    responses: BTreeSet<i64>,
    misses: bool,
}

fn read(sys: &System, s: &State, comp: &str, var: &str) -> i64 {
    let c = sys.component_index(comp).expect("a component");
    let v = sys.atom_of(c).var_index(var).expect("a variable");
    sys.value(s, c, v)
}

fn elapsed(sys: &System, s: &State, t: &Task) -> i64 {
    let comp = format!("{}_{}_task", t.module, t.name);
    let n = match sys
        .component_index("clock")
        .map(|c| sys.atom_of(c).var_index("n"))
    {
        Some(Some(_)) => read(sys, s, "clock", "n"),
        _ => 0,
    };
    let since = (n - t.delay).rem_euclid(t.period);
    let due_here = i64::from(read(sys, s, "clock", "due") != 0 && since == 0);
    (read(sys, s, &comp, "late") + due_here) * t.period + since
}

/// Every reachable state of `text`'s expansion, with what it shows of `tasks`; also
/// checks that time passes and that no state is without a step.
fn explore(text: &str, tasks: &[Task]) -> BTreeMap<&'static str, Found> {
    let sys = load_str("ts.ron", text).unwrap_or_else(|e| panic!("{}", e.summary()));
    let tick = sys.interaction_index("tick").expect("a tick");
    let done: Vec<u32> = tasks
        .iter()
        .map(|t| {
            sys.interaction_index(&format!("{}_{}_done", t.module, t.name))
                .expect("a job end")
        })
        .collect();
    let mut found: BTreeMap<&'static str, Found> =
        tasks.iter().map(|t| (t.name, Found::default())).collect();
    let first = sys.initial_state();
    let mut seen = HashSet::from([first.clone()]);
    let mut queue = VecDeque::from([first]);
    let mut ticks = 0usize;
    while let Some(s) = queue.pop_front() {
        for t in tasks {
            let stage = read(&sys, &s, &format!("{}_{}_task", t.module, t.name), "stage");
            if stage != 0 && elapsed(&sys, &s, t) > t.deadline {
                found.get_mut(t.name).expect("a task").misses = true;
            }
        }
        let next = sys.successors(&s).expect("no range error");
        assert!(!next.is_empty(), "a state without a step");
        for (step, n) in next {
            if step.label == Label::Interaction(tick) {
                ticks += 1;
            }
            for (t, &d) in tasks.iter().zip(&done) {
                if step.label == Label::Interaction(d) {
                    let e = elapsed(&sys, &s, t);
                    found.get_mut(t.name).expect("a task").responses.insert(e);
                }
            }
            if seen.insert(n.clone()) {
                queue.push_back(n);
            }
        }
    }
    assert!(ticks > 0, "time never passes");
    found
}

fn found(responses: &[i64], misses: bool) -> Found {
    Found {
        responses: responses.iter().copied().collect(),
        misses,
    }
}

/// A machine of one codel run each period, taking between `bcet` and `wcet` ms.
fn machine(bcet: i64, wcet: i64) -> String {
    format!(
        r#"codels: [(state: "start", yields: ["pause::run"], bcet: "{bcet}ms", wcet: "{wcet}ms"),
                    (state: "run", yields: ["pause::run"], bcet: "{bcet}ms", wcet: "{wcet}ms")]"#
    )
}

fn system(cpu: &str, tasks: &[String]) -> String {
    format!(
        r#"System(name: "ts", tick_ms: 1, time: Exact, cpus: [{cpu}],
            modules: [(name: "m", tasks: [{}])])"#,
        tasks.join(",\n")
    )
}

fn task(name: &'static str, period: i64, delay: i64, deadline: i64) -> Task {
    Task {
        module: "m",
        name,
        period,
        delay,
        deadline,
    }
}

#[test]
fn one_task_responds_in_its_codels_execution_time() {
    // the machine's `start` takes up to 1 ms at the first boundary (its BCET is 0), then
    // `run` 1 to 3 ms a period
    let text = system(
        r#"(name: "main", preemption: Job)"#,
        &[r#"(name: "t", period: 5, codels: [
            (state: "start", yields: ["pause::run"], wcet: "1ms"),
            (state: "run", yields: ["pause::run"], bcet: "1ms", wcet: "3ms")])"#
            .to_string()],
    );
    let got = explore(&text, &[task("t", 5, 0, 5)]);
    assert_eq!(got["t"], found(&[0, 1, 2, 3], false));
}

#[test]
fn on_one_core_the_higher_priority_goes_first_and_a_running_job_is_not_preempted() {
    let cpu = r#"(name: "main", preemption: Job)"#;
    // synchronous: `hi` runs [4, 6), `lo` waits and runs [6, 7)
    let text = system(
        cpu,
        &[
            format!(r#"(name: "hi", period: 4, priority: 2, {})"#, machine(2, 2)),
            format!(r#"(name: "lo", period: 4, priority: 1, {})"#, machine(1, 1)),
        ],
    );
    let tasks = [task("hi", 4, 0, 4), task("lo", 4, 0, 4)];
    let got = explore(&text, &tasks);
    assert_eq!(got["hi"], found(&[2], false));
    // (or alone, in 1 ms, once `hi`'s machine has ended on a codel's error path)
    assert_eq!(got["lo"], found(&[1, 3], false));
    // the same with a 2 ms deadline on `lo`: it misses it
    let tight = text.replacen("priority: 1,", r#"priority: 1, deadline: "2ms","#, 1);
    let got = explore(&tight, &[task("hi", 4, 0, 4), task("lo", 4, 0, 2)]);
    assert_eq!(got["lo"], found(&[1, 3], true));
    assert!(!got["hi"].misses);
    // `lo` runs 3 ms from 4, 8, ...; `hi`, released at 1, 5, ..., waits for it from its
    // second job on: cooperative scheduling blocks the more urgent task
    let blocked = system(
        cpu,
        &[
            format!(
                r#"(name: "hi", period: 4, delay: 1, priority: 2, {})"#,
                machine(1, 1)
            ),
            format!(r#"(name: "lo", period: 4, priority: 1, {})"#, machine(3, 3)),
        ],
    );
    let got = explore(&blocked, &[task("hi", 4, 1, 4), task("lo", 4, 0, 4)]);
    assert_eq!(got["hi"], found(&[1, 3], false));
    assert_eq!(got["lo"], found(&[3], false));
}

#[test]
fn global_tasks_share_the_cores_of_their_cpu() {
    // three tasks of 2 ms each period 4 on two cores: the two most urgent run [4, 6),
    // the third [6, 8), ends exactly at its deadline (late by the boundary at 8, then
    // released at once), and waits again
    let tasks = |cores: u32, pin: [&str; 3]| {
        system(
            &format!(r#"(name: "main", cores: {cores}, preemption: Job)"#),
            &[
                format!(
                    r#"(name: "a", period: 4, priority: 3, {} {})"#,
                    pin[0],
                    machine(2, 2)
                ),
                format!(
                    r#"(name: "b", period: 4, priority: 2, {} {})"#,
                    pin[1],
                    machine(2, 2)
                ),
                format!(
                    r#"(name: "c", period: 4, priority: 1, {} {})"#,
                    pin[2],
                    machine(2, 2)
                ),
            ],
        )
    };
    let set = [task("a", 4, 0, 4), task("b", 4, 0, 4), task("c", 4, 0, 4)];
    let got = explore(&tasks(2, ["", "", ""]), &set);
    assert_eq!(got["a"], found(&[2], false));
    assert_eq!(got["b"], found(&[2], false));
    // (or at once, once `a`'s or `b`'s machine has ended on a codel's error path)
    assert_eq!(got["c"], found(&[2, 4], false));
    // pinned: `c` alone on core 1 responds at once; `a` and `b` share core 0
    let got = explore(&tasks(2, ["core: 0,", "core: 0,", "core: 1,"]), &set);
    assert_eq!(got["a"], found(&[2], false));
    assert_eq!(got["b"], found(&[2, 4], false));
    assert_eq!(got["c"], found(&[2], false));
    // one core: `c` starts at 8, past its deadline of 4 from 4
    let got = explore(&tasks(1, ["", "", ""]), &set);
    assert!(got["c"].misses && !got["a"].misses, "{got:?}");
}

#[test]
fn a_codel_waits_for_a_lock_holding_its_core() {
    // two tasks on two cores, each codel exactly 2 ms: with a common lock, one runs
    // [4, 6) and the other waits on its core, then runs [6, 8)
    let set = |uses: &str| {
        let codels = format!(
            r#"codels: [(state: "start", yields: ["pause::run"], bcet: "2ms", wcet: "2ms"{uses}),
                       (state: "run", yields: ["pause::run"], bcet: "2ms", wcet: "2ms"{uses})]"#
        );
        system(
            r#"(name: "main", cores: 2, preemption: Job)"#,
            &[
                format!(r#"(name: "a", period: 4, priority: 2, {codels})"#),
                format!(r#"(name: "b", period: 4, priority: 1, {codels})"#),
            ],
        )
    };
    let tasks = [task("a", 4, 0, 4), task("b", 4, 0, 4)];
    let got = explore(&set(""), &tasks);
    assert_eq!(got["a"], found(&[2], false));
    assert_eq!(got["b"], found(&[2], false));
    // either takes the lock first; alone (the other's machine ended) it never waits
    let got = explore(&set(r#", uses: ["x"]"#), &tasks);
    assert_eq!(got["a"], found(&[2, 4], false));
    assert_eq!(got["b"], found(&[2, 4], false));
    // with a third task on a third core that also needs it, the last waits 4 ms: a miss
    let third = set(r#", uses: ["x"]"#)
        .replace("cores: 2", "cores: 3")
        .replace(
            r#"(name: "b","#,
            r#"(name: "c", period: 4, priority: 3, codels: [
                    (state: "start", yields: ["pause::run"], bcet: "2ms", wcet: "2ms", uses: ["x"]),
                    (state: "run", yields: ["pause::run"], bcet: "2ms", wcet: "2ms", uses: ["x"])]),
                (name: "b","#,
        );
    let got = explore(
        &third,
        &[task("a", 4, 0, 4), task("b", 4, 0, 4), task("c", 4, 0, 4)],
    );
    assert!(
        got["a"].misses && got["b"].misses && got["c"].misses,
        "{got:?}"
    );
}

#[test]
fn an_activity_waits_behind_an_earlier_one_that_waits_for_a_lock() {
    // `a` and `b`'s machine both lock `x` for 2 ms; `b`'s activity `S` (1 ms, no lock)
    // runs after `b`'s machine in the job: when `a` holds `x` first, `b` waits [4, 6),
    // runs its machine's codel [6, 8) and `S` [8, 9): 5 ms, past its 4 ms deadline. (Were
    // `S` to run while the machine waits, `b` would end at 8.)
    let text = r#"System(name: "ts", tick_ms: 1, time: Exact,
        cpus: [(name: "main", cores: 2, preemption: Job)],
        modules: [(name: "m",
            tasks: [
                (name: "a", period: 4, priority: 2, codels: [
                    (state: "start", yields: ["pause::start"], bcet: "2ms", wcet: "2ms", uses: ["x"])]),
                (name: "b", period: 4, priority: 1, codels: [
                    (state: "start", yields: ["pause::start"], bcet: "2ms", wcet: "2ms", uses: ["x"])]),
            ],
            services: [(name: "S", kind: Activity, task: "b", codels: [
                (state: "start", yields: ["pause::start"], bcet: "1ms", wcet: "1ms")])])])"#;
    let got = explore(text, &[task("a", 4, 0, 4), task("b", 4, 0, 4)]);
    assert!(got["b"].misses, "{got:?}");
    assert!(!got["a"].misses, "{got:?}");
    // without the lock `b` never misses
    let got = explore(
        &text.replace(r#", uses: ["x"]"#, ""),
        &[task("a", 4, 0, 4), task("b", 4, 0, 4)],
    );
    assert!(!got["b"].misses, "{got:?}");
}
