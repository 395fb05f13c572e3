//! Why time cannot pass in a state: for each interaction of a `Time` connector, what keeps
//! it from firing there (docs/model.md, "Time progress"). The verifier says this with a
//! timelock's trace, so that "time stops after 3 steps" comes with the priority or the
//! guard to look at.

#[allow(unused_imports)]
use crate::prelude::*;

use hashbrown::HashSet;

use crate::model::{RangeError, Role};
use crate::state::State;
use crate::steps::Steps;
use crate::system::System;

/// The name of the verifier's result on time progress, and of the verdict of its traces
/// (`Violation("TimeProgress")`): no reachable state from which time can never pass.
pub const TIME_PROGRESS: &str = "TimeProgress";

/// What holds back one interaction of a `Time` connector in a state.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum TimeHeld {
    /// It is enabled but a priority suppresses it: `chain` holds the declared priorities
    /// (indices into `System::priorities`) that lead up from it to `above`, an interaction
    /// enabled in the state, each one's `when` holding.
    Priority {
        time: u32,
        chain: Vec<u32>,
        above: u32,
    },
    /// The participants it needs (every one; the trigger of a broadcast) that have no
    /// enabled transition on their port.
    NotReady { time: u32, components: Vec<u32> },
    /// Every participant it needs is ready, but its connector's guard is false.
    Guard { time: u32 },
}

impl System {
    /// Why the interactions of `Time` connectors that have no step in `state` have none,
    /// one entry per interaction (an interaction with a step is not listed).
    pub fn why_time_held(&self, state: &State) -> Result<Vec<TimeHeld>, RangeError> {
        let mut enabled = Steps::new();
        self.enabled_steps(state, &mut enabled)?;
        let mut scratch = Steps::new();
        let mut out = Vec::new();
        for i in 0..self.interactions.len() as u32 {
            let inter = &self.interactions[i as usize];
            if self.connectors[inter.connector as usize].role != Role::Time
                || enabled
                    .iter()
                    .any(|s| s.label == crate::Label::Interaction(i))
            {
                continue;
            }
            scratch.clear();
            self.push_interaction_steps(state, i, &mut scratch)?;
            if !scratch.is_empty() {
                if let Some((chain, above)) = self.suppressing_chain(state, i)? {
                    out.push(TimeHeld::Priority {
                        time: i,
                        chain,
                        above,
                    });
                }
                continue;
            }
            let mut components = Vec::new();
            for (k, p) in inter.ports.iter().enumerate() {
                let needed = inter.trigger.is_none_or(|t| t as usize == k);
                if needed && !self.participant_ready(state, i, p.component)? {
                    components.push(p.component);
                }
            }
            out.push(if components.is_empty() {
                TimeHeld::Guard { time: i }
            } else {
                TimeHeld::NotReady {
                    time: i,
                    components,
                }
            });
        }
        Ok(out)
    }

    /// A shortest chain of declared priorities whose `when`s hold in `state`, from
    /// interaction `i` up to an interaction that has a step (before priorities).
    fn suppressing_chain(
        &self,
        state: &State,
        i: u32,
    ) -> Result<Option<(Vec<u32>, u32)>, RangeError> {
        let mut scratch = Steps::new();
        let mut seen = HashSet::new();
        seen.insert(i);
        // breadth first: (interaction, the chain that reached it)
        let mut layer: Vec<(u32, Vec<u32>)> = vec![(i, Vec::new())];
        while !layer.is_empty() {
            let mut next = Vec::new();
            for (x, chain) in &layer {
                for (k, p) in self.priorities.iter().enumerate() {
                    if !p.low.contains(x) {
                        continue;
                    }
                    // a `when` that cannot be evaluated here explains nothing
                    let holds = p.when.as_ref().is_none_or(|w| {
                        self.holds(w, state, "a priority's `when`").unwrap_or(false)
                    });
                    if !holds {
                        continue;
                    }
                    for y in p.high.clone() {
                        let mut to_y = chain.clone();
                        to_y.push(k as u32);
                        scratch.clear();
                        self.push_interaction_steps(state, y, &mut scratch)?;
                        if !scratch.is_empty() {
                            return Ok(Some((to_y, y)));
                        }
                        if seen.insert(y) {
                            next.push((y, to_y));
                        }
                    }
                }
            }
            layer = next;
        }
        Ok(None)
    }

    /// `held` in the model's names: ``tick` is below `spin` (priority `tick < spin`), which
    /// can fire``.
    pub fn describe_time_held(&self, state: &State, held: &TimeHeld) -> String {
        let name = |i: u32| self.interactions[i as usize].name.as_str();
        match held {
            TimeHeld::Priority { time, chain, above } => {
                let texts: Vec<String> = chain
                    .iter()
                    .map(|&k| format!("`{}`", self.priorities[k as usize].text))
                    .collect();
                format!(
                    "`{}` is below `{}` (priorit{} {}), which can fire",
                    name(*time),
                    name(*above),
                    if texts.len() == 1 { "y" } else { "ies" },
                    texts.join(", ")
                )
            }
            TimeHeld::NotReady { time, components } => {
                let inter = &self.interactions[*time as usize];
                let parts: Vec<String> = components
                    .iter()
                    .map(|&c| {
                        let port = inter
                            .ports
                            .iter()
                            .find(|p| p.component == c)
                            .map_or("?", |p| self.atom_of(c).ports[p.port as usize].as_str());
                        format!(
                            "`{}.{port}` is not ready (at `{}`)",
                            self.components[c as usize].name,
                            self.location_name(state, c)
                        )
                    })
                    .collect();
                format!("`{}` cannot fire: {}", name(*time), parts.join(", "))
            }
            TimeHeld::Guard { time } => {
                format!("`{}` cannot fire: its guard is false", name(*time))
            }
        }
    }
}

/// States [`System::time_can_pass`] may visit.
pub const MAX_TIME_SEARCH: usize = 1_000_000;

impl System {
    /// Whether a step of a `Time` connector fires from `state` itself, as the verifier's
    /// state graph has it: a tick in range error has no successor, so it lets no time
    /// pass (the run that takes it ends in the error, which `RangeErrors` reports).
    pub fn ticks_from(&self, state: &State) -> Result<bool, RangeError> {
        let mut steps = Steps::new();
        self.enabled_steps(state, &mut steps)?;
        let mut next = state.clone();
        let ticks = steps
            .iter()
            .any(|s| self.role(s.label) == Role::Time && self.fire(state, s, &mut next).is_ok());
        Ok(ticks)
    }

    /// Whether some run from `state` fires a step of a `Time` connector: a breadth-first
    /// search through every step, of at most [`MAX_TIME_SEARCH`] states, as the verifier's
    /// state graph has them (a step in range error has no successor; a state whose steps
    /// all fail, or cannot be computed, ends its runs in a range error, which is not a
    /// timelock). `Some(false)`: `state` is a timelock; `None`: the search reached its
    /// bound.
    pub fn time_can_pass(&self, state: &State) -> Result<Option<bool>, RangeError> {
        let mut seen = HashSet::new();
        seen.insert(state.clone());
        let mut queue = alloc::collections::VecDeque::new();
        queue.push_back(state.clone());
        let mut steps = Steps::new();
        let mut next = state.clone();
        while let Some(s) = queue.pop_front() {
            if self.enabled_steps(&s, &mut steps).is_err() {
                // the run ends in a range error, which is not a timelock
                return Ok(Some(true));
            }
            let mut fired = 0;
            for step in steps.iter() {
                // a step in range error has no successor, a tick included
                if self.fire(&s, step, &mut next).is_err() {
                    continue;
                }
                if self.role(step.label) == Role::Time {
                    return Ok(Some(true));
                }
                fired += 1;
                if !seen.contains(&next) {
                    if seen.len() >= MAX_TIME_SEARCH {
                        return Ok(None);
                    }
                    seen.insert(next.clone());
                    queue.push_back(next.clone());
                }
            }
            if fired == 0 && !steps.is_empty() {
                return Ok(Some(true));
            }
        }
        Ok(Some(false))
    }
}
