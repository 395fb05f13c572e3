//! A GenoM map's conditions evaluated in a state: why a request is refused, why a codel
//! is held.

#[allow(unused_imports)]
use crate::prelude::*;

use super::map::{CodelMap, Condition, ServiceMap};
use crate::model::RangeError;
use crate::state::State;
use crate::system::System;

impl Condition {
    pub fn holds(&self, system: &System, state: &State) -> Result<bool, RangeError> {
        system.holds(&self.expr, state, &self.text)
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
    for c in conds {
        if !c.holds(system, state)? {
            out.push(c);
        }
    }
    Ok(out)
}
