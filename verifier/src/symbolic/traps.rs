//! Interaction invariants from traps of the net (D-Finder's interaction invariants).
//!
//! A set of places `Q` is a trap if every net transition that takes a token from `Q` puts
//! one into `Q`. Once marked, a trap stays marked, so for an initially marked trap "some
//! component is at one of `Q`'s locations" holds in every reachable state.
//!
//! Traps are found lazily, for a candidate state the solver proposes: the largest trap
//! inside the candidate's unmarked places is computed by a fixpoint (linear in the net's
//! size, no solver call); if it holds an initially marked place, the candidate is
//! unreachable, and small traps grown from those places inside it are learned as
//! invariants, which rule out the candidate and every state like it.
//!
//! With groups and members (see `net.rs`), the trap condition for a member's move
//! `from → to` reads: if `from` is in `Q`, then `to` is in `Q`, or some member the move can
//! count on (`Net::others`) has all its targets in `Q`. This is exact for the product of
//! the members' moves without building it.

use super::net::Net;

/// The largest trap inside the places marked `true` in `allowed`.
pub fn max_trap(net: &Net, allowed: &[bool]) -> Vec<bool> {
    let mut in_s = allowed.to_vec();
    let members = &net.members;
    // per member: moves whose target is outside the set; all targets inside <=> 0
    let mut miss: Vec<u32> = members
        .iter()
        .map(|m| m.moves.iter().filter(|&&(_, t)| !in_s[t as usize]).count() as u32)
        .collect();
    // per member: members it can count on that have all their targets inside
    let mut ycount: Vec<u32> = (0..members.len() as u32)
        .map(|m| {
            net.others(m)
                .iter()
                .filter(|&&o| miss[o as usize] == 0)
                .count() as u32
        })
        .collect();
    let mut removed: Vec<u32> = Vec::new();
    let remove = |p: u32, in_s: &mut Vec<bool>, removed: &mut Vec<u32>| {
        if in_s[p as usize] {
            in_s[p as usize] = false;
            removed.push(p);
        }
    };
    // a member nobody can help: any move from inside to outside removes its source
    let settle = |m: usize, in_s: &mut Vec<bool>, removed: &mut Vec<u32>| {
        for &(f, t) in &members[m].moves {
            if in_s[f as usize] && !in_s[t as usize] {
                remove(f, in_s, removed);
            }
        }
    };
    for (m, &y) in ycount.iter().enumerate() {
        if y == 0 {
            settle(m, &mut in_s, &mut removed);
        }
    }
    while let Some(p) = removed.pop() {
        for &(m, k) in &net.producers[p as usize] {
            let m = m as usize;
            miss[m] += 1;
            if miss[m] == 1 {
                for &d in &net.dependents[m] {
                    let d = d as usize;
                    ycount[d] -= 1;
                    if ycount[d] == 0 {
                        settle(d, &mut in_s, &mut removed);
                    }
                }
            }
            if ycount[m] == 0 {
                let f = members[m].moves[k as usize].0;
                remove(f, &mut in_s, &mut removed);
            }
        }
    }
    in_s
}

/// A small trap containing `seed`, inside the trap `within`: grown from the seed, adding
/// for each unsatisfied move the option that adds the fewest places.
pub fn small_trap(net: &Net, seed: u32, within: &[bool]) -> Vec<u32> {
    let mut in_q = vec![false; net.places()];
    let mut list = vec![seed];
    in_q[seed as usize] = true;
    let all_in = |m: u32, set: &[bool]| {
        net.members[m as usize]
            .moves
            .iter()
            .all(|&(_, t)| set[t as usize])
    };
    let mut i = 0;
    while i < list.len() {
        let q = list[i];
        i += 1;
        for &(m, k) in &net.consumers[q as usize] {
            let (_, t) = net.members[m as usize].moves[k as usize];
            if in_q[t as usize] {
                continue;
            }
            let others = net.others(m);
            if others.iter().any(|&o| all_in(o, &in_q)) {
                continue;
            }
            let mut best: Option<Vec<u32>> = within[t as usize].then(|| vec![t]);
            for &o in &others {
                if !all_in(o, within) {
                    continue;
                }
                let mut add: Vec<u32> = net.members[o as usize]
                    .moves
                    .iter()
                    .map(|&(_, t)| t)
                    .filter(|&t| !in_q[t as usize])
                    .collect();
                add.sort_unstable();
                add.dedup();
                if best.as_ref().is_none_or(|b| add.len() < b.len()) {
                    best = Some(add);
                }
            }
            // `within` is a trap, so some option exists; if not, the caller's set was wrong
            for p in best.unwrap_or_default() {
                if !in_q[p as usize] {
                    in_q[p as usize] = true;
                    list.push(p);
                }
            }
        }
    }
    list.sort_unstable();
    list
}

/// The initially marked traps that are empty in a candidate state (given by the place
/// each component occupies), as small traps; empty if there is none, which means the
/// candidate is not excluded by any trap.
pub fn empty_traps(net: &Net, marked: &[u32], limit: usize) -> Vec<Vec<u32>> {
    let mut allowed = vec![true; net.places()];
    for &p in marked {
        allowed[p as usize] = false;
    }
    let q = max_trap(net, &allowed);
    let mut out: Vec<Vec<u32>> = Vec::new();
    for p in 0..net.places() as u32 {
        if out.len() >= limit {
            break;
        }
        if q[p as usize] && net.initial[p as usize] {
            // a place already in a trap found for this candidate gives the same trap again
            if out.iter().any(|t| t.binary_search(&p).is_ok()) {
                continue;
            }
            out.push(small_trap(net, p, &q));
        }
    }
    out
}
