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
use crate::steps::{OwnedStep, Steps};
use crate::system::System;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Trace", deny_unknown_fields)]
pub struct Trace {
    pub system: String,
    pub verdict: Verdict,
    pub steps: Vec<TraceStep>,
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
    /// A plain recording (simulation, engine run).
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
    /// A trace from the initial state along `path` (each step with the state it leads to).
    pub fn from_path(system: &System, verdict: Verdict, path: &[(OwnedStep, State)]) -> Trace {
        let mut prev = system.initial_state();
        let mut steps = Vec::with_capacity(path.len());
        for (step, state) in path {
            steps.push(TraceStep {
                step: system.label_name(step.label),
                state: system.diff(&prev, state),
            });
            prev = state.clone();
        }
        Trace {
            system: system.name.clone(),
            verdict,
            steps,
        }
    }

    /// Re-executes the trace with the step relation: each step must be enabled and lead to
    /// the recorded changes. Returns the steps and states it passes through.
    pub fn replay(&self, system: &System) -> Result<Vec<(OwnedStep, State)>, ReplayError> {
        match self.replay_prefix(system) {
            (path, None) => Ok(path),
            (_, Some(e)) => Err(e),
        }
    }

    /// Like [`Trace::replay`], but keeps the steps that replay before the first that does
    /// not: the path so far, and the error, if any.
    pub fn replay_prefix(&self, system: &System) -> (Vec<(OwnedStep, State)>, Option<ReplayError>) {
        let mut out = Vec::with_capacity(self.steps.len());
        let err = self.replay_into(system, &mut out).err();
        (out, err)
    }

    fn replay_into(
        &self,
        system: &System,
        out: &mut Vec<(OwnedStep, State)>,
    ) -> Result<(), ReplayError> {
        let slots = system.slot_by_name();
        let mut state = system.initial_state();
        let mut steps = Steps::new();
        for (k, ts) in self.steps.iter().enumerate() {
            let n = k + 1;
            let fail = |message: String| ReplayError { step: n, message };
            let mut recorded: Vec<(u32, &TraceValue)> = Vec::with_capacity(ts.state.len());
            for (name, value) in ts.state.iter() {
                let slot = *slots
                    .get(name)
                    .ok_or_else(|| fail(format!("`{name}` is not a component or variable")))?;
                recorded.push((slot, value));
            }
            system
                .enabled_steps(&state, &mut steps)
                .map_err(|e: RangeError| fail(format!("range error before the step: {e}")))?;
            let mut found = None;
            let mut same_name = 0;
            let mut next = state.clone();
            for s in steps.iter() {
                if system.label_name(s.label) != ts.step {
                    continue;
                }
                same_name += 1;
                if system.fire(&state, s, &mut next).is_err() {
                    continue;
                }
                if matches_record(system, &state, &next, &recorded) {
                    found = Some(s.to_owned());
                    break;
                }
            }
            let Some(step) = found else {
                return Err(fail(if same_name == 0 {
                    format!("`{}` is not enabled here", ts.step)
                } else {
                    format!(
                        "`{}` is enabled but does not lead to the recorded state",
                        ts.step
                    )
                }));
            };
            state = next;
            out.push((step, state.clone()));
        }
        Ok(())
    }

    /// A readable rendering; with the system, changes show as `old → new`.
    pub fn display<'a>(&'a self, system: Option<&'a System>) -> TraceDisplay<'a> {
        TraceDisplay {
            trace: self,
            system,
        }
    }
}

/// True if `after` differs from `before` exactly where the record says, with its values.
fn matches_record(
    system: &System,
    before: &State,
    after: &State,
    recorded: &[(u32, &TraceValue)],
) -> bool {
    for &(slot, v) in recorded {
        if system.trace_value(after, slot) != *v {
            return false;
        }
    }
    before
        .slots()
        .iter()
        .zip(after.slots())
        .enumerate()
        .all(|(slot, (a, b))| a == b || recorded.iter().any(|&(s, _)| s == slot as u32))
}

pub struct TraceDisplay<'a> {
    trace: &'a Trace,
    system: Option<&'a System>,
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
        writeln!(f, "{what} after {n} step{}", if n == 1 { "" } else { "s" })?;
        let mut current: HashMap<String, TraceValue> = HashMap::new();
        if let Some(sys) = self.system {
            let init = sys.initial_state();
            for slot in 0..sys.slot_count() as u32 {
                current.insert(sys.slot_name(slot), sys.trace_value(&init, slot));
            }
        }
        let width = t
            .steps
            .iter()
            .map(|s| s.step.len())
            .max()
            .unwrap_or(0)
            .min(32);
        let num_width = n.to_string().len();
        for (k, s) in t.steps.iter().enumerate() {
            write!(f, "  {:>num_width$}  {:<width$}", k + 1, s.step)?;
            for (i, (name, v)) in s.state.iter().enumerate() {
                let sep = if i == 0 { "  " } else { ", " };
                match current.insert(name.clone(), v.clone()) {
                    Some(old) => write!(f, "{sep}{name}: {old} → {v}")?,
                    None => write!(f, "{sep}{name} = {v}")?,
                }
            }
            writeln!(f)?;
        }
        Ok(())
    }
}
