//! A GenoM map's conditions evaluated in a state: why a request is refused, why a codel
//! is held.

#[allow(unused_imports)]
use crate::prelude::*;

use super::map::{CodelMap, Condition, ServiceMap};
use crate::model::RangeError;
use crate::state::State;
use crate::system::System;

impl Condition {
    /// Whether the condition holds in `state`; a range error names it as the model writes
    /// it (the constraint and its line), not as the expansion does.
    pub fn holds(&self, system: &System, state: &State) -> Result<bool, RangeError> {
        self.expr
            .holds(&mut crate::eval::Env::new(state.slots(), 0))
            .map_err(|e| system.range_error(e, &alloc::format!("condition {self}")))
    }
}

impl ServiceMap {
    /// The conditions that refuse a request in `state` (empty: the request is accepted,
    /// unless a user port of an extending connector is not ready).
    pub fn refused_by(
        &self,
        system: &System,
        state: &State,
    ) -> Result<Vec<&Condition>, RangeError> {
        failed(&self.refusals, system, state)
    }
}

impl CodelMap {
    /// The conditions that hold the codel back in `state`.
    pub fn held_by(&self, system: &System, state: &State) -> Result<Vec<&Condition>, RangeError> {
        failed(&self.holds, system, state)
    }
}

fn failed<'c>(
    conds: &'c [Condition],
    system: &System,
    state: &State,
) -> Result<Vec<&'c Condition>, RangeError> {
    let mut out = Vec::new();
    failing(conds, system, state, |k| out.push(&conds[k]))?;
    Ok(out)
}

/// Calls `found` with the index of each of `conds` that fails in `state`, evaluated as the
/// step relation evaluates the guard they make, their conjunction in this order (a
/// request's refusals, a codel's holds: bip-lang's expansion builds both from the same
/// list): left to right, where the guard stops at the first that fails. A condition
/// that cannot be evaluated is the guard's range error if none before it failed; after
/// one failed, the guard never evaluates it, so it is no error, and not listed. The
/// others after the first failure are evaluated and listed when they fail, to say all
/// that holds a request or a codel back.
pub fn failing(
    conds: &[Condition],
    system: &System,
    state: &State,
    mut found: impl FnMut(usize),
) -> Result<(), RangeError> {
    let mut any = false;
    for (k, c) in conds.iter().enumerate() {
        match c.holds(system, state) {
            Ok(true) => {}
            Ok(false) => {
                any = true;
                found(k);
            }
            Err(_) if any => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}
