//! The timed interpreter against task sets worked out by hand: each figure in these tests
//! is computed in its comment from docs/model.md's "Timed semantics", not read off the
//! interpreter.

use bip_random_systems::timed::{
    explore, generate, Codel, Cpu, Policy, Position, Preemption, Projected, Stage, Task, TaskSet,
    TaskState, Yield,
};

/// Tick and unit 1 ms: periods, delays and durations below are all in units.
fn set(cpus: Vec<Cpu>, tasks: Vec<Task>) -> TaskSet {
    TaskSet {
        tick_ms: 1,
        unit_us: Some(1000),
        cpus,
        tasks,
    }
}

fn cpu(cores: usize, policy: Policy) -> Cpu {
    Cpu {
        cores,
        policy,
        preemption: Preemption::Job,
    }
}

fn preempting(preemption: Preemption) -> Vec<Cpu> {
    vec![Cpu {
        cores: 1,
        policy: Policy::FixedPriority,
        preemption,
    }]
}

/// A codel of exactly `wcet` units (bcet = wcet) with these yields.
fn exact(wcet: u64, yields: Vec<Yield>) -> Codel {
    Codel {
        bcet_us: Some(wcet * 1000),
        wcet_us: Some(wcet * 1000),
        yields,
        uses: Vec::new(),
    }
}

/// A task on CPU 0 (global), no delay, deadline its period.
fn task(period: u64, priority: i64, codels: Vec<Codel>) -> Task {
    Task {
        module: 0,
        period_ticks: period,
        delay_ticks: 0,
        cpu: 0,
        core: None,
        priority,
        deadline_us: None,
        codels,
    }
}

/// A one-codel job of exactly `wcet` units each period.
fn job(period: u64, priority: i64, wcet: u64) -> Task {
    task(period, priority, vec![exact(wcet, vec![Yield::Pause(0)])])
}

#[test]
fn one_task_responds_in_the_sum_of_its_wcets() {
    // start, c1, c2 in one job, each in a window: the worst is 2 + 3 + 1 = 6, reached
    // when every codel takes its wcet; c1 may also pause, which ends the job after 5
    let codel = |bcet: u64, wcet: u64, yields| Codel {
        bcet_us: Some(bcet * 1000),
        wcet_us: Some(wcet * 1000),
        yields,
        uses: Vec::new(),
    };
    let t = task(
        10,
        1,
        vec![
            codel(1, 2, vec![Yield::Next(1)]),
            codel(0, 3, vec![Yield::Next(2), Yield::Pause(1)]),
            codel(1, 1, vec![Yield::Pause(0)]),
        ],
    );
    let v = explore(&set(vec![cpu(1, Policy::FixedPriority)], vec![t]));
    assert!(v.schedulable);
    assert_eq!(v.worst_response, vec![Some(6)]);
    assert_eq!(v.can_miss, vec![false]);
    assert_eq!(v.earliest_miss, None);
}

#[test]
fn every_state_of_a_tiny_set() {
    // period 2, one codel of exactly 1 unit that pauses back to itself (or fails, which
    // ends the machine); these are all its states, by hand
    let v = explore(&set(
        vec![cpu(1, Policy::FixedPriority)],
        vec![job(2, 1, 1)],
    ));
    let st = |n, stage, position, x, due| Projected {
        n,
        due,
        tasks: vec![TaskState {
            stage,
            position,
            x,
            late: false,
        }],
    };
    use Position::{Ended, Paused, Runnable};
    use Stage::{Idle, Ready};
    let (busy, holds) = (Stage::Running, Position::Running(0));
    let expected = [
        st(0, Idle, Paused(0), 0, false),    // the start
        st(1, Idle, Paused(0), 0, false),    // before the first boundary, and after each job
        st(0, Idle, Paused(0), 0, true),     // at the boundary 2, its release due
        st(0, Ready, Runnable(0), 0, false), // released
        st(0, busy, Runnable(0), 0, false),  // dispatched
        st(0, busy, holds, 0, false),        // started
        st(1, busy, holds, 1, false),        // one unit: at its wcet
        st(1, busy, Paused(0), 0, false),    // finished, pausing
        st(1, busy, Ended, 0, false),        // finished, failing
        st(1, Idle, Ended, 0, false),        // done for ever
        st(0, Idle, Ended, 0, true),         // a boundary with nothing to release
        st(0, Idle, Ended, 0, false),
    ];
    assert_eq!(v.states, expected.into_iter().collect());
    assert_eq!(v.worst_response, vec![Some(1)]);
}

#[test]
fn a_lower_priority_job_waits_for_the_higher_one() {
    // one core, both released at 10: the high one (priority 2) runs [10, 13], the low one
    // [13, 17]: responses 3 and 7
    let v = explore(&set(
        vec![cpu(1, Policy::FixedPriority)],
        vec![job(10, 2, 3), job(10, 1, 4)],
    ));
    assert!(v.schedulable);
    assert_eq!(v.worst_response, vec![Some(3), Some(7)]);
}

#[test]
fn a_miss_at_the_time_worked_out_by_hand() {
    // one core, both released at 5: the high one runs [5, 8], the low one [8, 11]; at 10 the
    // low one's boundary passes while it runs (late: elapsed 5, its deadline, not yet a
    // miss), at 11 its elapsed is 6 > 5
    let v = explore(&set(
        vec![cpu(1, Policy::FixedPriority)],
        vec![job(5, 2, 3), job(5, 1, 3)],
    ));
    assert!(!v.schedulable);
    // the high one can miss too, later: at 17 the low one's deferred release makes it
    // ready, the high one runs [17, 20] and finishes exactly at its boundary 20; taken
    // before the release there, its finish lets the low one take the core at 20, and the
    // high one, released at 20, runs [23, 26]: elapsed 6 > 5 at 26
    assert_eq!(v.can_miss, vec![true, true]);
    assert_eq!(v.earliest_miss, Some(11));
    // the high one's job released at 20 ends at 26, the most it can wait; the low one,
    // released at 15, waits for the high one's [17, 20] and is still ready when the
    // boundary 20 is released, its second late one: its figure (9) is a period short of
    // what it could be, and only the coalescing says so
    assert_eq!(v.worst_response[0], Some(6));
    assert_eq!(v.coalesces, vec![false, true]);
}

#[test]
fn two_global_cores_run_two_jobs_at_once() {
    // three jobs of 4 released at 10 on two global cores: the two highest run [10, 14],
    // the lowest [14, 18]
    let tasks = vec![job(10, 3, 4), job(10, 2, 4), job(10, 1, 4)];
    let v = explore(&set(vec![cpu(2, Policy::FixedPriority)], tasks.clone()));
    assert!(v.schedulable);
    assert_eq!(v.worst_response, vec![Some(4), Some(4), Some(8)]);
    // pinned to cores 0, 0, 1 instead: the middle one waits for the first
    let pinned: Vec<Task> = tasks
        .into_iter()
        .zip([0, 0, 1])
        .map(|(t, k)| Task { core: Some(k), ..t })
        .collect();
    let v = explore(&set(vec![cpu(2, Policy::FixedPriority)], pinned));
    assert_eq!(v.worst_response, vec![Some(4), Some(8), Some(4)]);
    // on one core they would need 12 of every 10
    let one = vec![job(10, 3, 4), job(10, 2, 4), job(10, 1, 4)];
    let v = explore(&set(vec![cpu(1, Policy::FixedPriority)], one));
    assert!(!v.schedulable);
    // the lowest misses first ([18, 22], past 20 at 21). The middle one too: after 20 the
    // highest runs [22, 26] and the middle one [26, 30]; it finishes exactly at the
    // boundary 30, and taken before the release there, its finish lets the lowest (ready
    // since its deferred release at 22) take the core; the middle one, released at 30,
    // runs [38, 42]. The highest never waits more than one job of 4.
    assert_eq!(v.can_miss, vec![false, true, true]);
}

#[test]
fn a_job_done_at_its_next_release_meets_its_deadline() {
    // period 4, a codel of exactly 4: released at 4, it holds the core until 8, when the
    // next boundary's release and its finish are due at once, in either order: released
    // first (late), the job's end releases it again at once; finished first, the boundary
    // finds the task idle. Either way the response is 4 = its deadline, not a miss
    let v = explore(&set(
        vec![cpu(1, Policy::FixedPriority)],
        vec![job(4, 1, 4)],
    ));
    assert!(v.schedulable, "{:?}", v.earliest_miss);
    assert_eq!(v.worst_response, vec![Some(4)]);
    let late_at_wcet = Projected {
        n: 0,
        due: false,
        tasks: vec![TaskState {
            stage: Stage::Running,
            position: Position::Running(0),
            x: 4,
            late: true,
        }],
    };
    assert!(v.states.contains(&late_at_wcet));
    // with a deadline of 3 the same job misses, first at 4 + 3 + 1 = 8
    let tight = Task {
        deadline_us: Some(3000),
        ..job(4, 1, 4)
    };
    let v = explore(&set(vec![cpu(1, Policy::FixedPriority)], vec![tight]));
    assert!(!v.schedulable);
    assert_eq!(v.earliest_miss, Some(8));
}

/// One core, `Job`, fixed priorities: `hi` of period and deadline 4 ms, `lo` of period
/// 8 ms, each codel between 0 and 4 ms. In real time: at 8 ms both are released, `hi`
/// runs 2 ms, `lo` 4 ms from 10 to 14, and `hi`, released at 12, waits for it and runs
/// 4 ms more, until 18: past its deadline at 16. At the 4 ms unit the same order of events
/// is an integer run: `hi` runs 8 to 12, finishes, `lo` takes the core at 12 before the
/// boundary's release at 12 (due, not yet applied), and `hi` waits until 16. A release
/// applied with the tick, before the instant's other steps, would give `hi` the core at 12
/// and miss this schedule at 4 ms.
#[test]
fn a_release_is_ordered_freely_among_its_instants_steps() {
    let codel = Codel {
        bcet_us: None,
        wcet_us: Some(4000),
        yields: vec![Yield::Pause(0)],
        uses: Vec::new(),
    };
    let hi = Task {
        codels: vec![codel.clone()],
        ..job(1, 2, 0)
    };
    let lo = Task {
        codels: vec![codel],
        ..job(2, 1, 0)
    };
    for unit_us in [4000, 2000] {
        let mut s = set(
            vec![cpu(1, Policy::FixedPriority)],
            vec![hi.clone(), lo.clone()],
        );
        s.tick_ms = 4;
        s.unit_us = Some(unit_us);
        let v = explore(&s);
        assert!(v.can_miss[0], "unit {unit_us} µs");
    }
}

/// Integer time is exact (docs/model.md, "Why whole units are enough"): on random sets,
/// exploring at half the unit finds no other verdict, and the same worst responses.
#[test]
fn a_finer_unit_finds_nothing_new() {
    for seed in 0..300 {
        let coarse = generate(seed);
        let unit = coarse.unit_us();
        let fine = TaskSet {
            unit_us: Some(unit / 2),
            ..coarse.clone()
        };
        let (c, f) = (explore(&coarse), explore(&fine));
        assert_eq!(c.can_miss, f.can_miss, "seed {seed}");
        let halves: Vec<Option<u64>> = c.worst_response.iter().map(|w| w.map(|u| 2 * u)).collect();
        assert_eq!(halves, f.worst_response, "seed {seed}");
        // the earliest miss is seen within a unit of the finer one's
        if let (Some(ce), Some(fe)) = (c.earliest_miss, f.earliest_miss) {
            assert!(
                2 * ce >= fe && 2 * ce <= fe + 2,
                "seed {seed}: {ce} vs {fe} halves"
            );
        }
    }
}

#[test]
fn edf_meets_a_deadline_fixed_priority_misses() {
    // one core, both released at 10: `slack` has the higher priority but deadline 10,
    // `urgent` the lower priority but deadline 4. Fixed priority: slack [10, 13], urgent
    // [13, 16], elapsed 6 > 4 from 15. EDF: urgent (due at 14) first [10, 13], then slack
    // [13, 16]: responses 3 and 6.
    let slack = job(10, 2, 3);
    let urgent = Task {
        deadline_us: Some(4000),
        ..job(10, 1, 3)
    };
    let tasks = vec![slack, urgent];
    let fp = explore(&set(vec![cpu(1, Policy::FixedPriority)], tasks.clone()));
    assert!(!fp.schedulable);
    assert_eq!(fp.can_miss, vec![false, true]);
    assert_eq!(fp.earliest_miss, Some(15));
    let edf = explore(&set(vec![cpu(1, Policy::Edf)], tasks));
    assert!(edf.schedulable);
    assert_eq!(edf.worst_response, vec![Some(6), Some(3)]);
}

#[test]
fn delays_place_the_boundaries() {
    // period 5, delay 2: boundaries at 2, 7, 12, …; a job of 3 is released at 2 and done at
    // 5; a second task without delay released at 5 on the same core finds it free
    let delayed = Task {
        delay_ticks: 2,
        ..job(5, 2, 3)
    };
    let v = explore(&set(
        vec![cpu(1, Policy::FixedPriority)],
        vec![delayed, job(5, 1, 2)],
    ));
    assert!(v.schedulable);
    assert_eq!(v.worst_response, vec![Some(3), Some(2)]);
}

#[test]
fn the_unit_is_derived_from_every_duration() {
    // tick 2 ms, periods 4 and 6 ticks (8 and 12 ms), wcets 2 ms and 4 ms: the unit is 2 ms
    let mut s = set(
        vec![cpu(1, Policy::FixedPriority)],
        vec![job(4, 2, 2), job(6, 1, 4)],
    );
    s.tick_ms = 2;
    s.unit_us = None;
    assert_eq!(s.unit_us(), 2000);
    assert_eq!((s.period(0), s.period(1), s.hyperperiod()), (4, 6, 12));
    assert_eq!(s.window(1, 0), (2, 2));
    // a 1 ms bcet makes it 1 ms
    s.tasks[0].codels[0].bcet_us = Some(1000);
    assert_eq!(s.unit_us(), 1000);
}

#[test]
fn random_sets_explore_and_render() {
    let (mut schedulable, mut not) = (0, 0);
    let mut preemptions = std::collections::BTreeMap::new();
    for seed in 0..200 {
        let s = generate(seed);
        let v = explore(&s);
        assert!(v.states.len() > 1, "seed {seed}");
        assert_eq!(v.schedulable, v.earliest_miss.is_none(), "seed {seed}");
        if v.schedulable {
            schedulable += 1;
        } else {
            not += 1;
        }
        let ron = s.to_ron();
        assert!(ron.contains("time: Exact") && ron.contains("preemption: "));
        for p in ["Job", "Codel", "Preemptive"] {
            *preemptions.entry(p).or_insert(0) += ron.matches(&format!("preemption: {p}")).count();
        }
    }
    // every preemption is drawn
    assert!(preemptions.values().all(|&n| n > 30), "{preemptions:?}");
    // the generator gives both verdicts often enough for a property test to mean something
    assert!(
        schedulable > 40 && not > 40,
        "{schedulable} schedulable, {not} not"
    );
}

#[test]
fn a_set_renders_in_the_timed_syntax() {
    let pinned = Task {
        delay_ticks: 1,
        core: Some(1),
        deadline_us: Some(1500),
        codels: vec![
            Codel {
                bcet_us: Some(500),
                wcet_us: Some(1000),
                yields: vec![Yield::Next(1), Yield::Pause(0)],
                uses: Vec::new(),
            },
            Codel {
                bcet_us: None,
                wcet_us: None,
                yields: vec![Yield::Pause(1)],
                uses: Vec::new(),
            },
        ],
        ..job(2, 7, 1)
    };
    let global = Task {
        module: 1,
        cpu: 1,
        ..job(3, 1, 2)
    };
    let mut s = set(
        vec![cpu(2, Policy::FixedPriority), cpu(1, Policy::Edf)],
        vec![pinned, global],
    );
    s.unit_us = Some(500);
    assert_eq!(
        s.to_ron(),
        r#"System(
  name: "timed",
  tick_ms: 1,
  time: Exact(unit: "500us"),
  cpus: [
    (name: "cpu0", cores: 2, policy: FixedPriority, preemption: Job),
    (name: "cpu1", cores: 1, policy: Edf, preemption: Job),
  ],
  modules: [
    (name: "m0", tasks: [
      (name: "t0", period: 2, delay: 1, cpu: "cpu0", priority: 7, core: 1, deadline: "1500us",
       codels: [
         (state: "start", yields: ["c1", "pause::start"], bcet: "500us", wcet: "1ms"),
         (state: "c1", yields: ["pause::c1"]),
       ]),
    ]),
    (name: "m1", tasks: [
      (name: "t1", period: 3, delay: 0, cpu: "cpu1",
       codels: [
         (state: "start", yields: ["pause::start"], bcet: "2ms", wcet: "2ms"),
       ]),
    ]),
  ],
)
"#
    );
    // locks: ids members, the module's out port, an in port connected to `m0.p`
    s.tasks[0].codels[0].uses = vec!["a", "p"];
    s.tasks[1].codels[0].uses = vec!["q"];
    let text = s.to_ron();
    for line in [
        r#"    (name: "m0", ports: [(name: "p")], tasks: ["#,
        r#"    (name: "m1", ports: [(name: "p")], in_ports: [(name: "q")], tasks: ["#,
        r#"         (state: "start", yields: ["c1", "pause::start"], bcet: "500us", wcet: "1ms", uses: ["a", "p"]),"#,
        r#"         (state: "start", yields: ["pause::start"], bcet: "2ms", wcet: "2ms", uses: ["q"]),"#,
        r#"    (port: "m1.q", reads: "m0.p"),"#,
    ] {
        assert!(text.lines().any(|l| l == line), "{line}\n{text}");
    }
}

/// `lo` (period 8, one codel of exactly 3) starts at 8, 16, …; `hi` (period 4, delay 1,
/// one codel of exactly 2) is released at 9, 13, 17, … while `lo` may run: the worst
/// responses of (`hi`, `lo`).
fn hi_during_lo(preemption: Preemption) -> (Option<u64>, Option<u64>) {
    let mut hi = job(4, 2, 2);
    hi.delay_ticks = 1;
    let lo = task(8, 1, vec![exact(3, vec![Yield::Pause(0)])]);
    let v = explore(&set(preempting(preemption), vec![hi, lo]));
    (v.worst_response[0], v.worst_response[1])
}

#[test]
fn preemption_stops_the_running_codel() {
    // Job: `hi` released at 9 waits for `lo` (8 to 11) and runs to 13: 4; `lo` always
    // finds the core free at its release (`hi` runs 13 to 15, 21 to 23): 3
    assert_eq!(hi_during_lo(Preemption::Job), (Some(4), Some(3)));
    // Preemptive: `hi` takes the core at 9 and runs to 11: 2; `lo`, stopped after 1 of
    // its 3 units, goes on at 11 and ends at 13: 5
    assert_eq!(hi_during_lo(Preemption::Preemptive), (Some(2), Some(5)));
}

#[test]
fn a_codel_boundary_is_where_a_cooperative_task_gives_its_core() {
    // `lo` runs two codels of exactly 2 from 8: at 9 `hi` is released and waits until
    // `lo`'s first codel ends at 10, takes the core to 12 (response 3), `lo` runs its
    // second codel 12 to 14 (6), and at 13 `hi` waits again until 14 (response 3)
    let mut hi = job(4, 2, 2);
    hi.delay_ticks = 1;
    let lo = task(
        8,
        1,
        vec![
            exact(2, vec![Yield::Next(1)]),
            exact(2, vec![Yield::Pause(0)]),
        ],
    );
    let v = explore(&set(preempting(Preemption::Codel), vec![hi, lo]));
    assert_eq!(v.worst_response, vec![Some(3), Some(6)]);
}
