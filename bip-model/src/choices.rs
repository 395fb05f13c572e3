//! How many steps an interaction may have in one state: one per combination of an enabled
//! transition per joining participant (docs/model.md, "Enabled steps"), so a product over
//! its ports. The step relation, its step tables and the engine's fire plans list an
//! interaction's steps one by one; a connector whose steps could outgrow
//! [`MAX_CHOICES`] is refused when the model is loaded, so that none of them ever lists
//! more.
//!
//! A port's factor is the most transitions on it that can be enabled together: per
//! location, the transitions from it on the port, counted where their guards hold together.
//! An atom's guards read only its own variables, so for an atom with few local states
//! (location and values, at most [`MAX_LOCAL_STATES`]) every one is tried, and transitions
//! with exclusive guards (`n < MAX` and `n == MAX`) count once; for a larger one, every
//! transition from the location counts.

#[allow(unused_imports)]
use crate::prelude::*;

use crate::eval::Env;
use crate::model::{Atom, Component, Interaction};

/// The most steps one interaction may have in one state.
pub const MAX_CHOICES: u64 = 1 << 16;

/// Atoms with at most this many local states have their guards tried in each.
const MAX_LOCAL_STATES: u64 = 1 << 12;

/// Per port of `atom`, the most transitions on it from one location that can be enabled
/// together.
pub fn most_enabled(atom: &Atom) -> Vec<u32> {
    let locations = atom.locations.len() as u32;
    let ports = atom.ports.len() as u32;
    let cell = |l: u32, p: u32| atom.transitions_from(l, Some(p));
    let sizes: Option<Vec<u64>> = atom
        .vars
        .iter()
        .map(|v| {
            let (lo, hi) = v.ty.range();
            u64::try_from(i128::from(hi) - i128::from(lo) + 1).ok()
        })
        .collect();
    let states = sizes
        .as_ref()
        .and_then(|s| s.iter().try_fold(1u64, |n, &k| n.checked_mul(k)))
        .filter(|&n| n <= MAX_LOCAL_STATES);
    let mut most = vec![0u32; ports as usize];
    for p in 0..ports {
        for l in 0..locations {
            let r = cell(l, p);
            let n = r.end - r.start;
            // one transition needs no trying, and a large atom is not tried
            if n <= 1 || states.is_none() {
                most[p as usize] = most[p as usize].max(n);
            }
        }
    }
    // the cells to try: several transitions on a port from one location
    let cells: Vec<(u32, core::ops::Range<u32>)> = (0..ports)
        .flat_map(|p| (0..locations).map(move |l| (p, cell(l, p))))
        .filter(|(_, r)| r.end - r.start > 1)
        .collect();
    let (Some(states), Some(sizes)) = (states, sizes) else {
        return most;
    };
    if cells.is_empty() {
        return most;
    }
    // slot 0 stands for the location (guards do not read it), then the variables
    let mut slots = vec![0i64; 1 + atom.vars.len()];
    for k in 0..states {
        let mut rest = k;
        for (v, &n) in sizes.iter().enumerate() {
            let (lo, _) = atom.vars[v].ty.range();
            slots[1 + v] = lo + (rest % n) as i64;
            rest /= n;
        }
        for (p, r) in &cells {
            // a guard that cannot be evaluated counts as holding
            let together = r
                .clone()
                .filter(|&t| match &atom.transitions[t as usize].guard {
                    None => true,
                    Some(g) => g.holds(&mut Env::new(&slots, 1)).unwrap_or(true),
                })
                .count() as u32;
            most[*p as usize] = most[*p as usize].max(together);
        }
    }
    most
}

/// The most steps interaction `inter` may have in one state, given [`most_enabled`] of
/// every atom (`most[a]` for atom `a`); `u64::MAX` stands for anything larger. A port
/// with no transition counts 0 (the interaction never fires) unless it is a broadcast's
/// receiver, which then does not join.
pub fn most_steps(components: &[Component], most: &[Vec<u32>], inter: &Interaction) -> u64 {
    let mut n = 1u64;
    for (k, p) in inter.ports.iter().enumerate() {
        let atom = components[p.component as usize].atom as usize;
        let factor = most[atom][p.port as usize];
        let receiver = inter.trigger.is_some_and(|t| t as usize != k);
        let factor = if receiver { factor.max(1) } else { factor };
        n = n.saturating_mul(u64::from(factor));
    }
    n
}
