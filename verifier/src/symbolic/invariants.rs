//! Component invariants: what each component can reach on its own.
//!
//! Each component is explored alone, with `bip-model`'s expression evaluation, assuming
//! every port it has in some connector is always available (the other components are
//! abstracted away) and that a connector action may give the variables it writes any value
//! of their range. The local states found over-approximate the component's part of every
//! reachable global state, so the formula "the location is one of those reached, and the
//! variables one of the valuations reached there" holds in every reachable state. Steps
//! whose guard or action fails are left out, as the global semantics leaves them out
//! (range errors are checked as a property of their own).
//!
//! The exploration also tells which transitions can ever fire ("live"): the others are
//! dropped from the Petri net whose traps and semiflows give the interaction invariants,
//! which makes those stronger. Components with the same atom, initial values, ports in use
//! and connector-written variables share one exploration (ten thousand philosophers are
//! explored once).

use std::collections::{HashMap, HashSet, VecDeque};

use bip_model::eval::{Env, Expr};
use bip_model::{Assign, System, Target};
use z3::ast::Bool;

use super::encode::{Encoding, Frame};
use super::term::{and, eq_num, implies, not, or};

/// Local states explored per component before giving up on exact values.
const MAX_LOCAL_STATES: usize = 100_000;
/// Valuations a connector action may leave, per step, before giving up on exact values.
const MAX_HAVOC: usize = 4096;
/// Valuations per location written out as a table; more become per-variable value sets.
const MAX_TABLE: usize = 64;

/// What one component can reach alone.
#[derive(Clone, Debug)]
pub struct ComponentInvariant {
    /// Per location: reachable.
    pub locations: Vec<bool>,
    /// Per location: the valuations of the variables reached there, when they were
    /// enumerated (`None`: only the declared ranges are known).
    pub values: Option<Vec<Vec<Vec<i64>>>>,
    /// Per transition: it fires from some reachable local state.
    pub live: Vec<bool>,
    /// The local states and, per transition, the moves between them, when the values
    /// were enumerated.
    pub graph: Option<LocalGraph>,
}

/// A component's reachable local states (`[location, values...]`) and, per transition,
/// the pairs of local states (by index) it connects; the last entry of `edges` holds the
/// changes a broadcast's action makes to a receiver that does not join.
#[derive(Clone, Debug)]
pub struct LocalGraph {
    pub states: Vec<Vec<i64>>,
    pub edges: Vec<Vec<(u32, u32)>>,
}

/// The invariants of every component.
pub struct ComponentInvariants {
    pub per_component: Vec<ComponentInvariant>,
    /// Components whose values were not enumerated (too many local states).
    pub approximate: usize,
}

/// The part of a component's situation that decides its local exploration.
#[derive(Clone, PartialEq, Eq, Hash)]
struct Key {
    atom: u32,
    init: Vec<i64>,
    ports: Vec<bool>,
    havoc: Vec<Vec<u32>>,
    /// Variables a broadcast's action may write while the component, a receiver, does not
    /// join (it does not move, but its values change).
    passive: Vec<u32>,
}

/// Stops early (with the components seen so far) once `stop` says so; the caller must not
/// use an incomplete result.
pub fn compute(enc: &Encoding<'_>, stop: &dyn Fn() -> bool) -> ComponentInvariants {
    let sys = enc.sys;
    let init = sys.initial_state();
    let mut cache: HashMap<Key, ComponentInvariant> = HashMap::new();
    let mut per_component = Vec::with_capacity(sys.components.len());
    let mut approximate = 0;
    for (c, comp) in sys.components.iter().enumerate() {
        if stop() {
            break;
        }
        let atom = &sys.atoms[comp.atom as usize];
        let nv = atom.vars.len();
        let start = comp.slot as usize;
        let mut ports = vec![false; atom.ports.len()];
        let mut havoc = vec![Vec::new(); atom.ports.len()];
        let mut passive = Vec::new();
        for &(i, k) in &enc.inters_of[c] {
            let inter = &sys.interactions[i as usize];
            let p = inter.ports[k as usize].port as usize;
            ports[p] = true;
            let receiver = !enc.required(i, k);
            for a in &inter.action {
                if let Target::Slot(s) = a.target {
                    if s > comp.slot && (s as usize) <= start + nv {
                        let v = s - comp.slot - 1;
                        if !havoc[p].contains(&v) {
                            havoc[p].push(v);
                        }
                        if receiver && !passive.contains(&v) {
                            passive.push(v);
                        }
                    }
                }
            }
        }
        for h in &mut havoc {
            h.sort_unstable();
        }
        passive.sort_unstable();
        let key = Key {
            atom: comp.atom,
            init: init.slots()[start..=start + nv].to_vec(),
            ports,
            havoc,
            passive,
        };
        let inv = cache
            .entry(key)
            .or_insert_with_key(|key| explore(sys, key))
            .clone();
        if inv.values.is_none() && nv > 0 {
            approximate += 1;
        }
        per_component.push(inv);
    }
    ComponentInvariants {
        per_component,
        approximate,
    }
}

/// A sentinel slot base: reads at or above it are the atom's own variables.
const LOCAL_BASE: u32 = 1 << 30;

fn reads_only_locals(e: &Expr) -> bool {
    let mut ok = true;
    e.for_each_slot(LOCAL_BASE, &mut |s| ok &= s >= LOCAL_BASE);
    ok
}

/// Explores one component alone.
fn explore(sys: &System, key: &Key) -> ComponentInvariant {
    let atom = &sys.atoms[key.atom as usize];
    let nv = atom.vars.len();
    let ranges: Vec<(i64, i64)> = atom.vars.iter().map(|v| v.ty.range()).collect();
    let usable: Vec<bool> = atom
        .transitions
        .iter()
        .map(|t| t.port.is_none_or(|p| key.ports[p as usize]))
        .collect();
    // a guard or action that reads outside the atom cannot be decided here: take both ways
    let local_guard: Vec<bool> = atom
        .transitions
        .iter()
        .map(|t| t.guard.as_ref().is_none_or(reads_only_locals))
        .collect();
    let local_action: Vec<bool> = atom
        .transitions
        .iter()
        .map(|t| t.action.iter().all(|a| reads_only_locals(&a.value)))
        .collect();
    let mut live = vec![false; atom.transitions.len()];
    let mut seen: HashMap<Vec<i64>, u32> = HashMap::new();
    let mut states: Vec<Vec<i64>> = Vec::new();
    let mut edges: Vec<HashSet<(u32, u32)>> = vec![HashSet::new(); atom.transitions.len() + 1];
    let passive_combos: usize = key
        .passive
        .iter()
        .map(|&v| (ranges[v as usize].1 - ranges[v as usize].0 + 1) as usize)
        .try_fold(1usize, |acc, n| acc.checked_mul(n))
        .unwrap_or(usize::MAX);
    let mut exact = passive_combos <= MAX_HAVOC;
    let mut queue = VecDeque::new();
    seen.insert(key.init.clone(), 0);
    states.push(key.init.clone());
    queue.push_back(key.init.clone());
    'search: while let Some(s) = queue.pop_front() {
        if !exact {
            break;
        }
        let loc = s[0] as u32;
        let from = seen[&s];
        // a broadcast this component does not join may still write its variables
        if !key.passive.is_empty() {
            for next in havocked(&s, &key.passive, &ranges) {
                let to = match seen.get(&next) {
                    Some(&i) => i,
                    None => {
                        if seen.len() >= MAX_LOCAL_STATES {
                            exact = false;
                            break 'search;
                        }
                        let i = states.len() as u32;
                        seen.insert(next.clone(), i);
                        states.push(next.clone());
                        queue.push_back(next);
                        i
                    }
                };
                if to != from {
                    edges[atom.transitions.len()].insert((from, to));
                }
            }
        }
        for (k, t) in atom.transitions.iter().enumerate() {
            if t.from != loc || !usable[k] {
                continue;
            }
            let enabled = match (&t.guard, local_guard[k]) {
                (None, _) | (_, false) => true,
                (Some(g), true) => matches!(g.holds(&mut Env::new(&s, 1)), Ok(true)),
            };
            if !enabled {
                continue;
            }
            // the connector may have written these variables (any value) before the action
            let mut written: Vec<u32> =
                t.port.map_or(Vec::new(), |p| key.havoc[p as usize].clone());
            if !local_action[k] {
                for a in &t.action {
                    if let Target::Local(v) = a.target {
                        written.push(v);
                    }
                }
            }
            let combos: usize = written
                .iter()
                .map(|&v| (ranges[v as usize].1 - ranges[v as usize].0 + 1) as usize)
                .try_fold(1usize, |acc, n| acc.checked_mul(n))
                .unwrap_or(usize::MAX);
            if combos > MAX_HAVOC {
                exact = false;
                break 'search;
            }
            for pre in havocked(&s, &written, &ranges) {
                let action: &[Assign] = if local_action[k] { &t.action } else { &[] };
                let Some(mut next) = run(action, &pre, &ranges) else {
                    continue;
                };
                next[0] = i64::from(t.to);
                live[k] = true;
                let to = match seen.get(&next) {
                    Some(&i) => i,
                    None => {
                        if seen.len() >= MAX_LOCAL_STATES {
                            exact = false;
                            break 'search;
                        }
                        let i = states.len() as u32;
                        seen.insert(next.clone(), i);
                        states.push(next.clone());
                        queue.push_back(next);
                        i
                    }
                };
                edges[k].insert((from, to));
            }
        }
    }
    if !exact {
        return locations_only(atom, key, &usable);
    }
    let mut locations = vec![false; atom.locations.len()];
    let mut values = vec![Vec::new(); atom.locations.len()];
    for s in &states {
        locations[s[0] as usize] = true;
        values[s[0] as usize].push(s[1..=nv].to_vec());
    }
    for v in &mut values {
        v.sort_unstable();
    }
    let edges = edges
        .into_iter()
        .map(|e| {
            let mut e: Vec<(u32, u32)> = e.into_iter().collect();
            e.sort_unstable();
            e
        })
        .collect();
    ComponentInvariant {
        locations,
        values: Some(values),
        live,
        graph: Some(LocalGraph { states, edges }),
    }
}

/// Every valuation with the `written` variables set to each value of their ranges.
fn havocked(s: &[i64], written: &[u32], ranges: &[(i64, i64)]) -> Vec<Vec<i64>> {
    let mut out = vec![s.to_vec()];
    for &v in written {
        let (lo, hi) = ranges[v as usize];
        out = out
            .into_iter()
            .flat_map(|x| {
                (lo..=hi).map(move |val| {
                    let mut y = x.clone();
                    y[1 + v as usize] = val;
                    y
                })
            })
            .collect();
    }
    out
}

/// Runs an atom action on a local state; `None` if it fails.
fn run(action: &[Assign], s: &[i64], ranges: &[(i64, i64)]) -> Option<Vec<i64>> {
    let mut out = s.to_vec();
    for a in action {
        let Target::Local(v) = a.target else {
            return None;
        };
        let val = a.value.eval(&mut Env::new(&out, 1)).ok()?;
        let (lo, hi) = ranges[v as usize];
        if val < lo || val > hi {
            return None;
        }
        out[1 + v as usize] = val;
    }
    Some(out)
}

/// When values cannot be enumerated: the locations reachable in the transition graph
/// (guards ignored), and every usable transition from them live.
fn locations_only(atom: &bip_model::Atom, key: &Key, usable: &[bool]) -> ComponentInvariant {
    let mut locations = vec![false; atom.locations.len()];
    let mut stack = vec![key.init[0] as u32];
    locations[key.init[0] as usize] = true;
    let mut live = vec![false; atom.transitions.len()];
    while let Some(l) = stack.pop() {
        for (k, t) in atom.transitions.iter().enumerate() {
            if t.from == l && usable[k] {
                live[k] = true;
                if !locations[t.to as usize] {
                    locations[t.to as usize] = true;
                    stack.push(t.to);
                }
            }
        }
    }
    ComponentInvariant {
        locations,
        values: None,
        live,
        graph: None,
    }
}

impl ComponentInvariants {
    /// The component invariants as constraints on a frame.
    pub fn constraints(&self, enc: &Encoding<'_>, f: &Frame) -> Vec<Bool> {
        let sys = enc.sys;
        let mut out = Vec::new();
        for (c, inv) in self.per_component.iter().enumerate() {
            enc.poll();
            let comp = &sys.components[c];
            let atom = &sys.atoms[comp.atom as usize];
            for (l, &reach) in inv.locations.iter().enumerate() {
                if !reach {
                    out.push(not(&enc.at(f, c as u32, l as u32)));
                }
            }
            let Some(values) = &inv.values else { continue };
            if atom.vars.is_empty() {
                continue;
            }
            let full: usize = atom
                .vars
                .iter()
                .map(|v| {
                    let (lo, hi) = v.ty.range();
                    usize::try_from(hi - lo + 1).unwrap_or(usize::MAX)
                })
                .try_fold(1usize, |a, n| a.checked_mul(n))
                .unwrap_or(usize::MAX);
            let var = |v: usize| f.slots[comp.var_slot(v as u32) as usize].int_term();
            for (l, tuples) in values.iter().enumerate() {
                if tuples.is_empty() || tuples.len() == full {
                    continue;
                }
                let here = enc.at(f, c as u32, l as u32);
                let allowed = if tuples.len() <= MAX_TABLE {
                    or(tuples
                        .iter()
                        .map(|t| and(t.iter().enumerate().map(|(v, &x)| eq_num(&var(v), x)))))
                } else {
                    // per variable: the values it takes here
                    and((0..atom.vars.len()).map(|v| {
                        let mut vals: Vec<i64> = tuples.iter().map(|t| t[v]).collect();
                        vals.sort_unstable();
                        vals.dedup();
                        let (lo, hi) = atom.vars[v].ty.range();
                        let x = var(v);
                        if vals.len() as i64 == hi - lo + 1 {
                            super::term::tt()
                        } else if vals.len() as i64 == vals[vals.len() - 1] - vals[0] + 1 {
                            and([x.ge(vals[0]), x.le(vals[vals.len() - 1])])
                        } else {
                            or(vals.iter().map(|&k| eq_num(&x, k)))
                        }
                    }))
                };
                out.push(implies(&here, &allowed));
            }
        }
        out
    }
}
