//! Steps as values: what a step is ([`Label`], [`Pick`], [`Step`]) and the reusable
//! buffer the step relation collects a state's steps into ([`Steps`]), which allocates
//! nothing once it has grown to the model's needs.

#[allow(unused_imports)]
use crate::prelude::*;

/// What a step is: an internal transition of one component, or an interaction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Label {
    Internal { component: u32 },
    Interaction(u32),
}

/// One transition of one component taking part in a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Pick {
    pub component: u32,
    pub transition: u32,
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct StepEntry {
    pub(crate) label: Label,
    pub(crate) picks_start: u32,
    pub(crate) picks_end: u32,
}

/// A step: its label and the transitions of its participants, in port order (for a
/// broadcast: the trigger and the receivers that join).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Step<'a> {
    pub label: Label,
    pub picks: &'a [Pick],
}

impl Step<'_> {
    /// An owned copy, for keeping a step beyond the buffer's next use.
    pub fn to_owned(&self) -> OwnedStep {
        OwnedStep {
            label: self.label,
            picks: self.picks.to_vec(),
        }
    }
}

/// A step that owns its picks.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct OwnedStep {
    pub label: Label,
    pub picks: Vec<Pick>,
}

impl OwnedStep {
    pub fn as_step(&self) -> Step<'_> {
        Step {
            label: self.label,
            picks: &self.picks,
        }
    }
}

/// A reusable buffer of enabled steps.
#[derive(Clone, Debug, Default)]
pub struct Steps {
    pub(crate) entries: Vec<StepEntry>,
    pub(crate) picks: Vec<Pick>,
    pub(crate) choices: Choices,
    /// Scratch: which interactions are enabled before priorities, and which of those are
    /// suppressed (one bit each).
    pub(crate) enabled: Vec<u64>,
    pub(crate) suppressed: Vec<u64>,
    pub(crate) search: PrioritySearch,
}

/// Scratch for deciding the searched interactions' suppression in one state: per group of
/// the priority graph and per priority, what the search found, valid where its stamp is
/// the current epoch (so that nothing is cleared between states).
#[derive(Clone, Debug, Default)]
pub(crate) struct PrioritySearch {
    pub(crate) epoch: u32,
    /// Per group: reached from an enabled interaction.
    pub(crate) reached: Vec<u32>,
    /// Per group and kind of path (`Through` in `suppression`): whether it leads to an
    /// enabled interaction; see [`Memo`].
    pub(crate) leads: [Vec<(u32, Memo)>; 3],
    /// Per priority: its `when`, once evaluated.
    pub(crate) when: Vec<(u32, bool)>,
    pub(crate) stack: Vec<u32>,
    pub(crate) frames: Vec<(u32, u32, u32)>,
}

/// What a search knows of a group.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum Memo {
    #[default]
    Open,
    Yes,
    No,
}

/// Scratch for expanding an interaction into steps: the enabled transitions of each
/// joining port, and an odometer over their combinations.
#[derive(Clone, Debug, Default)]
pub(crate) struct Choices {
    pub(crate) choices: Vec<Pick>,
    /// Per joining port, `(start, len)` in `choices`.
    pub(crate) bounds: Vec<(u32, u32)>,
    pub(crate) cursor: Vec<u32>,
}

impl Steps {
    pub fn new() -> Steps {
        Steps::default()
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    pub fn get(&self, i: usize) -> Step<'_> {
        let e = &self.entries[i];
        Step {
            label: e.label,
            picks: &self.picks[e.picks_start as usize..e.picks_end as usize],
        }
    }

    pub fn iter(&self) -> impl ExactSizeIterator<Item = Step<'_>> + '_ {
        (0..self.entries.len()).map(move |i| self.get(i))
    }

    pub(crate) fn clear(&mut self) {
        self.entries.clear();
        self.picks.clear();
    }

    pub(crate) fn push(&mut self, label: Label, picks: impl IntoIterator<Item = Pick>) {
        let start = self.picks.len() as u32;
        self.picks.extend(picks);
        self.entries.push(StepEntry {
            label,
            picks_start: start,
            picks_end: self.picks.len() as u32,
        });
    }
}
