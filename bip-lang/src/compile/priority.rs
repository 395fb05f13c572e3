//! Priorities: resolving `low`/`high` to interaction ranges, the transitive closure under
//! the conjunction of the `when` conditions, and the acyclicity check.
//!
//! A priority names a connector family (all its instances, a contiguous range of
//! interactions) or one instance (a range of one). `a < X` and `Y < c` give `a < c` whenever
//! the ranges `X` and `Y` share an interaction: every member of `a` is below that shared
//! interaction, which is below every member of `c`. Working on ranges keeps the closure the
//! size of the declared relation rather than the product of family sizes; it is exact,
//! since any chain through single interactions passes through such an overlap.

use std::collections::HashSet;
use std::ops::Range;

use crate::diag::ModelError;
use crate::source::Span;
use bip_model::eval;
use bip_model::PriorityRule;

/// A priority as declared, resolved.
pub(super) struct Declared {
    pub low: Range<u32>,
    pub high: Range<u32>,
    pub when: Option<eval::Expr>,
    /// `low < high` as written.
    pub text: String,
    pub span: Span,
}

/// The closure may not grow past this many rules (a model with that many derived
/// priorities is almost certainly generated wrongly, and checking it per state would crawl).
const MAX_RULES: usize = 100_000;

struct Rule {
    low: Range<u32>,
    high: Range<u32>,
    /// Indices of the declared priorities whose `when`s must all hold.
    when: Vec<u32>,
    /// The declared priorities this rule chains, in order.
    chain: Vec<u32>,
}

fn overlap(a: &Range<u32>, b: &Range<u32>) -> bool {
    a.start < b.end && b.start < a.end
}

/// Closes the declared priorities transitively; an error if the relation has a cycle.
/// Returns the rules and, per interaction, the rules in which it is the lower one.
pub(super) fn close(declared: &[Declared]) -> Result<Vec<PriorityRule>, ModelError> {
    let mut rules: Vec<Rule> = Vec::new();
    let mut seen: HashSet<(u32, u32, u32, u32, Vec<u32>)> = HashSet::new();
    let mut add = |rules: &mut Vec<Rule>, r: Rule| -> Result<(), ModelError> {
        if overlap(&r.low, &r.high) {
            return Err(cycle_error(declared, &r.chain));
        }
        let key = (
            r.low.start,
            r.low.end,
            r.high.start,
            r.high.end,
            r.when.clone(),
        );
        if seen.insert(key) {
            if rules.len() >= MAX_RULES {
                return Err(ModelError::new(
                    format!("the priorities close into more than {MAX_RULES} rules"),
                    declared.first().map_or(Span::NONE, |d| d.span),
                ));
            }
            rules.push(r);
        }
        Ok(())
    };
    for (k, d) in declared.iter().enumerate() {
        let when = if d.when.is_some() {
            vec![k as u32]
        } else {
            Vec::new()
        };
        add(
            &mut rules,
            Rule {
                low: d.low.clone(),
                high: d.high.clone(),
                when,
                chain: vec![k as u32],
            },
        )?;
    }
    // semi-naive closure: each rule is combined, both ways, with every rule before it
    let mut i = 0;
    while i < rules.len() {
        for j in 0..=i {
            for (a, b) in [(i, j), (j, i)] {
                if !overlap(&rules[a].high, &rules[b].low) {
                    continue;
                }
                let mut when = rules[a].when.clone();
                when.extend_from_slice(&rules[b].when);
                when.sort_unstable();
                when.dedup();
                let mut chain = rules[a].chain.clone();
                chain.extend_from_slice(&rules[b].chain);
                let r = Rule {
                    low: rules[a].low.clone(),
                    high: rules[b].high.clone(),
                    when,
                    chain,
                };
                add(&mut rules, r)?;
            }
        }
        i += 1;
    }
    let out = rules
        .iter()
        .map(|rule| PriorityRule {
            low: rule.low.clone(),
            high: rule.high.clone(),
            when: rule
                .when
                .iter()
                .filter_map(|&k| declared[k as usize].when.clone())
                .collect(),
            origin: rule
                .chain
                .iter()
                .map(|&k| declared[k as usize].text.as_str())
                .collect::<Vec<_>>()
                .join(", "),
        })
        .collect();
    Ok(out)
}

fn cycle_error(declared: &[Declared], chain: &[u32]) -> ModelError {
    // start the cycle at the priority declared first, so it reads in file order
    let start = (0..chain.len()).min_by_key(|&k| chain[k]).unwrap_or(0);
    let chain: Vec<u32> = chain[start..]
        .iter()
        .chain(&chain[..start])
        .copied()
        .collect();
    let texts: Vec<&str> = chain
        .iter()
        .map(|&k| declared[k as usize].text.as_str())
        .collect();
    let first = &declared[chain[0] as usize];
    let mut e = ModelError::new(
        format!("the priorities form a cycle: {}", texts.join(", ")),
        first.span,
    )
    .with_label("this priority is part of the cycle")
    .with_help("priorities must be acyclic: no interaction may end up below itself");
    for &k in &chain[1..] {
        let d = &declared[k as usize];
        e = e.with_note(d.span, format!("and {}", d.text));
    }
    e
}
