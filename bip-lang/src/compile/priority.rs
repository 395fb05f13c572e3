//! Priorities: resolving `low`/`high` to interaction ranges, and the acyclicity check.
//!
//! The transitive closure of docs/model.md ("Priorities") is not listed: it is reachability
//! in bip-model's [`PriorityGraph`], whose size is that of the declared relation. The
//! relation is acyclic when the graph has an order; if not, the graph names a cycle of
//! declared priorities, each one's high side meeting the next one's low side.

use crate::diag::ModelError;
use crate::source::Span;
use bip_model::{Priority, PriorityGraph, MAX_INCIDENCES};

/// A priority as declared, resolved, with where it is written.
pub(super) struct Declared {
    pub priority: Priority,
    pub span: Span,
}

/// The declared priorities, checked: an error if they form a cycle, or if their graph
/// would be too large to build.
pub(super) fn check(declared: Vec<Declared>) -> Result<Vec<Priority>, ModelError> {
    let (priorities, spans): (Vec<Priority>, Vec<Span>) =
        declared.into_iter().map(|d| (d.priority, d.span)).unzip();
    let incidences = PriorityGraph::incidences(&priorities);
    if incidences > MAX_INCIDENCES {
        return Err(ModelError::new(
            format!(
                "the priorities meet groups of interactions {incidences} times, more than \
                 {MAX_INCIDENCES}"
            ),
            spans.first().copied().unwrap_or(Span::NONE),
        )
        .with_label("the first priority")
        .with_help(
            "priorities on single instances (`c[3]`) cut a connector into groups, and a \
             priority on the whole connector meets every group: name fewer single \
             instances, or split the connector",
        ));
    }
    match PriorityGraph::new(&priorities).cycle() {
        Some(cycle) => Err(cycle_error(&priorities, &spans, cycle)),
        None => Ok(priorities),
    }
}

fn cycle_error(priorities: &[Priority], spans: &[Span], chain: &[u32]) -> ModelError {
    // start the cycle at the priority declared first, so it reads in file order
    let start = (0..chain.len()).min_by_key(|&k| chain[k]).unwrap_or(0);
    let chain: Vec<u32> = chain[start..]
        .iter()
        .chain(&chain[..start])
        .copied()
        .collect();
    let texts: Vec<&str> = chain
        .iter()
        .map(|&k| priorities[k as usize].text.as_str())
        .collect();
    let Some(&first) = chain.first() else {
        return ModelError::new("the priorities form a cycle", Span::NONE);
    };
    let mut e = ModelError::new(
        format!("the priorities form a cycle: {}", texts.join(", ")),
        spans[first as usize],
    )
    .with_label("this priority is part of the cycle")
    .with_help("priorities must be acyclic: no interaction may end up below itself");
    for &k in &chain[1..] {
        e = e.with_note(
            spans[k as usize],
            format!("and {}", priorities[k as usize].text),
        );
    }
    e
}
