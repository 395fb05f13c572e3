//! Random small timed task sets, their model files, and a naive interpreter of the timed
//! semantics (docs/model.md, "Timed semantics") that answers for them.
//!
//! A [`TaskSet`] is a timed model with task machines only: no services, no requests, no
//! ports. [`generate`] draws one, [`TaskSet::to_ron`] writes it as a model file, and
//! [`explore`] runs every behaviour of it one time unit at a time and returns a
//! [`Verdict`]: whether it is schedulable, each task's worst response time and whether
//! it can miss its deadline, and the set of reachable states projected on what the timed
//! semantics stores ([`Projected`]). A property test compares an expansion's exploration
//! with it.

mod oracle;
mod ron;

pub use oracle::{explore, Position, Projected, Stage, TaskState, Verdict};

/// When a task may lose its core (docs/model.md, "Preemption").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preemption {
    /// Never before its job is done.
    Job,
    /// Between two codels of its job, to a ready task that comes first.
    Codel,
    /// At any unit, to a ready task that comes first; its running codel waits.
    Preemptive,
}

use crate::Rng;

/// A timed model: CPUs, and tasks with their own state machines.
#[derive(Clone, Debug)]
pub struct TaskSet {
    /// The length of a tick in milliseconds: task periods and delays are in ticks.
    pub tick_ms: u64,
    /// The declared time unit in microseconds (`time: Exact(unit: ...)`); none: the unit is
    /// derived ([`TaskSet::unit_us`]).
    pub unit_us: Option<u64>,
    pub cpus: Vec<Cpu>,
    /// In declaration order: the modules' order, then the tasks' within a module (EDF
    /// breaks ties by it).
    pub tasks: Vec<Task>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Policy {
    FixedPriority,
    Edf,
}

/// A CPU: `cores` cores shared by its tasks.
#[derive(Clone, Debug)]
pub struct Cpu {
    pub cores: usize,
    pub policy: Policy,
    pub preemption: Preemption,
}

#[derive(Clone, Debug)]
pub struct Task {
    /// The module it is written in (modules are named `m0`, `m1`, …).
    pub module: usize,
    pub period_ticks: u64,
    pub delay_ticks: u64,
    pub cpu: usize,
    /// Pinned to this core of its CPU; none: global on its CPU's cores.
    pub core: Option<usize>,
    /// Larger is more urgent (fixed-priority CPUs; not written for EDF ones).
    pub priority: i64,
    /// None: the period.
    pub deadline_us: Option<u64>,
    /// The task machine: codel 0 is `start`, codel i > 0 is `c{i}`.
    pub codels: Vec<Codel>,
}

#[derive(Clone, Debug)]
pub struct Codel {
    /// None: 0.
    pub bcet_us: Option<u64>,
    /// None: the codel takes no time.
    pub wcet_us: Option<u64>,
    /// At least one. Besides these, every codel may fail, which ends the task machine.
    pub yields: Vec<Yield>,
    /// The names its `uses` lists, each a lock it holds while it runs (docs/model.md,
    /// "Codel locks"): `a` and `b`, ids members of its module; `p`, its module's out
    /// port; `q`, an in port of a module other than `m0`, connected to `m0.p`.
    pub uses: Vec<&'static str>,
}

/// What a name of a codel's `uses` locks, for a task of `module`: (the module it belongs
/// to, its name there); `q` is `m0.p`, which it reads.
pub fn lock(module: usize, name: &str) -> (usize, &str) {
    match name {
        "q" => (0, "p"),
        other => (module, other),
    }
}

/// Where a codel of a task machine may go next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Yield {
    /// Run this codel in the same job (a plain yield).
    Next(usize),
    /// Run this codel at the task's next period boundary (`pause::`).
    Pause(usize),
}

/// The name of codel `i` of a task machine.
pub fn codel_name(i: usize) -> String {
    if i == 0 {
        "start".into()
    } else {
        format!("c{i}")
    }
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

fn lcm(a: u64, b: u64) -> u64 {
    a / gcd(a, b) * b
}

impl Task {
    /// (name of its module, name of the task): `m{module}` and `t{index}`, the index
    /// counted over the whole set so that names stay unique whatever the modules.
    pub fn names(&self, index: usize) -> (String, String) {
        (format!("m{}", self.module), format!("t{index}"))
    }
}

impl TaskSet {
    /// Every duration of the model in microseconds: the tick, periods, delays, deadlines,
    /// bcets, wcets (zeros included).
    fn durations_us(&self) -> impl Iterator<Item = u64> + '_ {
        let tick = self.tick_ms * 1000;
        // the tick too: ports age once per tick, so a unit divides it
        std::iter::once(tick).chain(self.tasks.iter().flat_map(move |t| {
            [
                t.period_ticks * tick,
                t.delay_ticks * tick,
                t.deadline_us.unwrap_or(0),
            ]
            .into_iter()
            .chain(
                t.codels
                    .iter()
                    .flat_map(|c| [c.bcet_us.unwrap_or(0), c.wcet_us.unwrap_or(0)]),
            )
        }))
    }

    /// The time unit in microseconds: the declared one, or the gcd of every duration of
    /// the model.
    pub fn unit_us(&self) -> u64 {
        self.unit_us
            .unwrap_or_else(|| self.durations_us().fold(0, gcd).max(1))
    }

    /// A duration in units (the unit divides it in every set this module builds).
    pub fn units(&self, us: u64) -> u64 {
        us / self.unit_us()
    }

    pub fn period(&self, task: usize) -> u64 {
        self.units(self.tasks[task].period_ticks * self.tick_ms * 1000)
    }

    pub fn delay(&self, task: usize) -> u64 {
        self.units(self.tasks[task].delay_ticks * self.tick_ms * 1000)
    }

    pub fn deadline(&self, task: usize) -> u64 {
        let t = &self.tasks[task];
        t.deadline_us.map_or(self.period(task), |d| self.units(d))
    }

    /// (bcet, wcet) of a codel in units.
    pub fn window(&self, task: usize, codel: usize) -> (u64, u64) {
        let c = &self.tasks[task].codels[codel];
        (
            self.units(c.bcet_us.unwrap_or(0)),
            self.units(c.wcet_us.unwrap_or(0)),
        )
    }

    /// The hyperperiod in units: time is counted modulo it.
    pub fn hyperperiod(&self) -> u64 {
        (0..self.tasks.len()).fold(1, |h, t| lcm(h, self.period(t)))
    }
}

/// A random task set: 1-4 tasks on 1-2 CPUs of 1-3 cores, each CPU pinned or global and
/// fixed-priority or EDF; 1-3 codels per task, each yielding the next codel, a `pause::`,
/// or either; windows, delays and deadlines small enough for the interpreter to explore
/// every behaviour.
pub fn generate(seed: u64) -> TaskSet {
    let mut r = Rng(seed);
    // a tick of 1 or 2 ms, durations in whole milliseconds or, now and then with a tick
    // of 1 ms, in halves
    let tick_ms = 1 + r.below(2) as u64;
    let grain_us = if tick_ms == 1 && r.chance(20) {
        500
    } else {
        1000
    };
    let cpus: Vec<(Cpu, bool)> = (0..1 + r.below(2))
        .map(|_| {
            let cpu = Cpu {
                cores: 1 + r.below(3),
                policy: if r.chance(30) {
                    Policy::Edf
                } else {
                    Policy::FixedPriority
                },
                preemption: Preemption::Job,
            };
            (cpu, r.chance(50))
        })
        .collect();
    let modules = 1 + r.below(2);
    let count = 1 + r.below(4);
    let mut tasks = Vec::new();
    for i in 0..count {
        // periods that keep the hyperperiod at 12 ticks at most
        let period_ticks = [2, 3, 4, 6][r.below(4)];
        let period_us = period_ticks * tick_ms * 1000;
        let period_grains = period_us / grain_us;
        let cpu = r.below(cpus.len());
        let (cpu_def, pinned) = &cpus[cpu];
        let codels: Vec<Codel> = {
            let n = 1 + r.below(3);
            (0..n)
                .map(|c| {
                    // a job's codels together fit in about one period, so that most sets
                    // are schedulable and some are not
                    // durations are positive: a codel without a wcet takes no time, one
                    // without a bcet may take none
                    let most = (period_grains as usize / n).max(1);
                    let wcet = r.chance(80).then(|| 1 + r.below(most) as u64);
                    let bcet = match wcet {
                        Some(w) if r.chance(50) => Some(1 + r.below(w as usize) as u64),
                        _ => None,
                    };
                    let pause = Yield::Pause(r.below(n));
                    let yields = if c + 1 < n {
                        match r.below(4) {
                            0 => vec![Yield::Next(c + 1)],
                            _ => vec![Yield::Next(c + 1), pause],
                        }
                    } else {
                        vec![pause]
                    };
                    Codel {
                        bcet_us: bcet.map(|b| b * grain_us),
                        wcet_us: wcet.map(|w| w * grain_us),
                        yields,
                        uses: Vec::new(),
                    }
                })
                .collect()
        };
        let deadline_us = r
            .chance(40)
            .then(|| (1 + r.below(period_grains as usize) as u64) * grain_us);
        tasks.push(Task {
            module: if i == 0 { 0 } else { r.below(modules) },
            period_ticks,
            delay_ticks: if r.chance(50) {
                r.below(period_ticks as usize) as u64
            } else {
                0
            },
            cpu,
            core: pinned.then(|| r.below(cpu_def.cores)),
            priority: 0,
            deadline_us,
            codels,
        });
    }
    // declaration order is the modules' order, then the tasks' within each
    tasks.sort_by_key(|t| t.module);
    // distinct priorities per CPU: a random order of the tasks
    let mut order: Vec<usize> = (0..tasks.len()).collect();
    for i in (1..order.len()).rev() {
        order.swap(i, r.below(i + 1));
    }
    for (rank, &t) in order.iter().enumerate() {
        tasks[t].priority = 1 + rank as i64;
    }
    let unit_us = match r.below(3) {
        0 => Some(grain_us),
        _ => None,
    };
    // locks in half the sets, drawn last so that the other half are the sets drawn
    // before locks existed
    if r.chance(50) {
        for t in tasks.iter_mut() {
            let pool: &[&'static str] = match t.module {
                0 => &["a", "b", "p"],
                _ => &["a", "b", "p", "q"],
            };
            for c in t.codels.iter_mut() {
                for &name in pool {
                    if r.chance(30) {
                        c.uses.push(name);
                    }
                }
            }
        }
    }
    // preemption drawn after locks, for the same reason
    let mut cpus: Vec<Cpu> = cpus.into_iter().map(|(c, _)| c).collect();
    for c in cpus.iter_mut() {
        c.preemption = match r.below(3) {
            0 => Preemption::Job,
            1 => Preemption::Codel,
            _ => Preemption::Preemptive,
        };
    }
    // the tasks competing for a preemptive CPU's cores share no lock: a model refuses
    // them (a task waiting for a lock keeps its core, which a holder preempted by it
    // would need; docs/model.md, "Codel locks")
    for i in 0..tasks.len() {
        for j in 0..i {
            let (a, b) = (&tasks[j], &tasks[i]);
            let competing = a.cpu == b.cpu && a.core == b.core;
            if !competing || cpus[a.cpu].preemption != Preemption::Preemptive {
                continue;
            }
            let held: Vec<(usize, &'static str)> = a
                .codels
                .iter()
                .flat_map(|c| c.uses.iter().map(|&u| lock(a.module, u)))
                .collect();
            let module = b.module;
            for c in tasks[i].codels.iter_mut() {
                c.uses.retain(|&u| !held.contains(&lock(module, u)));
            }
        }
    }
    TaskSet {
        tick_ms,
        unit_us,
        cpus,
        tasks,
    }
}
