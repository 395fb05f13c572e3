//! Validation and compilation of a [`SystemDef`] into a [`System`]: constants, atoms,
//! component families, `forall` connectors, priorities and properties, with every name
//! resolved and every expression type-checked. All errors are collected with positions.
//!
//! This file holds the compiler's state, the limits on a model's size and the checks on
//! names every part uses; each part of the model is compiled in a file of its own, in the
//! order of `compile_core`:
//! - `constants.rs`: the constants (and `Constants`, for the GenoM expansion);
//! - `atoms.rs`, `components.rs`: atoms, then the component families built from them;
//! - `budgets.rs`: the CPUs, durations, the atoms that stand for periodic tasks, and the
//!   priority rules per CPU (the GenoM layer's time budgets use them too);
//! - `connectors.rs`: connectors and their `forall` instances, as interactions;
//! - `choices.rs`: the limit on an interaction's steps in one state;
//! - `priority.rs`: priorities resolved to interactions, and their acyclicity;
//! - `properties.rs`: properties and the global boolean expressions;
//! - `resolve.rs`: name resolution and type checking of expressions.

mod atoms;
pub(crate) mod budgets;
mod choices;
mod components;
mod connectors;
mod constants;
mod priority;
mod properties;
mod resolve;
mod response;

use std::collections::{HashMap, HashSet};

use crate::diag::{Errors, ModelError};
use crate::expr;
use crate::source::{ConstValue, Span};
use crate::syntax::{SystemDef, Text};
use bip_model::eval;
use bip_model::{Atom, Component, Connector, Family, Interaction, System, SystemParts};

pub(crate) use constants::Constants;
pub(crate) use properties::written_text;
pub(crate) use resolve::one_of;
pub use resolve::Ty;
use resolve::{ConstInfo, Names, ResolveError};
pub(crate) use response::disjuncts;

/// The largest family a model may declare; far beyond what any exploration handles, small
/// enough that a typo (`count: "10000000000"`) is an error rather than an out-of-memory.
const MAX_COUNT: i64 = 10_000_000;

/// The most components (and the most connector instances) a model may declare in all, over
/// every family (and every `forall`): the per-family limit alone lets a few families
/// together exhaust memory.
const MAX_TOTAL: usize = 10_000_000;

/// The most state slots (a location per component, and its variables) a model may have:
/// the state's tables take about 24 bytes a slot before any state is explored.
const MAX_SLOTS: usize = 50_000_000;

/// Compiles a core model (its GenoM layer, if any, is ignored: it must have been expanded
/// first), plus `extra` global boolean expressions over it (the GenoM layer's conditions,
/// for the engine's map). On failure, returns every error found.
pub(crate) fn compile_core(
    def: &SystemDef,
    extra: &[expr::Expr],
    time_unit_us: Option<u64>,
) -> Result<(System, Vec<eval::Expr>), Vec<ModelError>> {
    let mut c = Compiler {
        time_unit_us,
        ..Compiler::default()
    };
    c.constants(def);
    c.atoms(def);
    c.components(def);
    c.connectors(def);
    for e in choices::check(def, &c.atoms, &c.components, &c.connectors, &c.interactions) {
        c.errors.push(e);
    }
    let budgets = budgets::check(def, &mut c.errors);
    let priorities = c.priorities(def);
    c.tick_us = def.tick_ms.as_ref().and_then(|t| match t.value {
        ConstValue::Int(v) if v > 0 => (v as u64).checked_mul(1000),
        _ => None,
    });
    let properties = c.properties(def);
    let extra: Vec<eval::Expr> = extra.iter().filter_map(|e| c.global_bool_tree(e)).collect();
    if !c.errors.is_empty() {
        return Err(c.errors.list);
    }
    let tick_ms = def.tick_ms.as_ref().and_then(|t| match t.value {
        ConstValue::Int(v) if v > 0 => Some(v as u64),
        _ => None,
    });
    if let Some(t) = &def.tick_ms {
        if tick_ms.is_none() {
            return Err(vec![ModelError::new(
                "`tick_ms` must be a positive integer",
                t.span,
            )]);
        }
    }
    let system = System::new(SystemParts {
        name: def.name.value.clone(),
        tick_ms,
        constants: c.const_list,
        atoms: c.atoms,
        families: c.families,
        components: c.components,
        connectors: c.connectors,
        interactions: c.interactions,
        priorities,
        properties,
        initial: c.initial,
        slot_ranges: c.slot_ranges,
        genom: None,
        budgets,
    });
    Ok((system, extra))
}

#[derive(Default)]
struct Compiler {
    errors: Errors,
    consts: HashMap<String, ConstInfo>,
    const_list: Vec<(String, i64)>,
    atoms: Vec<Atom>,
    atom_by_name: HashMap<String, u32>,
    families: Vec<Family>,
    family_by_name: HashMap<String, u32>,
    components: Vec<Component>,
    slot_ranges: Vec<(i64, i64)>,
    initial: Vec<i64>,
    connectors: Vec<Connector>,
    connector_by_name: HashMap<String, u32>,
    /// Connectors that failed to compile: a priority naming one says nothing more.
    failed_connectors: HashSet<String>,
    interactions: Vec<Interaction>,
    /// A tick (`tick_ms`) in microseconds, if the model says.
    tick_us: Option<u64>,
    /// A timed model's time unit in microseconds: a `Time` step advances time by units,
    /// not by ticks.
    time_unit_us: Option<u64>,
}

/// Turns an expression error into a model error (trees have their positions in the file).
fn expr_error(e: ResolveError) -> ModelError {
    let mut m = ModelError::new(e.message, e.span);
    m.help = e.help;
    m
}

/// Checks that a user-given name can be written in expressions.
pub(crate) fn check_name(errors: &mut Errors, name: &Text, what: &str) -> bool {
    let n = name.as_str();
    let ok = n
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && n.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !ok {
        errors.push(
            ModelError::new(format!("`{n}` is not a valid {what} name"), name.span)
                .with_help("names use letters, digits and `_`, and do not start with a digit"),
        );
        return false;
    }
    if matches!(
        n,
        "true" | "false" | "forall" | "exists" | "sum" | "count" | "in" | "self_index"
    ) {
        errors.push(ModelError::new(
            format!("`{n}` is a reserved word and cannot name a {what}"),
            name.span,
        ));
        return false;
    }
    true
}

/// Reports duplicates among `names`; returns a map from name to first position.
pub(crate) fn unique<'t>(
    errors: &mut Errors,
    names: impl Iterator<Item = &'t Text>,
    what: &str,
) -> HashMap<&'t str, usize> {
    let mut seen: HashMap<&str, (usize, Span)> = HashMap::new();
    for (i, n) in names.enumerate() {
        if let Some(&(_, first)) = seen.get(n.as_str()) {
            errors.push(
                ModelError::new(format!("duplicate {what} `{n}`"), n.span)
                    .with_label("defined again here")
                    .with_note(first, "first defined here"),
            );
        } else {
            seen.insert(n.as_str(), (i, n.span));
        }
    }
    seen.into_iter().map(|(k, (i, _))| (k, i)).collect()
}

impl Compiler {
    fn names(&self) -> Names<'_> {
        Names {
            consts: &self.consts,
            atoms: &self.atoms,
            families: &self.families,
            family_by_name: &self.family_by_name,
            components: &self.components,
        }
    }
}
