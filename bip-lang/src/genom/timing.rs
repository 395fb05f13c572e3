//! Time budgets of the GenoM layer (docs/model.md, "Time budgets"): the CPUs, each task's
//! CPU, priority and deadline, each codel's WCET, checked against the periods they must
//! fit in; the priorities of each CPU's tasks checked together with those of the atoms
//! that stand for tasks. The expansion does not read them (the verifier's tick semantics
//! assumes every period's work ends in its period); the scheduling analysis and the
//! engine do.

use std::collections::HashMap;

use super::check::{Codel, Layer};
use crate::compile::budgets::{
    self, check_priorities, cpu_index, duration, duration_or_zero, show_us, Placed,
};
use crate::compile::Constants;
use crate::diag::{Errors, ModelError};
use crate::source::Span;
use crate::syntax::SystemDef;

/// What the layer declares of time, by names.
#[derive(Clone, Debug, Default)]
pub(crate) struct Timing {
    /// By (module, task).
    pub tasks: HashMap<(String, String), TaskBudget>,
    /// WCETs in microseconds, by (module, service, codel state).
    pub wcets: HashMap<(String, String, String), u64>,
    /// Declared BCETs in microseconds (each at most its codel's WCET), by (module,
    /// service, codel state).
    pub bcets: HashMap<(String, String, String), u64>,
    /// The number of cores of each declared CPU (`None` where the count is wrong).
    pub cores: Vec<Option<u32>>,
    /// A tick in microseconds, if known.
    pub tick_us: Option<u64>,
}

#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct TaskBudget {
    /// Index into the model's CPUs (0 when it declares none).
    pub cpu: u32,
    pub priority: Option<i64>,
    pub deadline_us: Option<u64>,
}

/// Checks the time budgets of `layer`, reporting what is wrong into `errors`.
pub(super) fn check(
    def: &SystemDef,
    layer: &Layer<'_>,
    consts: &Constants,
    errors: &mut Errors,
) -> Timing {
    budgets::cpus(def, errors);
    let mut timing = Timing::default();
    // A period in microseconds, once the tick's length is known.
    let tick_ms = def
        .tick_ms
        .as_ref()
        .and_then(|t| consts.int(t).ok())
        .and_then(|ms| u64::try_from(ms).ok())
        .filter(|&ms| ms > 0);
    let tick_us = tick_ms.and_then(|ms| ms.checked_mul(1000));
    if let (Some(ms), None, Some(t)) = (tick_ms, tick_us, &def.tick_ms) {
        errors.push(
            ModelError::new(
                format!("`tick_ms` of {ms} ms overflows: in microseconds it exceeds 64 bits"),
                t.span,
            )
            .with_help("a tick is a few milliseconds: `tick_ms: 100` is a tenth of a second"),
        );
    }
    // a `tick_ms` given but unusable is reported where it is (above, or by the compiler
    // if it is not a positive integer), not again at every budget
    let needs_tick = |errors: &mut Errors, span: Span| {
        if def.tick_ms.is_some() {
            return;
        }
        errors.push(
            ModelError::new("a time budget needs the model's `tick_ms`", span)
                .with_label("compared with a period in ticks")
                .with_help("give the length of a tick, e.g. `tick_ms: 100`, beside `name`"),
        );
    };
    let mut placed: Vec<Placed> = Vec::new();
    for module in &layer.modules {
        for task in &module.def.tasks {
            let mut budget = TaskBudget::default();
            let cpu = match &task.cpu {
                None => Some(0),
                Some(c) => cpu_index(def, c, errors),
            };
            budget.cpu = cpu.unwrap_or(0);
            if let Some(p) = &task.priority {
                match consts.int(p) {
                    Ok(v) => budget.priority = Some(v),
                    Err(e) => errors.push(e),
                }
            }
            if let (Some(d), None) = (&task.deadline, &task.period) {
                errors.push(
                    ModelError::new(
                        format!("task `{}.{}` has a deadline but no period", module.name, task.name),
                        d.span,
                    )
                    .with_label("a deadline counts from a period's release")
                    .with_help("an aperiodic task has no release to count from: give it a `period`, or leave the deadline out"),
                );
            } else if let Some(d) = &task.deadline {
                if tick_us.is_none() {
                    needs_tick(errors, d.span);
                }
                budget.deadline_us = duration(errors, consts, d, "a deadline");
            }
            // a priority in error is reported; the rules skip its task
            let priority_known = task.priority.is_none() || budget.priority.is_some();
            if let (Some(cpu), true) = (cpu, priority_known) {
                placed.push(Placed {
                    cpu,
                    name: format!("{}.{}", module.name, task.name),
                    span: task.name.span,
                    priority: budget.priority.zip(task.priority.as_ref().map(|p| p.span)),
                });
            }
            timing
                .tasks
                .insert((module.name.to_string(), task.name.value.clone()), budget);
        }
        for service in &module.services {
            for codel in &service.codels {
                let key = || {
                    (
                        module.name.to_string(),
                        service.name.to_string(),
                        codel.state.to_string(),
                    )
                };
                if let Some(us) = codel_bcet(errors, consts, module.name, service.name, codel) {
                    timing.bcets.insert(key(), us);
                }
                let Some(w) = &codel.def.wcet else { continue };
                let Some(task) = service.task.and_then(|t| module.tasks.get(t)) else {
                    errors.push(
                        ModelError::new(
                            format!(
                                "`{}.{}` runs in no task, so its codel `{}` has no time budget",
                                module.name, service.name, codel.state
                            ),
                            w.span,
                        )
                        .with_help("only the codels of an activity run in a task"),
                    );
                    continue;
                };
                if tick_us.is_none() {
                    needs_tick(errors, w.span);
                }
                let Some(us) = duration(errors, consts, w, "a WCET") else {
                    continue;
                };
                // an aperiodic task has no period for a codel to fit in
                let period_us = tick_us
                    .zip(task.1)
                    .and_then(|(t, p)| t.checked_mul(p as u64));
                if let Some(period_us) = period_us.filter(|&p| us > p) {
                    errors.push(
                        ModelError::new(
                            format!(
                                "codel `{}` of `{}.{}` may take {}, more than the period of its task `{}` ({})",
                                codel.state,
                                module.name,
                                service.name,
                                show_us(us),
                                task.0,
                                show_us(period_us)
                            ),
                            w.span,
                        )
                        .with_help("a codel must be able to finish within its task's period"),
                    );
                }
                timing.wcets.insert(key(), us);
            }
        }
    }
    // the atoms' tasks share the CPUs: their own errors are reported here too (the
    // expansion stops on them, before the compiler would report them again)
    placed.extend(
        budgets::component_tasks(def, consts, errors)
            .into_iter()
            .map(|t| t.1),
    );
    check_priorities(def.cpus.len(), &placed, errors);
    timing.cores = budgets::cpu_cores(def, consts, errors);
    timing.tick_us = tick_us;
    // a timed model's own checks are `timed`'s
    if def.time.is_none() {
        budgets::untimed_cpus(def, consts, errors);
        for task in layer.modules.iter().flat_map(|m| &m.def.tasks) {
            if let Some(core) = &task.core {
                errors.push(
                    ModelError::new(
                        format!(
                            "task `{}` is pinned to a core in an untimed model",
                            task.name
                        ),
                        core.span,
                    )
                    .with_label(
                        "the response-time analysis of an untimed model schedules one core per CPU",
                    )
                    .with_help(budgets::UNTIMED_HELP),
                );
            }
        }
    }
    timing
}

/// A codel's declared `bcet` in microseconds, checked against its WCET (a codel without
/// one takes no time); `None` if it declares none or it is wrong (reported).
fn codel_bcet(
    errors: &mut Errors,
    consts: &Constants,
    module: &str,
    service: &str,
    codel: &Codel<'_>,
) -> Option<u64> {
    let written = codel.def.bcet.as_ref()?;
    let bcet = duration_or_zero(errors, consts, written, "a BCET")?;
    let wcet = match &codel.def.wcet {
        // a wrong WCET is reported by itself
        Some(w) => duration(&mut Errors::default(), consts, w, "a WCET")?,
        None => 0,
    };
    if bcet > wcet {
        let at_least = format!(
            "codel `{}` of `{module}.{service}` takes at least {}",
            codel.state,
            show_us(bcet)
        );
        errors.push(match &codel.def.wcet {
            Some(w) => ModelError::new(
                format!("{at_least}, more than its WCET ({})", show_us(wcet)),
                written.span,
            )
            .with_note(w.span, "its WCET")
            .with_help("a codel's best-case execution time is at most its worst case"),
            None => ModelError::new(format!("{at_least}, and has no WCET"), written.span)
                .with_help("a codel without a `wcet` takes no time: give its `wcet`"),
        });
        return None;
    }
    Some(bcet)
}
