//! Validation of the GenoM layer: names, tasks, codel automata, `interrupts`, `after` and
//! constraints, with every error at its place in the file. The result, [`Layer`], holds
//! indices instead of names, which is what the expansion works from.
//!
//! This file holds the layer's types and the order of the checks; the checks are in:
//! - `module.rs`: modules and their services;
//! - `codels.rs`: an activity's codel automaton;
//! - `connections.rs`: which out port each in port reads, and port names resolved;
//! - `constraints.rs`: the constraints between services;
//! - `types.rs`: the data types of ports, arguments and outputs.

mod codels;
mod connections;
mod constraints;
mod module;
mod types;

use std::collections::HashSet;

use crate::compile::{check_name, unique, Constants};
use crate::diag::{Errors, ModelError};
use crate::source::line_col;
use crate::syntax::{CodelDef, ConstraintDef, ModuleDef, ServiceDef, ServiceKind, SystemDef, Text};
use bip_model::genom::map::{ConstraintRef, DataType, Reason};

pub use connections::port_ref;
use constraints::constraint;
pub use constraints::{service_ref, too_old};
use module::module;

/// The name of the final state of every activity (GenoM's `ether`).
pub const ETHER: &str = "ether";
/// The name of a service's `validate` codel, as the engine binds it and properties name
/// it (`yield(m.S.validate)`).
pub const VALIDATE: &str = "validate";
/// The prefix of a yield that waits for the task's next period.
pub const PAUSE: &str = "pause::";
/// Port names of a generated activity atom that codel states may not take.
pub const ACTIVITY_PORTS: [&str; 5] = ["request", "interrupt", "abort", "tick", "wake"];
/// Port names of a generated module atom that services may not take.
pub const MODULE_PORTS: [&str; 2] = ["tick", "write"];
/// A codel that writes ids takes one step per combination of values it may write (the
/// verifier explores them all); more than this many is almost surely a modelling mistake.
pub const MAX_IDS_VALUES: u128 = 1024;

/// A service of a module: `(module, service)` indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ServiceRef {
    pub module: usize,
    pub service: usize,
}

/// A port of a module: `(module, port)` indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PortRef {
    pub module: usize,
    pub port: usize,
}

/// The validated layer.
#[derive(Debug)]
pub struct Layer<'d> {
    pub modules: Vec<Module<'d>>,
    pub constraints: Vec<Constraint<'d>>,
}

#[derive(Debug)]
pub struct Module<'d> {
    pub def: &'d ModuleDef,
    pub name: &'d str,
    /// Task names and periods (in ticks, at least 1; `None`: an aperiodic task).
    pub tasks: Vec<(&'d str, Option<i64>)>,
    /// Each task's `delay` in ticks (0 if not given), below its period.
    pub delays: Vec<i64>,
    pub ports: Vec<&'d str>,
    /// The declared type of each port's data.
    pub port_types: Vec<Option<DataType>>,
    /// The in ports, with the out port each reads once `connections` are checked.
    pub in_ports: Vec<InPort<'d>>,
    /// The ids fields and their ranges (`None` if a bound is not a constant: the core
    /// reports it).
    pub ids: Vec<(&'d str, Option<(i64, i64)>)>,
    pub services: Vec<Service<'d>>,
}

/// An in port of a module.
#[derive(Debug)]
pub struct InPort<'d> {
    pub name: &'d str,
    /// The declared type of its data.
    pub ty: Option<DataType>,
    /// The out port it reads, if a connection says which.
    pub reads: Option<PortRef>,
}

#[derive(Debug)]
pub struct Service<'d> {
    pub def: &'d ServiceDef,
    pub name: &'d str,
    pub kind: ServiceKind,
    /// The task of an activity.
    pub task: Option<usize>,
    /// Services of the same module this one interrupts (itself included, if listed).
    pub interrupts: Vec<usize>,
    pub after: Vec<usize>,
    /// The codels of an activity, in the order written.
    pub codels: Vec<Codel<'d>>,
    /// A function's or attribute's codel (at `start`, yielding `ether`), run when its
    /// request is accepted.
    pub function: Option<Codel<'d>>,
    /// The exceptions of the service's `validate` codel, if it has one.
    pub validate: Option<Vec<&'d str>>,
    /// Codel states that are locations of the activity's atom: the targets of yields,
    /// `stop` (where an interrupt leads) and the states of async codels (where the
    /// activity waits while one runs). `start` is one only if a codel yields to it or it
    /// is async.
    pub locations: Vec<usize>,
    /// The declared types of a request's arguments and of the output.
    pub args: Option<DataType>,
    pub output: Option<DataType>,
    /// Index of the `stop` codel, if declared.
    pub stop: Option<usize>,
    /// True for the activity that stands for a task's own state machine
    /// (`genom::machines`): it starts with the component and nothing requests it.
    pub machine: bool,
}

impl Service<'_> {
    /// The async codels, numbered from 1 in codel order: the values of the activity's
    /// `busy` (docs/genom.md, "Async codels").
    pub fn async_codels(&self) -> impl Iterator<Item = (i64, &Codel<'_>)> {
        self.codels
            .iter()
            .filter(|c| c.def.asynchronous)
            .zip(1..)
            .map(|(c, n)| (n, c))
    }

    /// The number of codel `c` among the async codels, if it is one.
    pub fn async_number(&self, c: usize) -> Option<i64> {
        self.async_codels()
            .find(|(_, a)| std::ptr::eq(*a, &self.codels[c]))
            .map(|(n, _)| n)
    }

    pub fn is_activity(&self) -> bool {
        self.kind == ServiceKind::Activity
    }

    pub fn interrupts_itself(&self, me: usize) -> bool {
        self.interrupts.contains(&me)
    }

    /// Index of the codel at `state`.
    pub fn codel(&self, state: &str) -> Option<usize> {
        self.codels.iter().position(|c| c.state == state)
    }

    /// True if `state` names a location of the activity's atom (`ether` included).
    pub fn is_location(&self, state: &str) -> bool {
        state == ETHER
            || self
                .locations
                .iter()
                .any(|&k| self.codels[k].state == state)
    }
}

#[derive(Debug)]
pub struct Codel<'d> {
    pub def: &'d CodelDef,
    pub state: &'d str,
    pub yields: Vec<Yield>,
    /// Written ports (indices into the module's ports).
    pub writes: Vec<usize>,
    /// Written ids fields (indices into the module's ids), in the module's order.
    pub ids: Vec<usize>,
    pub throws: Vec<&'d str>,
}

/// Where a codel may go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Yield {
    /// Run this codel next, in the same cycle.
    Go(usize),
    /// Run this codel at the task's next period.
    Pause(usize),
    /// The activity ends successfully.
    Ether,
}

#[derive(Debug)]
pub struct Constraint<'d> {
    pub kind: ConstraintKind<'d>,
    /// What the requests it refuses and the codels it holds say.
    pub reason: Reason,
}

#[derive(Debug)]
pub enum ConstraintKind<'d> {
    Exclusive(Vec<ServiceRef>),
    AtMost {
        max: i64,
        services: Vec<ServiceRef>,
    },
    Requires {
        service: ServiceRef,
        active: Vec<ServiceRef>,
    },
    Fresh {
        service: ServiceRef,
        port: PortRef,
        max_age: i64,
    },
    Guard {
        service: ServiceRef,
        when: &'d Text,
    },
}

/// Validates the modules and constraints of `def`; `text` is the file it was read from,
/// if any (reasons give the constraints' lines).
pub fn check<'d>(
    def: &'d SystemDef,
    consts: &Constants,
    text: Option<&str>,
) -> Result<Layer<'d>, Vec<ModelError>> {
    let mut errors = Errors::default();
    unique(&mut errors, def.modules.iter().map(|m| &m.name), "module");
    let mut seen = HashSet::new();
    let mut modules = Vec::new();
    for m in &def.modules {
        if !check_name(&mut errors, &m.name, "module") || !seen.insert(m.name.as_str()) {
            continue;
        }
        modules.push(module(&mut errors, consts, m));
    }
    let mut layer = Layer {
        modules,
        constraints: Vec::new(),
    };
    connections::connect(&mut errors, &mut layer, &def.connections);
    unique(
        &mut errors,
        def.constraints.iter().filter_map(ConstraintDef::name),
        "constraint name",
    );
    for (index, c) in def.constraints.iter().enumerate() {
        if let Some(k) = constraint(&mut errors, consts, &layer, c) {
            let reason = Reason::Constraint(ConstraintRef {
                index,
                kind: c.kind().to_string(),
                name: c.name().map(|n| n.value.clone()),
                written: c.written(),
                line: text
                    .filter(|_| !c.span().is_none())
                    .and_then(|t| u32::try_from(line_col(t, c.span().start).0).ok()),
            });
            layer.constraints.push(Constraint { kind: k, reason });
        }
    }
    if errors.is_empty() {
        Ok(layer)
    } else {
        Err(errors.list)
    }
}
