//! Time budgets of the GenoM layer (docs/model.md, "Time budgets"): the CPUs, each task's
//! CPU, priority and deadline, each codel's WCET, checked against the periods they must
//! fit in. The expansion does not read them (the verifier's tick semantics assumes every
//! period's work ends in its period); the scheduling analysis and the engine do.

use std::collections::HashMap;

use super::check::Layer;
use crate::compile::{check_name, unique, Constants};
use crate::diag::{Errors, ModelError};
use crate::source::{ConstExpr, ConstValue, Span};
use crate::syntax::SystemDef;

/// What the layer declares of time, by names.
#[derive(Clone, Debug, Default)]
pub(crate) struct Timing {
    pub cpus: Vec<String>,
    /// By (module, task).
    pub tasks: HashMap<(String, String), TaskBudget>,
    /// WCETs in microseconds, by (module, service, codel state).
    pub wcets: HashMap<(String, String, String), u64>,
}

#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct TaskBudget {
    /// Index into [`Timing::cpus`] (0 when the model declares none).
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
    let mut timing = Timing::default();
    for cpu in &def.cpus {
        check_name(errors, cpu, "CPU");
    }
    unique(errors, def.cpus.iter(), "CPU");
    timing.cpus = def.cpus.iter().map(|c| c.value.clone()).collect();
    // A period in microseconds, once the tick's length is known.
    let tick_us = def
        .tick_ms
        .as_ref()
        .and_then(|t| consts.int(t).ok())
        .and_then(|ms| u64::try_from(ms).ok())
        .and_then(|ms| ms.checked_mul(1000))
        .filter(|&us| us > 0);
    let needs_tick = |errors: &mut Errors, span: Span| {
        errors.push(
            ModelError::new("a time budget needs the model's `tick_ms`", span)
                .with_label("compared with a period in ticks")
                .with_help("give the length of a tick, e.g. `tick_ms: 100`, beside `name`"),
        );
    };
    // (CPU, task name's span, whether it gives a priority), for the all-or-none rule
    let mut placed: Vec<(u32, Span, bool)> = Vec::new();
    for module in &layer.modules {
        for task in &module.def.tasks {
            let mut budget = TaskBudget::default();
            let mut placed_on_known_cpu = true;
            if let Some(cpu) = &task.cpu {
                placed_on_known_cpu = false;
                match def.cpus.iter().position(|c| c.value == cpu.value) {
                    Some(i) => {
                        budget.cpu = i as u32;
                        placed_on_known_cpu = true;
                    }
                    None if def.cpus.is_empty() => errors.push(
                        ModelError::new(format!("unknown CPU `{cpu}`"), cpu.span).with_help(
                            "the model declares no CPUs: add `cpus: [...]` beside `name`",
                        ),
                    ),
                    None => errors.push(
                        ModelError::new(format!("unknown CPU `{cpu}`"), cpu.span)
                            .with_help(format!("the model's CPUs are: {}", timing.cpus.join(", "))),
                    ),
                }
            }
            if let Some(p) = &task.priority {
                match consts.int(p) {
                    Ok(v) => budget.priority = Some(v),
                    Err(e) => errors.push(e),
                }
            }
            if let Some(d) = &task.deadline {
                if tick_us.is_none() {
                    needs_tick(errors, d.span);
                }
                budget.deadline_us = duration(errors, consts, d, "a deadline");
            }
            if placed_on_known_cpu {
                placed.push((budget.cpu, task.name.span, task.priority.is_some()));
            }
            timing
                .tasks
                .insert((module.name.to_string(), task.name.value.clone()), budget);
        }
        for service in &module.services {
            for codel in &service.codels {
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
                let period_us = tick_us.and_then(|t| t.checked_mul(task.1 as u64));
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
                timing.wcets.insert(
                    (
                        module.name.to_string(),
                        service.name.to_string(),
                        codel.state.to_string(),
                    ),
                    us,
                );
            }
        }
    }
    for cpu in 0..def.cpus.len().max(1) as u32 {
        let on_cpu = || placed.iter().filter(move |t| t.0 == cpu);
        let with = on_cpu().find(|t| t.2);
        let without = on_cpu().find(|t| !t.2);
        if let (Some(with), Some(without)) = (with, without) {
            errors.push(
                ModelError::new(
                    "some tasks on this CPU have a priority, and this one has none",
                    without.1,
                )
                .with_note(with.1, "this one has a priority")
                .with_help(
                    "give every task of a CPU a priority, or none for rate-monotonic priorities",
                ),
            );
        }
    }
    timing
}

/// A duration in microseconds: `"2ms"`, `"1.5 ms"`, `"150us"`, `"1s"`, or a number (or
/// constant expression) of microseconds; positive.
fn duration(errors: &mut Errors, consts: &Constants, c: &ConstExpr, what: &str) -> Option<u64> {
    let us = match &c.value {
        ConstValue::Expr(text) => match with_unit(text) {
            Some(Ok(us)) => Ok(us),
            Some(Err(why)) => Err(why),
            None => consts
                .int(c)
                .map_err(|e| e.message)
                .and_then(|v| u64::try_from(v).map_err(|_| format!("{v} µs is negative"))),
        },
        ConstValue::Int(v) => u64::try_from(*v).map_err(|_| format!("{v} µs is negative")),
        ConstValue::Bool(_) => Err("a duration is a number, not a boolean".into()),
    };
    match us {
        Ok(0) => errors.push(
            ModelError::new(format!("{what} of zero"), c.span)
                .with_help("a duration is positive: `\"2ms\"`, `\"150us\"`, or microseconds"),
        ),
        Ok(us) => return Some(us),
        Err(why) => errors.push(
            ModelError::new(format!("{what} must be a duration: {why}"), c.span)
                .with_help("write `\"2ms\"`, `\"150us\"`, `\"1s\"`, or a number of microseconds"),
        ),
    }
    None
}

/// `Some` if `text` ends with a unit of time: the duration in microseconds, or why not.
fn with_unit(text: &str) -> Option<Result<u64, String>> {
    let text = text.trim();
    let (number, scale) = [("us", 1u64), ("µs", 1), ("ms", 1000), ("s", 1_000_000)]
        .into_iter()
        .find_map(|(unit, scale)| Some((text.strip_suffix(unit)?.trim_end(), scale)))?;
    if number.is_empty() || !number.bytes().all(|b| b.is_ascii_digit() || b == b'.') {
        return None;
    }
    let (whole, fraction) = number.split_once('.').unwrap_or((number, ""));
    let digits = fraction.len();
    let exact = || -> Option<u64> {
        let whole: u64 = if whole.is_empty() {
            0
        } else {
            whole.parse().ok()?
        };
        let fraction: u64 = if digits == 0 {
            0
        } else {
            fraction.parse().ok()?
        };
        let ten = 10u64.checked_pow(u32::try_from(digits).ok()?)?;
        let scaled = fraction.checked_mul(scale)?;
        if scaled % ten != 0 {
            return None;
        }
        whole.checked_mul(scale)?.checked_add(scaled / ten)
    };
    Some(
        exact().ok_or_else(|| {
            format!("`{text}` is not a whole number of microseconds that bip can hold")
        }),
    )
}

/// A duration for messages, in the largest unit that writes it exactly.
pub(crate) fn show_us(us: u64) -> String {
    if us.is_multiple_of(1_000_000) {
        format!("{} s", us / 1_000_000)
    } else if us.is_multiple_of(1000) {
        format!("{} ms", us / 1000)
    } else {
        format!("{us} µs")
    }
}

#[cfg(test)]
mod tests {
    use super::with_unit;

    #[test]
    fn durations_with_units() {
        assert_eq!(with_unit("2ms"), Some(Ok(2000)));
        assert_eq!(with_unit(" 1.5 ms "), Some(Ok(1500)));
        assert_eq!(with_unit("150us"), Some(Ok(150)));
        assert_eq!(with_unit("150µs"), Some(Ok(150)));
        assert_eq!(with_unit("1s"), Some(Ok(1_000_000)));
        assert_eq!(with_unit(".25s"), Some(Ok(250_000)));
        assert!(matches!(with_unit("0.5us"), Some(Err(_))));
        assert!(matches!(with_unit("99999999999999999999s"), Some(Err(_))));
        // not a duration with a unit: a constant expression
        assert_eq!(with_unit("WCET"), None);
        assert_eq!(with_unit("N * 2"), None);
        assert_eq!(with_unit("ms"), None);
    }
}
