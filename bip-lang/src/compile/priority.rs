//! Priorities: resolving `low`/`high` to interaction ranges, and the acyclicity check.
//!
//! The transitive closure of docs/model.md ("Priorities") is not listed: it is reachability
//! in bip-model's [`PriorityGraph`], whose size is that of the declared relation. The
//! relation is acyclic when the graph has an order; if not, the graph names a cycle of
//! declared priorities, each one's high side meeting the next one's low side.

use super::resolve::{one_of, Place, Resolver, Ty};
use super::{expr_error, Compiler};
use crate::diag::ModelError;
use crate::expr::ExprKind;
use crate::source::Span;
use crate::syntax::{ExprDef, SystemDef};
use bip_model::{Priority, PriorityGraph, MAX_INCIDENCES};

impl Compiler {
    pub(super) fn priorities(&mut self, def: &SystemDef) -> Vec<Priority> {
        let mut declared = Vec::new();
        for p in &def.priorities {
            let low = self.priority_target(&p.low);
            let high = self.priority_target(&p.high);
            let when = match &p.when {
                None => Some(None),
                Some(w) => self.global_bool(w).map(Some),
            };
            if let (Some(low), Some(high), Some(when)) = (low, high, when) {
                declared.push(Declared {
                    priority: Priority {
                        low,
                        high,
                        when,
                        text: format!("{} < {}", p.low, p.high),
                    },
                    span: p.low.span(),
                });
            }
        }
        match check(declared) {
            Ok(r) => r,
            Err(e) => {
                self.errors.push(e);
                Vec::new()
            }
        }
    }

    /// `"left"` (every instance of a connector) or `"left[3]"` (the instance for the
    /// `forall` value 3) as a range of interactions.
    fn priority_target(&mut self, t: &ExprDef) -> Option<std::ops::Range<u32>> {
        let e = match t.tree() {
            Ok(e) => e,
            Err(e) => {
                self.errors.push(e);
                return None;
            }
        };
        let (name, index) = match &e.kind {
            ExprKind::Name(n) => (n, None),
            ExprKind::Index(base, idx) => match &base.kind {
                ExprKind::Name(n) => (n, Some(idx)),
                _ => (&String::new(), None),
            },
            _ => (&String::new(), None),
        };
        let Some(&c) = self.connector_by_name.get(name.as_str()) else {
            if self.failed_connectors.contains(name.as_str()) {
                return None;
            }
            let msg = if name.is_empty() {
                "expected a connector name or `connector[index]`".to_string()
            } else {
                format!("unknown connector `{name}`")
            };
            self.errors
                .push(ModelError::new(msg, t.span()).with_help(one_of(
                    "the connectors are",
                    self.connectors.iter().map(|c| c.name.as_str()),
                )));
            return None;
        };
        let conn = &self.connectors[c as usize];
        let Some(idx) = index else {
            return Some(conn.interactions.clone());
        };
        if conn.indices.is_empty() && conn.interactions.len() == 1 {
            self.errors.push(
                ModelError::new(
                    format!("connector `{name}` has no `forall`; it has no instances"),
                    t.span(),
                )
                .with_help(format!("write `{name}`")),
            );
            return None;
        }
        let names = self.names();
        let value = match Resolver::new(&names, Place::Constant, &[]).constant(idx, Ty::Int) {
            Ok(v) => v,
            Err(e) => {
                self.errors.push(expr_error(e));
                return None;
            }
        };
        match conn.indices.iter().position(|&v| v == value) {
            Some(k) => {
                let i = conn.interactions.start + k as u32;
                Some(i..i + 1)
            }
            None => {
                self.errors.push(ModelError::new(
                    format!("connector `{name}` has no instance {value}"),
                    idx.span,
                ));
                None
            }
        }
    }
}

/// A priority as declared, resolved, with where it is written.
struct Declared {
    pub priority: Priority,
    pub span: Span,
}

/// The declared priorities, checked: an error if they form a cycle, or if their graph
/// would be too large to build.
fn check(declared: Vec<Declared>) -> Result<Vec<Priority>, ModelError> {
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
