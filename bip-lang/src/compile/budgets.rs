//! Time budgets (docs/model.md, "Time budgets") that do not need the GenoM layer: the
//! CPUs, durations, the atoms that stand for periodic tasks, and the rules on the
//! priorities of the tasks of one CPU, which the GenoM layer's tasks share.

use std::collections::HashMap;

use super::{check_name, unique, Constants};
use crate::diag::{Errors, ModelError};
use crate::source::{ConstExpr, ConstValue, Span, Text};
use crate::syntax::{AtomTaskDef, Policy, Preemption, SystemDef};
use bip_model::{Budgets, ComponentTask};

/// The model's CPUs, checked: names and no duplicate.
pub(crate) fn cpus(def: &SystemDef, errors: &mut Errors) -> Vec<String> {
    for cpu in &def.cpus {
        check_name(errors, &cpu.name, "CPU");
    }
    unique(errors, def.cpus.iter().map(|c| &c.name), "CPU");
    def.cpus.iter().map(|c| c.name.value.clone()).collect()
}

/// The number of cores of each CPU, checked (at least 1; 1 if not given), one per
/// declared CPU; `None` where a count is wrong (reported).
pub(crate) fn cpu_cores(
    def: &SystemDef,
    consts: &Constants,
    errors: &mut Errors,
) -> Vec<Option<u32>> {
    def.cpus
        .iter()
        .map(|cpu| {
            let Some(written) = &cpu.cores else {
                return Some(1);
            };
            match consts.int(written) {
                Ok(n) if n >= 1 => match u32::try_from(n) {
                    Ok(n) => Some(n),
                    Err(_) => {
                        errors.push(ModelError::new(
                            format!("CPU `{}` has {n} cores, more than bip can count", cpu.name),
                            written.span,
                        ));
                        None
                    }
                },
                Ok(n) => {
                    errors.push(
                        ModelError::new(format!("CPU `{}` has {n} cores", cpu.name), written.span)
                            .with_label("a CPU has at least one core"),
                    );
                    None
                }
                Err(e) => {
                    errors.push(e);
                    None
                }
            }
        })
        .collect()
}

/// The help of an error on what only a timed model gives a meaning to.
pub(crate) const UNTIMED_HELP: &str = "add `time: Exact` beside `name` to verify the GenoM \
    layer's codels taking time on the CPUs' cores (docs/model.md, \"Time budgets\")";

/// What only a timed GenoM layer gives a meaning to, refused in a model without one: the
/// response-time analysis of an untimed model (`bip sched`, `Schedulable`) schedules one
/// core per CPU, by fixed priorities, preemptively.
pub(crate) fn untimed_cpus(def: &SystemDef, consts: &Constants, errors: &mut Errors) {
    let help = UNTIMED_HELP;
    for cpu in &def.cpus {
        if let Some(c) = &cpu.cores {
            if consts.int(c).is_ok_and(|n| n != 1) {
                errors.push(
                    ModelError::new(
                        format!("CPU `{}` has several cores in an untimed model", cpu.name),
                        c.span,
                    )
                    .with_label(
                        "the response-time analysis of an untimed model schedules one core per CPU",
                    )
                    .with_help(help),
                );
            }
        }
        if let Some(p) = cpu
            .policy
            .as_ref()
            .filter(|p| p.value != Policy::FixedPriority)
        {
            errors.push(
                ModelError::new(
                    format!(
                        "CPU `{}` schedules by `{}` in an untimed model",
                        cpu.name,
                        p.value.word()
                    ),
                    p.span,
                )
                .with_label("the response-time analysis of an untimed model is by fixed priorities")
                .with_help(help),
            );
        }
        if let Some(p) = cpu
            .preemption
            .as_ref()
            .filter(|p| p.value != Preemption::Preemptive)
        {
            errors.push(
                ModelError::new(
                    format!(
                        "CPU `{}` has `preemption: {}` in an untimed model",
                        cpu.name,
                        p.value.word()
                    ),
                    p.span,
                )
                .with_label("the response-time analysis of an untimed model is preemptive")
                .with_help(help),
            );
        }
    }
}

/// The index of `cpu` among the model's CPUs, or an error at it.
pub(crate) fn cpu_index(def: &SystemDef, cpu: &Text, errors: &mut Errors) -> Option<u32> {
    if let Some(i) = def.cpus.iter().position(|c| c.name.value == cpu.value) {
        return Some(i as u32);
    }
    let help = if def.cpus.is_empty() {
        "the model declares no CPUs: add `cpus: [...]` beside `name`".to_string()
    } else {
        let names: Vec<&str> = def.cpus.iter().map(|c| c.name.as_str()).collect();
        format!("the model's CPUs are: {}", names.join(", "))
    };
    errors.push(ModelError::new(format!("unknown CPU `{cpu}`"), cpu.span).with_help(help));
    None
}

/// A task on a known CPU, as the priority rules see it.
#[derive(Clone, Debug)]
pub(crate) struct Placed {
    pub cpu: u32,
    /// The task in the user's names: `loc.fast`, `sensor[1]`.
    pub name: String,
    /// Where the task is declared.
    pub span: Span,
    /// Its priority and where it is written.
    pub priority: Option<(i64, Span)>,
}

/// The priorities of each CPU's tasks: given on all of them or on none, and distinct
/// (fixed-priority scheduling orders a CPU's tasks strictly; a tie would be broken
/// silently).
pub(crate) fn check_priorities(cpus: usize, placed: &[Placed], errors: &mut Errors) {
    for cpu in 0..cpus.max(1) as u32 {
        let on_cpu = || placed.iter().filter(move |t| t.cpu == cpu);
        let with = on_cpu().find(|t| t.priority.is_some());
        let without = on_cpu().find(|t| t.priority.is_none());
        if let (Some(with), Some(without)) = (with, without) {
            errors.push(
                ModelError::new(
                    "some tasks on this CPU have a priority, and this one has none",
                    without.span,
                )
                .with_note(with.span, "this one has a priority")
                .with_help(
                    "give every task of a CPU a priority, or none for rate-monotonic priorities",
                ),
            );
        }
        let mut seen: Vec<(&Placed, i64, Span)> = Vec::new();
        for task in on_cpu() {
            let Some((p, span)) = task.priority else {
                continue;
            };
            match seen.iter().find(|s| s.1 == p) {
                Some(&(first, _, first_span)) => {
                    let mut e = ModelError::new(
                        format!(
                            "`{}` and `{}` both have priority {p} on one CPU",
                            first.name, task.name
                        ),
                        span,
                    );
                    if first_span == span {
                        e = e.with_help(
                            "the components of a family share their atom's priority: give the \
                             tasks no priority (rate-monotonic), or one atom each",
                        );
                    } else {
                        e = e.with_note(first_span, "the same priority").with_help(
                            "the priorities of a CPU's tasks are distinct: they order the tasks",
                        );
                    }
                    errors.push(e);
                }
                None => seen.push((task, p, span)),
            }
        }
    }
}

/// An atom's task, checked: what each of its components gets.
#[derive(Clone, Copy, Debug)]
struct AtomTask {
    period_us: u64,
    wcet_us: u64,
    cpu: u32,
    priority: Option<(i64, Span)>,
    deadline_us: Option<u64>,
}

/// The task an atom declares, checked; `None` once an error in it is reported.
fn atom_task(
    def: &SystemDef,
    consts: &Constants,
    atom: &Text,
    task: &AtomTaskDef,
    errors: &mut Errors,
) -> Option<AtomTask> {
    let period = duration(errors, consts, &task.period, "a period");
    let wcet = duration(errors, consts, &task.wcet, "a WCET");
    let deadline = match &task.deadline {
        None => Ok(None),
        Some(d) => duration(errors, consts, d, "a deadline")
            .map(Some)
            .ok_or(()),
    };
    let cpu = match &task.cpu {
        None => Some(0),
        Some(c) => cpu_index(def, c, errors),
    };
    let priority = match task.priority.as_ref().map(|p| (consts.int(p), p.span)) {
        None => Ok(None),
        Some((Ok(v), span)) => Ok(Some((v, span))),
        Some((Err(e), _)) => {
            errors.push(e);
            Err(())
        }
    };
    let (period_us, wcet_us) = (period?, wcet?);
    if wcet_us > period_us {
        errors.push(
            ModelError::new(
                format!(
                    "atom `{atom}` may work {} per period, more than its period ({})",
                    show_us(wcet_us),
                    show_us(period_us)
                ),
                task.wcet.span,
            )
            .with_help("a task must be able to do a period's work within its period"),
        );
        return None;
    }
    Some(AtomTask {
        period_us,
        wcet_us,
        cpu: cpu?,
        priority: priority.ok()?,
        deadline_us: deadline.ok()?,
    })
}

/// The tasks of the atoms that stand for one, a task per component, each with how the
/// priority rules see it. Errors in an atom's task (bad durations, an unknown CPU, a WCET
/// above the period) are reported into `errors`, once per atom.
pub(crate) fn component_tasks(
    def: &SystemDef,
    consts: &Constants,
    errors: &mut Errors,
) -> Vec<(ComponentTask, Placed)> {
    let checked: HashMap<&str, Option<AtomTask>> = def
        .atoms
        .iter()
        .filter_map(|(name, atom)| {
            let task = atom.task.as_ref()?;
            Some((name.as_str(), atom_task(def, consts, name, task, errors)))
        })
        .collect();
    let mut tasks = Vec::new();
    let mut component = 0u32;
    for cd in &def.components {
        let count = match &cd.count {
            None => Some(1),
            Some(c) => consts.int(c).ok().and_then(|n| u32::try_from(n).ok()),
        };
        // a bad count is the compiler's to report; the components after it have no index
        let Some(count) = count else {
            break;
        };
        let first = component;
        component = component.saturating_add(count);
        let Some(Some(task)) = checked.get(cd.atom.as_str()) else {
            continue;
        };
        for k in 0..count {
            let name = match cd.count {
                None => cd.name.value.clone(),
                Some(_) => format!("{}[{k}]", cd.name),
            };
            tasks.push((
                ComponentTask {
                    component: first + k,
                    period_us: task.period_us,
                    wcet_us: task.wcet_us,
                    cpu: task.cpu,
                    priority: task.priority.map(|p| p.0),
                    deadline_us: task.deadline_us,
                },
                Placed {
                    cpu: task.cpu,
                    name,
                    span: cd.name.span,
                    priority: task.priority,
                },
            ));
        }
    }
    tasks
}

/// The budgets of a core model: its CPUs and its atoms' tasks, with every rule checked.
pub(crate) fn check(def: &SystemDef, errors: &mut Errors) -> Budgets {
    let (consts, _) = Constants::new(def); // the compiler reports its errors
    if let Some(time) = &def.time {
        errors.push(
            ModelError::new("`time: Exact` times a GenoM layer, and this model has none", time.span)
                .with_help("leave `time` out: an atom that stands for a task is analysed by `bip sched`, its codels do not take time in the model"),
        );
    }
    let cpus = cpus(def, errors);
    cpu_cores(def, &consts, errors);
    untimed_cpus(def, &consts, errors);
    let tasks = component_tasks(def, &consts, errors);
    let placed: Vec<Placed> = tasks.iter().map(|t| t.1.clone()).collect();
    check_priorities(cpus.len(), &placed, errors);
    Budgets {
        cpus,
        tasks: tasks.into_iter().map(|t| t.0).collect(),
    }
}

/// A duration in microseconds: `"2ms"`, `"1.5 ms"`, `"150us"`, `"1s"`, or a number (or
/// constant expression) of microseconds; positive.
/// The shortest duration a number without a unit may give: below it, a unit is required,
/// since `4` (microseconds) is most likely a slip for `"4ms"`.
pub(crate) const BARE_MICROSECONDS: u64 = 100;

pub(crate) fn duration(
    errors: &mut Errors,
    consts: &Constants,
    c: &ConstExpr,
    what: &str,
) -> Option<u64> {
    duration_in(errors, consts, c, what, false)
}

/// [`duration`], zero allowed (a best-case execution time).
pub(crate) fn duration_or_zero(
    errors: &mut Errors,
    consts: &Constants,
    c: &ConstExpr,
    what: &str,
) -> Option<u64> {
    duration_in(errors, consts, c, what, true)
}

fn duration_in(
    errors: &mut Errors,
    consts: &Constants,
    c: &ConstExpr,
    what: &str,
    zero_ok: bool,
) -> Option<u64> {
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
    let bare = !matches!(&c.value, ConstValue::Expr(text) if with_unit(text).is_some());
    match us {
        Ok(0) if zero_ok => return Some(0),
        Ok(0) => errors.push(
            ModelError::new(format!("{what} of zero"), c.span)
                .with_help("a duration is positive: `\"2ms\"`, `\"150us\"`, or microseconds"),
        ),
        // `wcet: 4` is 4 µs, rarely meant: no codel or period is that short, while 4 ms
        // is a common budget
        Ok(us) if bare && us < BARE_MICROSECONDS => errors.push(
            ModelError::new(
                format!("{what} of {us} µs, written without a unit"),
                c.span,
            )
            .with_label("a number without a unit is microseconds")
            .with_help(format!(
                "write the unit: `\"{us}ms\"` if milliseconds were meant, `\"{us}us\"` if microseconds"
            )),
        ),
        Ok(us) => return Some(us),
        Err(why) => errors.push(
            ModelError::new(format!("{what} must be a duration: {why}"), c.span)
                .with_help("write `\"2ms\"`, `\"150us\"`, `\"1s\"`, or a number of microseconds"),
        ),
    }
    None
}

/// `Some` if `c` is written with a unit of time: the duration in microseconds, or why not.
pub(crate) fn written_duration(c: &ConstExpr) -> Option<Result<u64, String>> {
    match &c.value {
        ConstValue::Expr(text) => with_unit(text),
        _ => None,
    }
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
