//! A run of a timed model as a schedule: time on the horizontal axis, in the model's
//! units; a lane per core, showing the task whose job holds it, and a lane per task:
//! waiting for a core, running a codel, its releases and job ends as marks, and the
//! deadline miss in red where the trace ends in one (docs/verify.md, "Timed models").
//! Global cores are counted, never named, in the model: the picture gives a job the
//! first core free when it is dispatched.

use bip_model::{Label, System, Trace, Verdict};
use bip_picture::timeline::{Event, Lane, Segment, Timeline};

use super::timed::{Stage, TimedLayer};

/// A segment being drawn: where it starts, in units, and its label.
type Open = Option<(u64, String)>;

/// The lane of core `k` of CPU `cpu`, made when first used.
fn core_lane(lanes: &mut Vec<((u32, u32), Lane)>, cpus: &[String], cpu: u32, k: u32) -> usize {
    if let Some(i) = lanes.iter().position(|(key, _)| *key == (cpu, k)) {
        return i;
    }
    let name = match cpus.get(cpu as usize) {
        Some(c) => format!("{c} core {k}"),
        None => format!("core {k}"),
    };
    lanes.push((
        (cpu, k),
        Lane {
            name,
            segments: Vec::new(),
            events: Vec::new(),
        },
    ));
    lanes.len() - 1
}

/// Closes the segment opened at `from` (if any) at `to`.
fn close(lane: &mut Lane, from: &mut Open, to: u64, kind: &str) {
    if let Some((start, label)) = from.take() {
        lane.segments.push(Segment {
            from: start as usize,
            to: to as usize,
            kind: kind.into(),
            label,
        });
    }
}

/// The schedule of `trace` on `system`, or why it cannot be drawn.
pub fn schedule(system: &System, trace: &Trace) -> Result<Timeline, String> {
    let Some(map) = &system.genom else {
        return Err("a schedule shows tasks: the model has no GenoM layer".into());
    };
    let Some(layer) = TimedLayer::of(system) else {
        return Err(
            "a schedule needs a timed model (`time: Exact`): in another one codels take no time"
                .into(),
        );
    };
    let (unit_us, tasks) = (layer.unit_us, &layer.tasks);
    let path = trace
        .replay(system)
        .map_err(|e| format!("the trace does not fit the model: {e}"))?;
    // CPUs are named only where there are several
    let cpus: Vec<String> = match &system.budgets.cpus {
        c if c.len() > 1 => c.clone(),
        _ => Vec::new(),
    };
    let mut lanes: Vec<Lane> = tasks
        .iter()
        .map(|t| Lane {
            name: t.name.clone(),
            segments: Vec::new(),
            events: Vec::new(),
        })
        .collect();
    let mut cores: Vec<((u32, u32), Lane)> = Vec::new();
    // per task: waiting since, running a codel since, holding which core since
    let mut waiting: Vec<Open> = vec![None; tasks.len()];
    let mut running: Vec<Open> = vec![None; tasks.len()];
    let mut holding: Vec<Option<(usize, Open)>> = vec![None; tasks.len()];
    let initial = system.initial_state();
    let mut before = &initial;
    let mut now = 0u64;
    for (step, after) in &path {
        let units = system
            .time_advance(before, step.as_step())
            .map_err(|e| format!("the trace does not fit the model: {e}"))?;
        let at = now + units;
        let Label::Interaction(i) = step.label else {
            before = after;
            now = at;
            continue;
        };
        for (k, t) in tasks.iter().enumerate() {
            let (was, is) = (t.stage(system, before), t.stage(system, after));
            let lane = &mut lanes[k];
            if is == Stage::Ready && was != Stage::Ready {
                if was == Stage::Idle {
                    lane.events.push(Event {
                        at: at as usize,
                        kind: "release".into(),
                        label: format!("{} released", t.name),
                    });
                }
                waiting[k] = Some((at, "waits for a core".into()));
            }
            if was == Stage::Ready && is != Stage::Ready {
                close(lane, &mut waiting[k], at, "ready");
            }
            if let Some(c) = t.codels.iter().find(|c| c.start == i) {
                running[k] = Some((at, c.name.clone()));
            }
            if t.running_codel(system, before).is_some() && t.running_codel(system, after).is_none()
            {
                close(lane, &mut running[k], at, "running");
            }
            if is == Stage::Running && was != Stage::Running {
                let busy: Vec<usize> = holding.iter().flatten().map(|(c, _)| *c).collect();
                let core = match t.core {
                    Some(c) => core_lane(&mut cores, &cpus, t.cpu, c),
                    None => (0..)
                        .map(|c| core_lane(&mut cores, &cpus, t.cpu, c))
                        .find(|c| !busy.contains(c))
                        .unwrap_or(0),
                };
                holding[k] = Some((core, Some((at, t.name.clone()))));
            }
            if was == Stage::Running && is != Stage::Running {
                if let Some((core, mut open)) = holding[k].take() {
                    close(&mut cores[core].1, &mut open, at, "job");
                }
                lane.events.push(Event {
                    at: at as usize,
                    kind: "done".into(),
                    label: format!("{}'s job ends", t.name),
                });
                if is == Stage::Ready {
                    waiting[k] = Some((at, "waits for a core".into()));
                }
            }
        }
        before = after;
        now = at;
    }
    // what is still going on at the end is drawn up to it
    for (k, lane) in lanes.iter_mut().enumerate() {
        close(lane, &mut waiting[k], now, "ready");
        close(lane, &mut running[k], now, "running");
        if let Some((core, mut open)) = holding[k].take() {
            close(&mut cores[core].1, &mut open, now, "job");
        }
    }
    if let Verdict::Violation(name) = &trace.verdict {
        if let Some((k, task)) = tasks
            .iter()
            .enumerate()
            .find(|(_, t)| name.starts_with(&format!("{} meets its", t.name)))
        {
            lanes[k].events.push(Event {
                at: now as usize,
                kind: "miss".into(),
                label: format!("{} misses its deadline", task.name),
            });
        }
    }
    cores.sort_by_key(|(key, _)| *key);
    let mut all: Vec<Lane> = cores.into_iter().map(|(_, l)| l).collect();
    all.extend(lanes);
    let tick_units = map.tick_ms.map_or(1, |ms| (ms * 1000 / unit_us).max(1));
    let legend = [
        ("job", "the task whose job holds the core"),
        ("ready", "released, waits for a core"),
        ("running", "runs the codel named"),
        ("release", "a period's work released"),
        ("done", "the job ends"),
        ("miss", "past its deadline"),
    ]
    .iter()
    .map(|(k, m)| (k.to_string(), m.to_string()))
    .collect();
    let unit = bip_sched::show_micros(unit_us);
    Ok(Timeline {
        title: format!(
            "{}: {} of {unit}, a lane per core and per task",
            system.name,
            plural(now, "unit")
        ),
        steps: now.max(1) as usize,
        axis: format!("units of {unit}"),
        instants: true,
        lanes: all,
        ticks: (1..=now)
            .filter(|t| t % tick_units == 0)
            .map(|t| t as usize)
            .collect(),
        legend,
    })
}

fn plural(n: u64, what: &str) -> String {
    if n == 1 {
        format!("1 {what}")
    } else {
        format!("{n} {what}s")
    }
}
