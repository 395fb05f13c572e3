//! A timed layer (`time: Exact`, docs/model.md, "Time budgets"), checked: the time unit
//! (declared, or the greatest common divisor of the model's durations), every duration
//! in units, the common cycle of the periods, the CPUs' cores and scheduling, and each
//! task's core; what the timed expansion works from. What this version does not
//! schedule yet (aperiodic tasks, atoms' tasks, async codels) is refused at the value
//! that asks for it.

use std::collections::HashMap;

use super::check::Layer;
use super::timing::Timing;
use crate::compile::budgets::{duration, show_us, written_duration};
use crate::compile::Constants;
use crate::diag::{Errors, ModelError};
use crate::source::{ConstExpr, Span};
use crate::syntax::{Policy, Preemption, PropertyDef, SystemDef};

/// The common cycle of a timed model's periods is at most this many time units.
pub(crate) const MAX_HYPERPERIOD: u64 = 1 << 20;

/// A timed layer, every duration in time units.
#[derive(Clone, Debug)]
pub(crate) struct Timed {
    pub unit_us: u64,
    /// The units in a tick of `tick_ms`.
    pub tick_units: u64,
    /// The least common multiple of the periods.
    pub hyperperiod: u64,
    /// The number of cores of each CPU (one CPU when the model declares none).
    pub cores: Vec<u32>,
    /// Whether each CPU dispatches by earliest deadline (else by fixed priority).
    pub edf: Vec<bool>,
    /// When each CPU's tasks may lose their core.
    pub preemption: Vec<Preemption>,
    /// Per module, per task.
    pub tasks: Vec<Vec<TimedTask>>,
    /// (best, worst) execution time by (module, service, codel state) indices; a codel
    /// without a WCET takes (0, 0).
    pub codels: HashMap<(usize, usize, usize), (u64, u64)>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct TimedTask {
    pub period: u64,
    /// Below the period.
    pub delay: u64,
    /// At most the period.
    pub deadline: u64,
    pub cpu: u32,
    /// Pinned to this core of its CPU; `None`: on any free core.
    pub core: Option<u32>,
    /// Larger is more urgent; distinct among the tasks of a CPU (rate-monotonic when the
    /// model gives none: shorter periods first, then in declaration order).
    pub priority: i64,
}

impl Timed {
    pub fn task(&self, module: usize, task: usize) -> &TimedTask {
        &self.tasks[module][task]
    }

    /// A codel's (best, worst) execution time in units.
    pub fn codel(&self, module: usize, service: usize, codel: usize) -> (u64, u64) {
        self.codels
            .get(&(module, service, codel))
            .copied()
            .unwrap_or((0, 0))
    }
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// A duration of the model, where it is written and what it is.
struct Written {
    us: u64,
    span: Span,
    what: String,
}

/// Checks a timed layer; `None` once an error is reported (or the model is untimed).
pub(super) fn check(
    def: &SystemDef,
    layer: &Layer<'_>,
    consts: &Constants,
    timing: &Timing,
    errors: &mut Errors,
) -> Option<Timed> {
    def.time.as_ref()?;
    let mut mine = Errors::default();
    let (tick_us, cores) = (timing.tick_us, &timing.cores);
    let timed = check_in(def, layer, consts, timing, tick_us, cores, &mut mine);
    if errors.absorb(mine) {
        return None;
    }
    timed
}

fn check_in(
    def: &SystemDef,
    layer: &Layer<'_>,
    consts: &Constants,
    timing: &Timing,
    tick_us: Option<u64>,
    cores: &[Option<u32>],
    errors: &mut Errors,
) -> Option<Timed> {
    let time = def.time.as_ref()?;
    let Some(tick_us) = tick_us else {
        if def.tick_ms.is_none() {
            errors.push(
                ModelError::new("a timed model needs the model's `tick_ms`", time.span)
                    .with_label("task periods are in ticks")
                    .with_help("give the length of a tick, e.g. `tick_ms: 1`, beside `name`"),
            );
        }
        return None;
    };
    unsupported_tasks(def, layer, errors);
    // every duration, in file order: the declared unit must divide each
    let mut written: Vec<Written> = Vec::new();
    let mut push = |us: u64, span: Span, what: String| written.push(Written { us, span, what });
    // ports age once per tick, and the engine's clock counts ticks
    let tick_span = def.tick_ms.as_ref().map_or(time.span, |t| t.span);
    push(tick_us, tick_span, "a tick (`tick_ms`)".to_string());
    for m in &layer.modules {
        for (ti, t) in m.def.tasks.iter().enumerate() {
            let name = format!("`{}.{}`", m.name, t.name);
            let (Some(period), Some(p)) = (m.tasks[ti].1, &t.period) else {
                continue;
            };
            push(
                period as u64 * tick_us,
                p.span,
                format!("the period of {name}"),
            );
            if let Some(d) = &t.delay {
                push(
                    m.delays[ti] as u64 * tick_us,
                    d.span,
                    format!("the delay of {name}"),
                );
            }
            let budget = &timing.tasks[&(m.name.to_string(), t.name.value.clone())];
            if let (Some(us), Some(d)) = (budget.deadline_us, &t.deadline) {
                push(us, d.span, format!("the deadline of {name}"));
            }
        }
        for s in &m.services {
            for c in &s.codels {
                let key = (m.name.to_string(), s.name.to_string(), c.state.to_string());
                let name = format!("codel `{}` of `{}.{}`", c.state, m.name, s.name);
                if let (Some(&us), Some(b)) = (timing.bcets.get(&key), &c.def.bcet) {
                    push(us, b.span, format!("the BCET of {name}"));
                }
                if let (Some(&us), Some(w)) = (timing.wcets.get(&key), &c.def.wcet) {
                    push(us, w.span, format!("the WCET of {name}"));
                }
            }
        }
    }
    // a bound in real time is counted in units too
    for p in &def.properties {
        let within = match p {
            PropertyDef::Response { within, .. } => Some(within),
            PropertyDef::Replies { within, .. } => within.as_ref(),
            _ => None,
        };
        if let Some((Some(Ok(us)), k)) = within.map(|k| (written_duration(k), k)) {
            push(us, k.span, format!("the bound of `{}`", p.name()));
        }
    }
    let unit_us = match &time.unit {
        Some(u) => declared_unit(errors, consts, u, &written)?,
        None => written.iter().fold(tick_us, |g, w| gcd(g, w.us)),
    };
    if !errors.is_empty() {
        return None;
    }
    let units = |us: u64| us / unit_us;
    let mut tasks = Vec::new();
    // whether each task's priority is given, in declaration order
    let mut given = Vec::new();
    let mut hyperperiod = 1u64;
    for m in &layer.modules {
        let mut of_module = Vec::new();
        for (ti, t) in m.def.tasks.iter().enumerate() {
            let period = units(m.tasks[ti].1.unwrap_or(1) as u64 * tick_us);
            hyperperiod = (hyperperiod / gcd(hyperperiod, period)).saturating_mul(period);
            if hyperperiod > MAX_HYPERPERIOD {
                let span = t.period.as_ref().map_or(t.name.span, |p| p.span);
                errors.push(
                    ModelError::new(
                        format!(
                            "the task periods have a common cycle longer than {MAX_HYPERPERIOD} time units of {}",
                            show_us(unit_us)
                        ),
                        span,
                    )
                    .with_label("with the periods before it, this period makes the cycle too long")
                    .with_help("use periods with a small least common multiple, or a coarser `unit` in `time: Exact(unit: ...)`"),
                );
                return None;
            }
            let budget = &timing.tasks[&(m.name.to_string(), t.name.value.clone())];
            let deadline = budget.deadline_us.map_or(period, units);
            if deadline > period {
                let d = t.deadline.as_ref().map_or(t.name.span, |d| d.span);
                errors.push(
                    ModelError::new(
                        format!(
                            "task `{}.{}` has a deadline of {}, past its period ({})",
                            m.name,
                            t.name,
                            show_us(deadline * unit_us),
                            show_us(period * unit_us)
                        ),
                        d,
                    )
                    .with_label("in a timed model a deadline is at most the period")
                    .with_help("a period's work is released again at the next period: give a deadline up to the period, or a longer period"),
                );
            }
            let core = t.core.as_ref().and_then(|c| {
                core(
                    errors,
                    consts,
                    c,
                    budget.cpu,
                    cores,
                    &def.cpus,
                    &t.name.value,
                )
            });
            of_module.push(TimedTask {
                period,
                delay: units(m.delays[ti] as u64 * tick_us),
                deadline,
                cpu: budget.cpu,
                core,
                priority: budget.priority.unwrap_or(0),
            });
            given.push(budget.priority.is_some());
        }
        tasks.push(of_module);
    }
    pinned_or_global(layer, &tasks, def, errors);
    rate_monotonic(&mut tasks, &given);
    let mut codels = HashMap::new();
    for (mi, m) in layer.modules.iter().enumerate() {
        for (si, s) in m.services.iter().enumerate() {
            for (ci, c) in s.codels.iter().enumerate() {
                let key = (m.name.to_string(), s.name.to_string(), c.state.to_string());
                let wcet = timing.wcets.get(&key).copied().unwrap_or(0);
                let bcet = timing.bcets.get(&key).copied().unwrap_or(0);
                codels.insert((mi, si, ci), (units(bcet), units(wcet)));
            }
        }
    }
    let cores = if def.cpus.is_empty() {
        vec![1]
    } else {
        cores.iter().map(|c| c.unwrap_or(1)).collect()
    };
    let edf = if def.cpus.is_empty() {
        vec![false]
    } else {
        def.cpus
            .iter()
            .map(|c| c.policy.as_ref().is_some_and(|p| p.value == Policy::Edf))
            .collect()
    };
    let preemption = if def.cpus.is_empty() {
        vec![Preemption::Preemptive]
    } else {
        def.cpus.iter().map(|c| c.preemption()).collect()
    };
    Some(Timed {
        unit_us,
        tick_units: tick_us / unit_us,
        hyperperiod,
        cores,
        edf,
        preemption,
        tasks,
        codels,
    })
}

/// A declared unit, checked against every duration of the model.
fn declared_unit(
    errors: &mut Errors,
    consts: &Constants,
    unit: &ConstExpr,
    written: &[Written],
) -> Option<u64> {
    let unit_us = duration(errors, consts, unit, "a time unit")?;
    if let Some(w) = written.iter().find(|w| w.us % unit_us != 0) {
        errors.push(
            ModelError::new(
                format!(
                    "{} ({}) is not a whole number of time units of {}",
                    w.what,
                    show_us(w.us),
                    show_us(unit_us)
                ),
                w.span,
            )
            .with_note(unit.span, "the time unit")
            .with_help("declare a unit that divides every period, delay, deadline, BCET and WCET, or leave `unit` out: bip then takes the largest that does"),
        );
        return None;
    }
    Some(unit_us)
}

/// The tasks a timed model does not schedule yet: aperiodic ones, atoms' tasks, and
/// tasks with `async` codels.
fn unsupported_tasks(def: &SystemDef, layer: &Layer<'_>, errors: &mut Errors) {
    for m in &layer.modules {
        for s in &m.services {
            for c in s.codels.iter().filter(|c| c.def.asynchronous) {
                errors.push(
                    ModelError::new(
                        format!(
                            "codel `{}` of `{}.{}` is async, which a timed model does not support yet",
                            c.state, m.name, s.name
                        ),
                        c.def.state.span,
                    )
                    .with_help("leave `time` out (an untimed model runs async codels apart from their task), or make the codel synchronous"),
                );
            }
        }
        for (ti, t) in m.def.tasks.iter().enumerate() {
            if m.tasks[ti].1.is_none() {
                errors.push(
                    ModelError::new(
                        format!(
                            "task `{}.{}` is aperiodic, which a timed model does not support yet",
                            m.name, t.name
                        ),
                        t.name.span,
                    )
                    .with_help("give the task a `period`"),
                );
            }
        }
    }
    for (name, atom) in def.atoms.iter() {
        if let Some(task) = &atom.task {
            errors.push(
                ModelError::new(
                    format!("atom `{name}` stands for a task, which a timed model does not schedule yet"),
                    task.period.span,
                )
                .with_help("in a timed model, write the task as a GenoM task with codels"),
            );
        }
    }
}

/// A task's `core`, checked against its CPU's cores.
fn core(
    errors: &mut Errors,
    consts: &Constants,
    written: &ConstExpr,
    cpu: u32,
    cores: &[Option<u32>],
    cpus: &[crate::syntax::CpuDef],
    task: &str,
) -> Option<u32> {
    let k = match consts.int(written) {
        Ok(k) => k,
        Err(e) => {
            errors.push(e);
            return None;
        }
    };
    // a wrong core count is reported by itself
    let n = match cores.get(cpu as usize) {
        Some(n) => (*n)?,
        None => 1,
    };
    if (0..i64::from(n)).contains(&k) {
        return Some(k as u32);
    }
    let cpu_name = cpus.get(cpu as usize).map_or("", |c| c.name.as_str());
    let cores_are = if n == 1 {
        "core 0".to_string()
    } else {
        format!("cores 0 to {}", n - 1)
    };
    errors.push(
        ModelError::new(
            format!("task `{task}` is pinned to core {k} of CPU `{cpu_name}`, which has {n}"),
            written.span,
        )
        .with_label(format!("its CPU has {cores_are}"))
        .with_help("pin the task to one of its CPU's cores, or give the CPU more `cores`"),
    );
    None
}

/// Every task of a CPU is pinned, or none is.
fn pinned_or_global(
    layer: &Layer<'_>,
    tasks: &[Vec<TimedTask>],
    def: &SystemDef,
    errors: &mut Errors,
) {
    let mut first: HashMap<u32, (bool, Span)> = HashMap::new();
    for (mi, m) in layer.modules.iter().enumerate() {
        for (ti, t) in m.def.tasks.iter().enumerate() {
            let task = &tasks[mi][ti];
            let pinned = t.core.is_some();
            let span = t.core.as_ref().map_or(t.name.span, |c| c.span);
            let (first_pinned, first_span) = *first.entry(task.cpu).or_insert((pinned, span));
            if pinned != first_pinned {
                let cpu = def
                    .cpus
                    .get(task.cpu as usize)
                    .map_or("", |c| c.name.as_str());
                let (this, that) = if pinned {
                    ("pinned to a core", "runs on any free core")
                } else {
                    ("runs on any free core", "is pinned to a core")
                };
                errors.push(
                    ModelError::new(
                        format!(
                            "task `{}.{}` {this} of CPU `{cpu}`, where another task {that}",
                            m.name, t.name
                        ),
                        span,
                    )
                    .with_note(first_span, format!("this task {that}"))
                    .with_help("pin every task of a CPU to a core (`core: 0`), or none"),
                );
                // once per CPU
                first.insert(task.cpu, (pinned, span));
            }
        }
    }
}

/// Gives the tasks of a CPU without priorities (`given` says which have one, in
/// declaration order; a CPU's tasks have one or none, checked) rate-monotonic ones:
/// shorter periods are more urgent, ties in declaration order.
fn rate_monotonic(tasks: &mut [Vec<TimedTask>], given: &[bool]) {
    let mut cpus: Vec<u32> = tasks.iter().flatten().map(|t| t.cpu).collect();
    cpus.sort_unstable();
    cpus.dedup();
    for cpu in cpus {
        let mut on_cpu: Vec<&mut TimedTask> = tasks
            .iter_mut()
            .flatten()
            .zip(given)
            .filter(|(t, &given)| t.cpu == cpu && !given)
            .map(|(t, _)| t)
            .collect();
        // stable: equal periods keep declaration order, the first the most urgent
        on_cpu.sort_by_key(|t| t.period);
        let n = on_cpu.len() as i64;
        for (rank, t) in on_cpu.iter_mut().enumerate() {
            t.priority = n - rank as i64;
        }
    }
}
