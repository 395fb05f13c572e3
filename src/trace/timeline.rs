//! A run of a GenoM layer as a timeline: one lane per activity, showing when it is
//! pending (requested, waiting for its task's period), running which codel, paused until
//! the next period, on its stop path, and the requests and ends (done, error,
//! interrupted) as marks; ticks as rules.

use bip_model::{Label, State, System, Trace};
use bip_picture::timeline::{Event, Lane, Segment, Timeline};

/// What an activity is doing in a state: its kind and label, `None` when idle.
fn status(system: &System, state: &State, component: u32) -> Option<(&'static str, String)> {
    let atom = system.atom_of(component);
    let var = |name: &str| {
        atom.vars
            .iter()
            .position(|v| v.name == name)
            .is_some_and(|k| system.value(state, component, k as u32) != 0)
    };
    let location = system.location_name(state, component);
    match location {
        "ether" if var("req") => Some(("pending", "pending".into())),
        "ether" => None,
        "stop" if var("stopping") => Some(("stopping", "stop".into())),
        s if var("paused") => Some(("paused", format!("{s} (paused)"))),
        s => Some(("running", s.to_string())),
    }
}

/// The timeline of `trace` on `system`, or why it cannot be drawn.
pub fn timeline(system: &System, trace: &Trace) -> Result<Timeline, String> {
    let Some(map) = &system.genom else {
        return Err("a timeline shows activities: the model has no GenoM layer".into());
    };
    let path = trace
        .replay(system)
        .map_err(|e| format!("the trace does not fit the model: {e}"))?;
    let mut lanes = Vec::new();
    for module in &map.modules {
        for service in &module.services {
            let Some(component) = service.component else {
                continue;
            };
            let mut lane = Lane {
                name: format!("{}.{}", module.name, service.name),
                segments: Vec::new(),
                events: Vec::new(),
            };
            let mut before = status(system, &system.initial_state(), component);
            for (k, (step, state)) in path.iter().enumerate() {
                let now = status(system, state, component);
                let Label::Interaction(i) = step.label else {
                    before = now;
                    continue;
                };
                let fail = service.codels.iter().any(|c| c.fail == i);
                let event = if Some(i) == service.request {
                    Some(("request", format!("request {}", lane.name)))
                } else if before.is_some() && now.is_none() {
                    Some(if fail {
                        ("error", "ends with an error".to_string())
                    } else if service.codels.iter().any(|c| c.run == i) {
                        ("done", "ends (ether)".to_string())
                    } else {
                        (
                            "interrupted",
                            format!("interrupted by {}", system.label_name(step.label)),
                        )
                    })
                } else {
                    None
                };
                if let Some((kind, label)) = event {
                    lane.events.push(Event {
                        at: k,
                        kind: kind.into(),
                        label,
                    });
                }
                before = now;
            }
            // segments: runs of one status, the state after step k covering [k, k + 1)
            for (k, (_, state)) in path.iter().enumerate() {
                let Some((kind, label)) = status(system, state, component) else {
                    continue;
                };
                match lane.segments.last_mut() {
                    Some(s) if s.to == k && s.kind == kind && s.label == label => s.to = k + 1,
                    _ => lane.segments.push(Segment {
                        from: k,
                        to: k + 1,
                        kind: kind.into(),
                        label,
                    }),
                }
            }
            lanes.push(lane);
        }
    }
    let ticks = path
        .iter()
        .enumerate()
        .filter(|(_, (step, _))| step.label == Label::Interaction(map.tick))
        .map(|(k, _)| k)
        .collect();
    let legend = [
        ("pending", "requested, waits for its task's period"),
        ("running", "runs the codel named"),
        ("paused", "waits for the next period"),
        ("stopping", "runs its stop path"),
        ("request", "a request"),
        ("done", "ends (ether)"),
        ("error", "ends with an error"),
        ("interrupted", "ends, interrupted"),
    ]
    .iter()
    .map(|(k, m)| (k.to_string(), m.to_string()))
    .collect();
    Ok(Timeline {
        title: format!(
            "{}: {} steps, one lane per activity",
            system.name,
            path.len()
        ),
        steps: path.len(),
        axis: "steps".into(),
        instants: false,
        lanes,
        ticks,
        legend,
    })
}
