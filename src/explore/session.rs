//! An exploration: a path from the initial state, chosen step by step among the enabled
//! steps (or loaded from a trace), a position on it to go back and forward, and the view
//! of the state there in the user's terms. No sockets here: the API and its tests drive
//! it directly.

use bip_model::{
    Liveness, LivenessChecker, OwnedStep, Property, PropertyKind, ResponseWatch, State, Steps,
    System, Trace, Verdict,
};
use serde_json::{json, Value};

use super::timing;
use crate::trace::timed::TimedLayer;
use crate::trace::{self, view};

/// Bound on the steps of one history, so that a deep link cannot make the server work
/// without end.
pub const MAX_HISTORY: usize = 100_000;

pub struct Session {
    system: System,
    /// The steps taken, each with the state it leads to and its index among the enabled
    /// steps of the state before (what a deep link records).
    path: Vec<(OwnedStep, State)>,
    choices: Vec<usize>,
    /// How many steps of `path` lead to the current state.
    position: usize,
    /// The loaded trace's verdict, in words, while its steps are the history.
    loaded: Option<String>,
    liveness: LivenessChecker,
    /// A timed model's clock and tasks.
    timed: Option<TimedLayer>,
}

impl Session {
    pub fn new(system: System) -> Session {
        Session {
            timed: TimedLayer::of(&system),
            system,
            path: Vec::new(),
            choices: Vec::new(),
            position: 0,
            loaded: None,
            liveness: LivenessChecker::default(),
        }
    }

    pub fn state(&self) -> State {
        match self.position {
            0 => self.system.initial_state(),
            n => self.path[n - 1].1.clone(),
        }
    }

    fn enabled(&self, state: &State) -> Result<Vec<OwnedStep>, String> {
        let mut steps = Steps::new();
        self.system
            .enabled_steps(state, &mut steps)
            .map_err(|e| format!("range error in this state: {e}"))?;
        Ok(steps.iter().map(|s| s.to_owned()).collect())
    }

    /// Fires the enabled step `index` of the current state. The steps after the current
    /// state are dropped, unless `index` is the one they begin with (then it goes forward).
    pub fn fire(&mut self, index: usize) -> Result<(), String> {
        if self.choices.get(self.position) == Some(&index) {
            self.position += 1;
            return Ok(());
        }
        if self.position >= MAX_HISTORY {
            return Err(format!("a history has at most {MAX_HISTORY} steps"));
        }
        let state = self.state();
        let enabled = self.enabled(&state)?;
        let Some(step) = enabled.get(index) else {
            return Err(match enabled.len() {
                0 => format!("no step is enabled here, so not step {index}"),
                n => format!(
                    "no enabled step {index}: this state has {n} (0 to {})",
                    n - 1
                ),
            });
        };
        let mut next = state.clone();
        self.system
            .fire(&state, step.as_step(), &mut next)
            .map_err(|e| format!("range error firing it: {e}"))?;
        self.path.truncate(self.position);
        self.choices.truncate(self.position);
        self.path.push((step.clone(), next));
        self.choices.push(index);
        self.position += 1;
        self.loaded = None;
        Ok(())
    }

    /// The index of the enabled step named `name`: its label as the page shows it
    /// (`request ndd.GoTo`) or its interaction (`ndd_GoTo_request`, `comp.internal`).
    pub fn index_of(&self, name: &str) -> Result<usize, (u16, String)> {
        let state = self.state();
        let enabled = self.enabled(&state).map_err(|e| (409, e))?;
        let labels = self.labels(&enabled, &vec![&state; enabled.len()]);
        let named: Vec<usize> = (0..enabled.len())
            .filter(|&k| labels[k].0 == name || self.system.label_name(enabled[k].label) == name)
            .collect();
        match named[..] {
            [k] => Ok(k),
            [] => {
                let known = self.system.interaction_index(name).is_some()
                    || name
                        .strip_suffix(".internal")
                        .is_some_and(|c| self.system.component_index(c).is_some());
                if known {
                    Err((409, format!("`{name}` is not enabled here")))
                } else {
                    Err((
                        404,
                        format!("no enabled step is `{name}`, and no interaction is so named"),
                    ))
                }
            }
            _ => Err((
                409,
                format!(
                    "{} enabled steps are `{name}`: give its index ({})",
                    named.len(),
                    named
                        .iter()
                        .map(|k| k.to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )),
        }
    }

    pub fn back(&mut self) -> Result<(), String> {
        self.go(self.position.checked_sub(1).ok_or("at the initial state")?)
    }

    pub fn forward(&mut self) -> Result<(), String> {
        if self.position == self.path.len() {
            return Err("at the last step of the history".into());
        }
        self.go(self.position + 1)
    }

    /// Goes to the state after `position` steps of the history.
    pub fn go(&mut self, position: usize) -> Result<(), String> {
        if position > self.path.len() {
            return Err(format!(
                "no position {position}: the history has {} step{}",
                self.path.len(),
                if self.path.len() == 1 { "" } else { "s" }
            ));
        }
        self.position = position;
        Ok(())
    }

    /// Replays a deep link's history (each step's index among the enabled steps) and goes
    /// to `position` (its end by default). On an error the session is as it was.
    pub fn replay(&mut self, choices: &[usize], position: Option<usize>) -> Result<(), String> {
        if choices.len() > MAX_HISTORY {
            return Err(format!("a history has at most {MAX_HISTORY} steps"));
        }
        let mut fresh = Session::new(self.system.clone());
        for (k, &index) in choices.iter().enumerate() {
            fresh
                .fire(index)
                .map_err(|e| format!("step {} of the history: {e}", k + 1))?;
        }
        fresh.go(position.unwrap_or(choices.len()))?;
        self.path = fresh.path;
        self.choices = fresh.choices;
        self.position = fresh.position;
        self.loaded = None;
        Ok(())
    }

    /// Takes a trace's steps as the history, at its initial state.
    pub fn load(&mut self, trace: &Trace) -> Result<(), String> {
        if trace.steps.len() > MAX_HISTORY {
            return Err(format!("a history has at most {MAX_HISTORY} steps"));
        }
        let path = trace
            .replay(&self.system)
            .map_err(|e| format!("the trace does not fit the model: {e}"))?;
        let mut choices = Vec::with_capacity(path.len());
        let mut before = self.system.initial_state();
        for (k, (step, after)) in path.iter().enumerate() {
            let index = self
                .enabled(&before)?
                .iter()
                .position(|s| s == step)
                .ok_or_else(|| format!("step {} of the trace is not enabled", k + 1))?;
            choices.push(index);
            before = after.clone();
        }
        self.path = path;
        self.choices = choices;
        self.position = 0;
        self.loaded = Some(view::verdict(trace));
        Ok(())
    }

    /// The current state and everything the page shows of it, as JSON.
    pub fn view(&mut self) -> Value {
        let state = self.state();
        let liveness = self.liveness_here(&state);
        let system = &self.system;
        let (enabled, range_error) = match self.enabled(&state) {
            Ok(e) => (e, None),
            Err(e) => (Vec::new(), Some(e)),
        };
        let labels = self.labels(&enabled, &vec![&state; enabled.len()]);
        let enabled_json: Vec<Value> = enabled
            .iter()
            .zip(&labels)
            .enumerate()
            .map(|(index, (step, (label, advance)))| {
                let mut out = json!({
                    "index": index,
                    "label": label,
                    "interaction": system.label_name(step.label),
                    "time": system.role(step.label) == bip_model::Role::Time,
                });
                if let Some(advance) = advance {
                    out["advance"] = advance.clone();
                }
                out
            })
            .collect();
        let properties = self.properties(&state, liveness);
        // no progress, where deadlock freedom allows it: an end, not a deadlock
        let terminal = properties.iter().any(|p| p["status"] == "terminal");
        let initial = system.initial_state();
        let history_steps: Vec<OwnedStep> = self.path.iter().map(|(s, _)| s.clone()).collect();
        let befores: Vec<&State> = std::iter::once(&initial)
            .chain(self.path.iter().map(|(_, after)| after))
            .collect();
        let history_labels: Vec<String> = self
            .labels(&history_steps, &befores)
            .into_iter()
            .map(|(label, _)| label)
            .collect();
        let timing = self.timed.as_ref().map(|layer| {
            let along = &history_steps[..self.position];
            let since_start = timing::elapsed(system, along, &befores);
            timing::state(layer, system, &state, since_start)
        });
        let groups: Vec<Value> = view::user_state(system, &state, false)
            .into_iter()
            .filter(|g| !g.entries.is_empty())
            // a timed model's task atoms are shown by `timing`, in the user's terms
            .filter(|g| {
                !self
                    .timed
                    .as_ref()
                    .is_some_and(|l| l.has_task_named(&g.name))
            })
            .map(|g| {
                json!({
                    "name": g.name,
                    "entries": g.entries.iter().map(|(n, v)| json!([n, v])).collect::<Vec<_>>(),
                })
            })
            .collect();
        json!({
            "system": system.name,
            "position": self.position,
            "history": self.choices,
            "steps": history_labels,
            "loaded": self.loaded,
            "state": groups,
            "timing": timing,
            "enabled": enabled_json,
            "range_error": range_error,
            "liveness": if terminal { "terminal" } else { liveness_name(liveness) },
            "held": self.held(&state),
            "properties": properties,
            "chart": self.chart(liveness, &properties),
        })
    }

    /// The labels of `steps`, each leaving the state of `befores` at its index, as a trace
    /// names them, with a timed model's time step's advance (as JSON).
    fn labels(&self, steps: &[OwnedStep], befores: &[&State]) -> Vec<(String, Option<Value>)> {
        let labels = view::step_labels(&self.system, steps, befores);
        labels
            .into_iter()
            .zip(steps)
            .zip(befores)
            .map(|((label, step), before)| {
                let advance = self
                    .timed
                    .as_ref()
                    .and_then(|layer| timing::advance(layer, &self.system, before, step));
                (label, advance)
            })
            .collect()
    }

    fn liveness_here(&mut self, state: &State) -> Option<Liveness> {
        let mut steps = Steps::new();
        self.system.enabled_steps(state, &mut steps).ok()?;
        self.system.liveness(state, &steps, &mut self.liveness).ok()
    }

    /// The codels ready here (or once time passes) that a constraint or an `after` holds
    /// back, and by what: the explanation `bip verify` gives under a deadlock.
    fn held(&self, state: &State) -> Vec<Value> {
        let Some(genom) = &self.system.genom else {
            return Vec::new();
        };
        match genom.stuck(&self.system, state) {
            Ok(stuck) => stuck
                .iter()
                .map(|st| {
                    json!({
                        "codel": format!("{st} but held by"),
                        "module": st.module,
                        "held_by": st.held_by.iter().map(|c| c.to_string()).collect::<Vec<_>>(),
                    })
                })
                .collect(),
            Err(e) => vec![json!({"codel": format!("cannot tell ({e})"), "held_by": []})],
        }
    }

    /// Each property in this state: an invariant true or false, a reachability target
    /// reached or not, deadlock freedom as this state's liveness says.
    fn properties(&self, state: &State, liveness: Option<Liveness>) -> Vec<Value> {
        let system = &self.system;
        system
            .properties
            .iter()
            .map(|p| {
                let (kind, status) = match &p.kind {
                    PropertyKind::Invariant(e) => (
                        "invariant",
                        match system.holds(e, state, &p.name) {
                            Ok(true) => "holds".to_string(),
                            Ok(false) => "fails".to_string(),
                            Err(e) => format!("range error: {e}"),
                        },
                    ),
                    PropertyKind::Reachable(e) => (
                        "reachable",
                        match system.holds(e, state, &p.name) {
                            Ok(true) => "reached".to_string(),
                            Ok(false) => "not here".to_string(),
                            Err(e) => format!("range error: {e}"),
                        },
                    ),
                    PropertyKind::DeadlockFree { terminal } => {
                        let terminal_here = terminal
                            .as_ref()
                            .is_some_and(|t| system.holds(t, state, &p.name) == Ok(true));
                        let status = match liveness {
                            Some(Liveness::Deadlock) if terminal_here => "terminal",
                            Some(Liveness::Deadlock) => "fails",
                            Some(Liveness::Unknown) | None => "cannot tell",
                            Some(_) => "holds",
                        };
                        ("deadlock freedom", status.to_string())
                    }
                    PropertyKind::Response { within, .. } => (
                        if within.is_some() {
                            "bounded response"
                        } else {
                            "response"
                        },
                        self.response_status(p),
                    ),
                };
                json!({"name": p.name, "kind": kind, "text": p.text, "status": status})
            })
            .collect()
    }

    /// A response property along the history up to here (a property of runs: whether
    /// this state has a trigger waiting, not whether the property holds).
    fn response_status(&self, p: &Property) -> String {
        let Some(spec) = p.kind.response_spec() else {
            return "cannot tell".into();
        };
        let system = &self.system;
        let init = system.initial_state();
        let watched = (|| -> Result<Result<Option<u64>, usize>, bip_model::RangeError> {
            let mut watch = ResponseWatch::start(system, spec, &init, &p.name)?;
            let mut before = &init;
            for (k, (step, after)) in self.path[..self.position].iter().enumerate() {
                if watch.observe(system, spec, before, step.as_step(), after, &p.name)? {
                    return Ok(Err(k + 1));
                }
                before = after;
            }
            Ok(Ok(watch.waiting))
        })();
        match watched {
            Ok(Ok(None)) => "nothing waits".into(),
            Ok(Ok(Some(ticks))) => format!(
                "a trigger waits ({ticks} tick{} so far)",
                if ticks == 1 { "" } else { "s" }
            ),
            Ok(Err(k)) => format!("fails at step {k}: the bound passed"),
            Err(e) => format!("range error: {e}"),
        }
    }

    /// The history so far as a sequence chart, its end marked as a trace's would be: the
    /// deadlock and why, the failed invariant, the reached target.
    fn chart(&self, liveness: Option<Liveness>, properties: &[Value]) -> Value {
        let first = |kind: &str, status: &str| {
            properties
                .iter()
                .find(|p| p["kind"] == kind && p["status"] == status)
                .and_then(|p| p["name"].as_str())
                .map(str::to_string)
        };
        let verdict = if liveness == Some(Liveness::Deadlock)
            && properties
                .iter()
                .any(|p| p["kind"] == "deadlock freedom" && p["status"] == "fails")
        {
            Verdict::Deadlock
        } else if let Some(name) = first("invariant", "fails") {
            Verdict::Violation(name)
        } else if let Some(name) = first("reachable", "reached") {
            Verdict::Witness(name)
        } else {
            Verdict::None
        };
        let trace = Trace::from_path(&self.system, verdict, &self.path[..self.position]);
        match trace::chart_svg(&self.system, &trace) {
            Ok(svg) => json!({ "svg": svg }),
            Err(e) => json!({ "error": format!("cannot draw the chart: {e}") }),
        }
    }
}

fn liveness_name(l: Option<Liveness>) -> &'static str {
    match l {
        Some(Liveness::Progress) => "progress",
        Some(Liveness::AfterTime { .. }) => "progress after time passes",
        Some(Liveness::Deadlock) => "deadlock",
        Some(Liveness::Unknown) | None => "cannot tell",
    }
}
