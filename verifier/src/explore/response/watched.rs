//! What the response properties keep of the stored graph: which steps are ticks and how
//! many time units each stands for, and where each property's trigger and response
//! happen, on states and on steps, as flag bits; and the first range error met in
//! evaluating them.

use bip_model::{Happenings, Happens, Role, State, Step, System};

use crate::explore::graph::{Graph, Keep};

/// A response property's trigger and response.
pub(crate) struct Watched<'a> {
    /// What a range error in them is reported in: `property NAME`.
    pub(crate) context: String,
    pub(crate) trigger: &'a Happens,
    pub(crate) response: &'a Happens,
}

/// Flag bits: on an edge, bit 0 is a tick (on a state, bit 0 is the graph's `IN_ERROR`).
/// Property `p`'s trigger is bit `1 + 2p`, its response bit `2 + 2p`, on the steps and
/// states where they happen; bit 31, on an edge, a step of the environment.
pub(crate) const TICK: u32 = 1;
/// On an edge, the step of an `Environment` connector (above the properties' bits).
pub(crate) const ENVIRONMENT: u32 = 1 << 31;
/// The properties one graph can flag.
pub(crate) const MAX_WATCHED: usize = 15;

pub(crate) fn trigger_bit(p: usize) -> u32 {
    1 << (1 + 2 * p)
}

pub(crate) fn response_bit(p: usize) -> u32 {
    1 << (2 + 2 * p)
}

/// Where property `p`'s trigger and response happen in the initial state (state 0).
pub(crate) fn at_start(g: &Flagged, p: usize) -> Happenings {
    of_bits(g.state_flags[0], p)
}

/// Where property `p`'s trigger and response happen on edge `e`, counting the state it
/// leads to (as `System::happenings_on` does).
pub(crate) fn on_edge(g: &Flagged, p: usize, e: usize) -> Happenings {
    of_bits(g.edge_data[e] | g.state_flags[g.targets[e] as usize], p)
}

/// The time units tick `e` stands for ([`System::time_advance`]): 1 in a model without
/// `advance`.
pub(crate) fn units(g: &Flagged, e: usize) -> u32 {
    g.notes.units.get(e).copied().unwrap_or(1)
}

fn of_bits(bits: u32, p: usize) -> Happenings {
    Happenings {
        trigger: bits & trigger_bit(p) != 0,
        response: bits & response_bit(p) != 0,
    }
}

/// The first range error met in evaluating a property's trigger or response: in a state
/// (or on a step out of it), with the message.
pub(crate) struct EvalFailure {
    pub(crate) state: u32,
    pub(crate) message: String,
}

/// The graph the response properties are decided on: flag bits on its edges, and per
/// property its first range error.
pub(crate) type Flagged = Graph<u32, Notes>;

/// What the graph notes besides its flags: per property its first range error, and in a
/// model with `advance` the time units of each edge in edge order (0 but for ticks; a
/// chunk's edges and the chunks come in order), empty otherwise so that other models pay
/// nothing for it.
pub(crate) struct Notes {
    pub(crate) failures: Vec<Option<EvalFailure>>,
    pub(crate) units: Vec<u32>,
}

/// The properties watched on a graph of `system`.
pub(crate) struct Watching<'s, 'a> {
    pub(crate) system: &'s System,
    pub(crate) watched: &'s [Watched<'a>],
    /// The graph notes units: the system has an `advance` ([`System::has_advance`]) and
    /// a bounded response property, the one question that counts them, is watched.
    pub(crate) advance: bool,
}

impl Keep for Watching<'_, '_> {
    type Edge = u32;
    type Notes = Notes;

    fn notes(&self) -> Self::Notes {
        Notes {
            failures: (0..self.watched.len()).map(|_| None).collect(),
            units: Vec::new(),
        }
    }

    fn state(&self, state: &State, me: u32, notes: &mut Self::Notes) -> u32 {
        let mut flags = 0u32;
        for (p, w) in self.watched.iter().enumerate() {
            for (bit, h) in [(trigger_bit(p), w.trigger), (response_bit(p), w.response)] {
                match self.system.happens_in(h, state, &w.context) {
                    Ok(true) => flags |= bit,
                    Ok(false) => {}
                    Err(e) => fail(&mut notes.failures[p], me, e.to_string()),
                }
            }
        }
        flags
    }

    fn edge(
        &self,
        state: &State,
        step: Step<'_>,
        next: &State,
        me: u32,
        notes: &mut Self::Notes,
    ) -> u32 {
        let mut flags = match self.system.role(step.label) {
            Role::Time => TICK,
            Role::Environment => ENVIRONMENT,
            _ => 0,
        };
        if self.advance {
            // the step fired, so its advance evaluates (to at least 1)
            let units = self.system.time_advance(state, step);
            notes
                .units
                .push(units.map_or(1, |u| u32::try_from(u).unwrap_or(u32::MAX)));
        }
        for (p, w) in self.watched.iter().enumerate() {
            for (bit, h) in [(trigger_bit(p), w.trigger), (response_bit(p), w.response)] {
                match self.system.happens_on(h, state, step, next, &w.context) {
                    Ok(true) => flags |= bit,
                    Ok(false) => {}
                    Err(err) => fail(&mut notes.failures[p], me, err.to_string()),
                }
            }
        }
        flags
    }

    fn merge(&self, notes: &mut Self::Notes, later: Self::Notes) {
        for (mine, theirs) in notes.failures.iter_mut().zip(later.failures) {
            if mine.is_none() {
                *mine = theirs;
            }
        }
        notes.units.extend(later.units);
    }
}

fn fail(slot: &mut Option<EvalFailure>, state: u32, message: String) {
    if slot.is_none() {
        *slot = Some(EvalFailure { state, message });
    }
}
