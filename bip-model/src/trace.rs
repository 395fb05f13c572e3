//! The shared trace format (docs/model.md, "Traces"): counterexamples, witnesses, simulations
//! and engine recordings. Each step names the fired interaction (or `comp.internal`) and
//! the locations and variables that changed.

#[allow(unused_imports)]
use crate::prelude::*;

use core::fmt;
use hashbrown::HashMap;

use serde::{Deserialize, Serialize};

use crate::model::{RangeError, VarType};
use crate::ordered_map::OrderedMap;
use crate::state::State;
use crate::steps::{Label, OwnedStep, Steps};
use crate::system::System;

/// A trace file reads `Trace(system: "...", steps: [...], verdict: ...)`; the verdict comes
/// last so that a recording can be written as it runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Trace", deny_unknown_fields)]
pub struct Trace {
    pub system: String,
    /// The run is of the model's timed semantics (docs/model.md, "Timed semantics"), as
    /// `time: Exact` gives it, or as `bip sched --exact` and `bip simulate --codel-time` run
    /// a model that does not say so: the model is to be loaded timed to read the trace.
    /// Absent (false) for an untimed run; earlier files have none.
    #[serde(default, skip_serializing_if = "is_false")]
    pub timed: bool,
    pub steps: Vec<TraceStep>,
    pub verdict: Verdict,
    /// A lasso (a run that goes on forever): the run repeats the steps after the first
    /// `loop_start` steps, and the last step returns to the state reached after them.
    /// Absent for a finite trace; earlier files have none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loop_start: Option<usize>,
}

fn is_false(b: &bool) -> bool {
    !*b
}

/// Why a trace was recorded.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Verdict {
    /// The last state has no enabled step.
    Deadlock,
    /// The last state violates the named invariant.
    Violation(String),
    /// The last state satisfies the named `Reachable` property.
    Witness(String),
    /// The step after the last state (or its guards) leaves a variable's range; the
    /// message says where.
    RangeError(String),
    /// A plain recording (simulation, engine run). Written `Recording`; files of earlier
    /// versions say `r#None`.
    #[serde(rename = "Recording", alias = "None")]
    None,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TraceStep {
    /// The interaction's name (`left[0]`) or `comp.internal`.
    pub step: String,
    /// What changed: `"phil[0]": "hungry"` for a location, `"buf.count": 3` for a variable.
    pub state: OrderedMap<String, TraceValue>,
}

impl TraceStep {
    /// The step `label` from `before` to `after`, as a trace records it.
    pub fn between(system: &System, label: Label, before: &State, after: &State) -> TraceStep {
        TraceStep {
            step: system.label_name(label),
            state: system.diff(before, after),
        }
    }
}

#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum TraceValue {
    Bool(bool),
    Int(i64),
    /// A location name.
    Location(String),
}

impl fmt::Display for TraceValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TraceValue::Bool(b) => write!(f, "{b}"),
            TraceValue::Int(i) => write!(f, "{i}"),
            TraceValue::Location(l) => f.write_str(l),
        }
    }
}

/// A trace that does not fit its system.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReplayError {
    /// 1-based number of the step that failed (0: the trace itself is malformed).
    pub step: usize,
    pub message: String,
}

impl fmt::Display for ReplayError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "step {}: {}", self.step, self.message)
    }
}

impl core::error::Error for ReplayError {}

impl System {
    /// The value of a slot as a trace shows it.
    pub fn trace_value(&self, state: &State, slot: u32) -> TraceValue {
        let c = self.component_of_slot(slot);
        let comp = &self.components[c as usize];
        let atom = &self.atoms[comp.atom as usize];
        let v = state.slots()[slot as usize];
        if slot == comp.slot {
            TraceValue::Location(atom.locations[v as usize].clone())
        } else {
            match atom.vars[(slot - comp.slot - 1) as usize].ty {
                VarType::Bool => TraceValue::Bool(v != 0),
                VarType::Int { .. } => TraceValue::Int(v),
            }
        }
    }

    /// The slot a trace key names (`phil[0]` or `buf.count`) and how to read its value.
    fn slot_by_name(&self) -> HashMap<String, u32> {
        let mut m = HashMap::with_capacity(self.slot_count());
        for slot in 0..self.slot_count() as u32 {
            m.insert(self.slot_name(slot), slot);
        }
        m
    }

    /// The changes from `before` to `after`, as a trace records them.
    pub fn diff(&self, before: &State, after: &State) -> OrderedMap<String, TraceValue> {
        let mut out = OrderedMap::default();
        for (slot, (a, b)) in before.slots().iter().zip(after.slots()).enumerate() {
            if a != b {
                out.push(
                    self.slot_name(slot as u32),
                    self.trace_value(after, slot as u32),
                );
            }
        }
        out
    }
}

impl Trace {
    /// A finite trace of `system` made of `steps`; timed if the system is.
    pub fn new(system: &System, verdict: Verdict, steps: Vec<TraceStep>) -> Trace {
        Trace {
            system: system.name.clone(),
            timed: system.is_timed(),
            steps,
            verdict,
            loop_start: None,
        }
    }

    /// A trace from the initial state along `path` (each step with the state it leads to).
    pub fn from_path(system: &System, verdict: Verdict, path: &[(OwnedStep, State)]) -> Trace {
        Trace::from_path_at(system, &system.initial_state(), verdict, path)
    }

    /// A trace from `start` along `path` (the last steps of a longer run).
    pub fn from_path_at(
        system: &System,
        start: &State,
        verdict: Verdict,
        path: &[(OwnedStep, State)],
    ) -> Trace {
        let mut prev = start;
        let mut steps = Vec::with_capacity(path.len());
        for (step, state) in path {
            steps.push(TraceStep::between(system, step.label, prev, state));
            prev = state;
        }
        Trace::new(system, verdict, steps)
    }

    /// Re-executes the trace with the step relation: each step must be enabled and lead to
    /// the recorded changes. Returns the steps and states it passes through.
    /// A lasso's last step must return to the state where its loop starts.
    pub fn replay(&self, system: &System) -> Result<Vec<(OwnedStep, State)>, ReplayError> {
        match self.replay_prefix(system) {
            (path, None) => {
                self.check_loop(system, &path)?;
                Ok(path)
            }
            (_, Some(e)) => Err(e),
        }
    }

    /// For a lasso replayed along `path` from the initial state: an error unless the loop
    /// start is a step of the trace and its last state is the state where the loop starts.
    pub fn check_loop(
        &self,
        system: &System,
        path: &[(OwnedStep, State)],
    ) -> Result<(), ReplayError> {
        let Some(k) = self.loop_start else {
            return Ok(());
        };
        let malformed = |message: String| ReplayError { step: 0, message };
        if k >= path.len() {
            return Err(malformed(format!(
                "the loop starts after step {k}, but the trace has {} step{}",
                path.len(),
                if path.len() == 1 { "" } else { "s" }
            )));
        }
        let init = system.initial_state();
        let start = if k == 0 { &init } else { &path[k - 1].1 };
        let Some((_, last)) = path.last() else {
            return Ok(());
        };
        if last != start {
            let differences: Vec<String> = system
                .diff(start, last)
                .iter()
                .map(|(name, v)| format!("`{name}` is {v}"))
                .collect();
            return Err(ReplayError {
                step: path.len(),
                message: format!(
                    "the last step does not return to the state where the loop starts (after step {k}): {}",
                    differences.join(", ")
                ),
            });
        }
        Ok(())
    }

    /// Like [`Trace::replay`], but keeps the steps that replay before the first that does
    /// not: the path so far, and the error, if any.
    pub fn replay_prefix(&self, system: &System) -> (Vec<(OwnedStep, State)>, Option<ReplayError>) {
        self.replay_prefix_from(system, system.initial_state())
    }

    /// Like [`Trace::replay`], from `start` instead of the initial state (the last steps of
    /// a longer run, as an engine's windowed recording keeps them).
    pub fn replay_from(
        &self,
        system: &System,
        start: State,
    ) -> Result<Vec<(OwnedStep, State)>, ReplayError> {
        match self.replay_prefix_from(system, start) {
            (path, None) => Ok(path),
            (_, Some(e)) => Err(e),
        }
    }

    fn replay_prefix_from(
        &self,
        system: &System,
        start: State,
    ) -> (Vec<(OwnedStep, State)>, Option<ReplayError>) {
        let mut out = Vec::with_capacity(self.steps.len());
        let err = self.replay_into(system, start, &mut out).err();
        (out, err)
    }

    fn replay_into(
        &self,
        system: &System,
        start: State,
        out: &mut Vec<(OwnedStep, State)>,
    ) -> Result<(), ReplayError> {
        if self.timed && !system.is_timed() {
            return Err(ReplayError {
                step: 0,
                message: "the trace is of the model run as a timed model (`timed: true`), \
                          and the model was loaded untimed"
                    .into(),
            });
        }
        let slots = system.slot_by_name();
        let mut state = start;
        let mut steps = Steps::new();
        for (k, ts) in self.steps.iter().enumerate() {
            let n = k + 1;
            let fail = |message: String| ReplayError { step: n, message };
            let mut recorded: Vec<(u32, &TraceValue)> = Vec::with_capacity(ts.state.len());
            for (name, value) in ts.state.iter() {
                let slot = *slots.get(name).ok_or_else(|| {
                    fail(format!(
                        "`{name}` is not a component or variable{}",
                        did_you_mean(name, slots.keys().map(String::as_str))
                    ))
                })?;
                recorded.push((slot, value));
            }
            system
                .enabled_steps(&state, &mut steps)
                .map_err(|e: RangeError| fail(format!("range error before the step: {e}")))?;
            let mut found = None;
            // the differences of the enabled step with this name that comes closest
            let mut closest: Option<Vec<String>> = None;
            let mut fire_error = None;
            let mut next = state.clone();
            for s in steps.iter() {
                if system.label_name(s.label) != ts.step {
                    continue;
                }
                if let Err(e) = system.fire(&state, s, &mut next) {
                    fire_error.get_or_insert(e);
                    continue;
                }
                let differences = record_differences(system, &state, &next, &recorded);
                if differences.is_empty() {
                    found = Some(s.to_owned());
                    break;
                }
                if closest.as_ref().is_none_or(|c| differences.len() < c.len()) {
                    closest = Some(differences);
                }
            }
            let Some(step) = found else {
                return Err(fail(match (closest, fire_error) {
                    (Some(differences), _) => format!(
                        "`{}` is enabled but does not lead to the recorded state: {}",
                        ts.step,
                        differences.join(", ")
                    ),
                    (None, Some(e)) => {
                        format!("`{}` is enabled but has a range error: {e}", ts.step)
                    }
                    (None, None) if system.has_label(&ts.step) => {
                        format!("`{}` is not enabled here", ts.step)
                    }
                    (None, None) => format!(
                        "no such interaction: `{}`{}",
                        ts.step,
                        did_you_mean(&ts.step, system.label_names().iter().map(String::as_str))
                    ),
                }));
            };
            state = next;
            out.push((step, state.clone()));
        }
        Ok(())
    }

    /// A readable rendering; with the system, changes show as `old → new`, and the GenoM
    /// expansion's bookkeeping variables are left out unless asked
    /// ([`TraceDisplay::all_variables`]).
    pub fn display<'a>(&'a self, system: Option<&'a System>) -> TraceDisplay<'a> {
        TraceDisplay {
            trace: self,
            system,
            all_variables: false,
            start: None,
            notes: None,
            header: true,
        }
    }
}

impl System {
    /// The first range error met from `state`, where the verifier looks for one (a
    /// `RangeError` verdict at the end of a trace is one of these): a property's state
    /// condition in it (an invariant, a reachability, a response property's state trigger
    /// or response), its enabled steps (a guard, a priority's `when`), firing one of them,
    /// a response property's step pattern on one, or, if it is a deadlock, the terminal
    /// condition of `DeadlockFree`.
    pub fn range_error_from(&self, state: &State) -> Option<RangeError> {
        self.range_error_in(state).err()
    }

    fn range_error_in(&self, state: &State) -> Result<(), RangeError> {
        use crate::model::PropertyKind;
        for p in &self.properties {
            let context = format!("property {}", p.name);
            match &p.kind {
                PropertyKind::Invariant(e) | PropertyKind::Reachable(e) => {
                    self.holds(e, state, &context)?;
                }
                PropertyKind::Response {
                    trigger, response, ..
                } => {
                    self.happens_in(trigger, state, &context)?;
                    self.happens_in(response, state, &context)?;
                }
                PropertyKind::DeadlockFree { .. } => {}
            }
        }
        let mut steps = Steps::new();
        self.enabled_steps(state, &mut steps)?;
        let mut next = state.clone();
        for step in steps.iter() {
            self.fire(state, step, &mut next)?;
            for p in &self.properties {
                if let Some(spec) = p.kind.response_spec() {
                    let context = format!("property {}", p.name);
                    self.happens_on(spec.trigger, state, step, &next, &context)?;
                    self.happens_on(spec.response, state, step, &next, &context)?;
                }
            }
        }
        let terminal = self.properties.iter().find_map(|p| match &p.kind {
            PropertyKind::DeadlockFree { terminal } => terminal.as_ref(),
            _ => None,
        });
        if let Some(terminal) = terminal {
            let mut checker = crate::deadlock::LivenessChecker::default();
            // a liveness that cannot be told is no range error of this state: the
            // verifier counts it as unknown
            if let Ok(crate::deadlock::Liveness::Deadlock) =
                self.liveness(state, &steps, &mut checker)
            {
                self.holds(terminal, state, "terminal condition of DeadlockFree")?;
            }
        }
        Ok(())
    }
}

impl System {
    /// True for a variable the GenoM expansion keeps for its own bookkeeping, which a
    /// trace shows only on request: an activity's `req` (a request is pending) and
    /// `paused` (it waits for its task's next period), as bip-lang's `genom::names` calls
    /// them.
    pub fn is_bookkeeping(&self, slot: u32) -> bool {
        let Some(map) = &self.genom else {
            return false;
        };
        let c = self.component_of_slot(slot);
        let comp = &self.components[c as usize];
        if slot == comp.slot {
            return false;
        }
        let is_activity = map
            .modules
            .iter()
            .flat_map(|m| &m.services)
            .any(|s| s.component == Some(c));
        let var = &self.atom_of(c).vars[(slot - comp.slot - 1) as usize].name;
        is_activity && (var == "req" || var == "paused")
    }
}

/// Where `after` differs from what the record says (a recorded value, or no change where
/// the record has none), each as "`name`: recorded X, the step gives Y"; empty if it fits.
fn record_differences(
    system: &System,
    before: &State,
    after: &State,
    recorded: &[(u32, &TraceValue)],
) -> Vec<String> {
    let mut out = Vec::new();
    for &(slot, v) in recorded {
        let actual = system.trace_value(after, slot);
        if actual != *v {
            out.push(format!(
                "`{}` recorded {v}, the step gives {actual}",
                system.slot_name(slot)
            ));
        }
    }
    for (slot, (a, b)) in before.slots().iter().zip(after.slots()).enumerate() {
        let slot = slot as u32;
        if a != b && !recorded.iter().any(|&(s, _)| s == slot) {
            out.push(format!(
                "`{}` recorded unchanged ({}), the step gives {}",
                system.slot_name(slot),
                system.trace_value(before, slot),
                system.trace_value(after, slot)
            ));
        }
    }
    out
}

impl System {
    /// Every step name a trace may use: the interactions, and `comp.internal` for each
    /// component with internal transitions.
    fn label_names(&self) -> Vec<String> {
        let mut names: Vec<String> = self.interactions.iter().map(|i| i.name.clone()).collect();
        for (c, comp) in self.components.iter().enumerate() {
            let atom = self.atom_of(c as u32);
            if atom.transitions.iter().any(|t| t.port.is_none()) {
                names.push(format!("{}.internal", comp.name));
            }
        }
        names
    }

    fn has_label(&self, name: &str) -> bool {
        self.interaction_index(name).is_some() || self.label_names().iter().any(|n| n == name)
    }
}

/// ", did you mean `x`?" for the name closest to `name` (by edit distance, within a third
/// of its length), or nothing.
fn did_you_mean<'a>(name: &str, candidates: impl Iterator<Item = &'a str>) -> String {
    let limit = (name.chars().count() / 3).max(1);
    let best = candidates
        .map(|c| (edit_distance(name, c), c))
        .filter(|&(d, _)| d <= limit)
        .min();
    match best {
        Some((_, c)) => format!(" (did you mean `{c}`?)"),
        None => String::new(),
    }
}

/// Levenshtein distance, over characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let above = row[j + 1];
            row[j + 1] = if ca == *cb {
                diagonal
            } else {
                1 + diagonal.min(above).min(row[j])
            };
            diagonal = above;
        }
    }
    row[b.len()]
}

pub struct TraceDisplay<'a> {
    trace: &'a Trace,
    system: Option<&'a System>,
    all_variables: bool,
    /// For the last steps of a longer run: the state before the first, and the steps
    /// before it.
    start: Option<(&'a State, u64)>,
    /// A note per step, shown between its name and its changes (replay: what the engine
    /// did with it); only the steps with a note are shown.
    notes: Option<&'a [String]>,
    header: bool,
}

impl<'a> TraceDisplay<'a> {
    /// Shows the GenoM expansion's bookkeeping variables too (`-v`).
    pub fn all_variables(mut self, all: bool) -> Self {
        self.all_variables = all;
        self
    }

    /// The trace is the last steps of a run: `skipped` steps came before, ending in `start`.
    pub fn from(mut self, start: &'a State, skipped: u64) -> Self {
        self.start = Some((start, skipped));
        self
    }

    /// Shows `notes[k]` with step `k`, and only the steps that have one.
    pub fn notes(mut self, notes: &'a [String]) -> Self {
        self.notes = Some(notes);
        self
    }

    /// Leaves out the first line (what the trace shows, after how many steps).
    pub fn without_header(mut self) -> Self {
        self.header = false;
        self
    }
}

impl fmt::Display for TraceDisplay<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let t = self.trace;
        let what = match &t.verdict {
            Verdict::Deadlock => "deadlock".to_string(),
            Verdict::Violation(p) => format!("violation of {p}"),
            Verdict::Witness(p) => format!("witness for {p}"),
            Verdict::RangeError(m) => format!("range error: {m}"),
            Verdict::None => "recording".to_string(),
        };
        let n = t.steps.len();
        let skipped = self.start.map_or(0, |(_, k)| k);
        let total = skipped + n as u64;
        if self.header {
            match t.loop_start {
                Some(k) => {
                    let cycle = n.saturating_sub(k);
                    write!(
                        f,
                        "{what}: a run that repeats steps {}-{n} forever ({k} step{} to the cycle, a cycle of {cycle})",
                        k + 1,
                        plural(k as u64)
                    )?;
                }
                None => write!(f, "{what} after {total} step{}", plural(total))?,
            }
            if skipped > 0 {
                write!(f, " (the last {n} shown)")?;
            }
            writeln!(f)?;
        }
        let mut current: HashMap<String, TraceValue> = HashMap::new();
        let mut hidden: HashMap<String, ()> = HashMap::new();
        if let Some(sys) = self.system {
            let init = sys.initial_state();
            let start = self.start.map_or(&init, |(s, _)| s);
            for slot in 0..sys.slot_count() as u32 {
                current.insert(sys.slot_name(slot), sys.trace_value(start, slot));
                if !self.all_variables && sys.is_bookkeeping(slot) {
                    hidden.insert(sys.slot_name(slot), ());
                }
            }
        }
        let width = t
            .steps
            .iter()
            .map(|s| s.step.len())
            .max()
            .unwrap_or(0)
            .min(32);
        let num_width = total.to_string().len();
        let note_width = self
            .notes
            .map_or(0, |n| {
                n.iter().map(|s| s.chars().count()).max().unwrap_or(0)
            })
            .min(40);
        let shown = self.notes.map_or(n, |notes| notes.len().min(n));
        for (k, s) in t.steps.iter().enumerate().take(shown) {
            if t.loop_start == Some(k) {
                writeln!(
                    f,
                    "  {:>num_width$}  ┌ the cycle: the steps below repeat forever",
                    ""
                )?;
            }
            write!(
                f,
                "  {:>num_width$}  {:<width$}",
                skipped + k as u64 + 1,
                s.step
            )?;
            if let Some(notes) = self.notes {
                write!(f, "  {:<note_width$}", notes[k])?;
            }
            let mut first = true;
            for (name, v) in s.state.iter() {
                let old = current.insert(name.clone(), v.clone());
                if hidden.contains_key(name) {
                    continue;
                }
                let sep = if first { "  " } else { ", " };
                first = false;
                match old {
                    Some(old) => write!(f, "{sep}{name}: {old} → {v}")?,
                    None => write!(f, "{sep}{name} = {v}")?,
                }
            }
            writeln!(f)?;
        }
        if let Some(k) = t.loop_start {
            if shown == n && k < n {
                writeln!(
                    f,
                    "  {:>num_width$}  └ back to the state after step {k}, where the cycle starts",
                    ""
                )?;
            }
        }
        Ok(())
    }
}

/// "s" unless there is one.
fn plural(n: u64) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}
