//! The Petri net the components and connectors form, for the interaction invariants.
//!
//! Places are the components' locations; each component holds one token, on its current
//! location. An interaction moves the tokens of its participants, each along one of its
//! transitions on the interaction's port. Rather than listing every combination of the
//! participants' transitions (a product), the net keeps one *group* per interaction with
//! one *member* per participant and the member's possible moves: a net transition is one
//! move per member (every member for a rendezvous; the trigger and any subset of the
//! receivers for a broadcast). Only live transitions (see `invariants.rs`) are moves, and
//! an interaction with a required participant that has none is left out: it never fires.
//! Internal transitions form one single-member group per component.
//!
//! Places are refined by data where it is cheap (D-Finder's abstract states): a component
//! with at most [`MAX_REFINED`] reachable local states (location and values, from its
//! component invariant) gets one place per local state, and its moves follow its local
//! transitions between them. Traps and semiflows then relate one component's data to
//! another's location ("the sequencer has left `boot` only if `Init` has run").
//!
//! The over-approximation (all receiver subsets, data ignored, priorities ignored) is
//! sound: every step the system takes is a transition of this net, so traps and
//! semiflows of the net are invariants of the system.

use std::collections::HashMap;

use bip_model::State;
use z3::ast::Bool;

use super::encode::{Encoding, Frame};
use super::invariants::ComponentInvariants;
use super::term::and;

/// Components with at most this many local states get a place per local state.
pub const MAX_REFINED: usize = 64;

pub struct Net {
    /// First place of each component.
    pub place_of: Vec<u32>,
    /// Per place: component and location.
    pub comp_of: Vec<u32>,
    pub loc_of: Vec<u32>,
    /// Per place of a refined component: the values of its variables there.
    pub vals_of: Vec<Option<Vec<i64>>>,
    /// Per refined component: its local states' places.
    refined: Vec<Option<HashMap<Vec<i64>, u32>>>,
    /// Per place: marked in the initial state.
    pub initial: Vec<bool>,
    /// Per place: reachable by the component alone.
    pub reachable: Vec<bool>,
    pub groups: Vec<Group>,
    pub members: Vec<Member>,
    /// Per member: the members whose clause it appears in (see [`Net::others`]).
    pub dependents: Vec<Vec<u32>>,
    /// Per place: the (member, move) pairs leaving it and entering it.
    pub consumers: Vec<Vec<(u32, u32)>>,
    pub producers: Vec<Vec<(u32, u32)>>,
}

pub struct Group {
    pub first: u32,
    pub len: u32,
    /// For a broadcast, the trigger's index among the members; the others may not join.
    pub trigger: Option<u32>,
}

pub struct Member {
    pub group: u32,
    /// Index within the group.
    pub index: u32,
    /// (from place, to place) of each live transition of the participant on the port.
    pub moves: Vec<(u32, u32)>,
}

impl Net {
    /// Stops early once `stop` says so; the caller must not use an incomplete net.
    pub fn new(enc: &Encoding<'_>, ci: &ComponentInvariants, stop: &dyn Fn() -> bool) -> Net {
        let sys = enc.sys;
        let init = sys.initial_state();
        let mut net = Net {
            place_of: Vec::with_capacity(sys.components.len()),
            comp_of: Vec::new(),
            loc_of: Vec::new(),
            vals_of: Vec::new(),
            refined: Vec::with_capacity(sys.components.len()),
            initial: Vec::new(),
            reachable: Vec::new(),
            groups: Vec::new(),
            members: Vec::new(),
            dependents: Vec::new(),
            consumers: Vec::new(),
            producers: Vec::new(),
        };
        for (c, comp) in sys.components.iter().enumerate() {
            if stop() {
                return net;
            }
            let atom = &sys.atoms[comp.atom as usize];
            net.place_of.push(net.comp_of.len() as u32);
            let inv = &ci.per_component[c];
            let graph = inv
                .graph
                .as_ref()
                .filter(|g| !atom.vars.is_empty() && g.states.len() <= MAX_REFINED);
            match graph {
                Some(g) => {
                    let start = comp.slot as usize;
                    let here = &init.slots()[start..=start + atom.vars.len()];
                    let mut index = HashMap::new();
                    for st in &g.states {
                        index.insert(st.clone(), net.comp_of.len() as u32);
                        net.comp_of.push(c as u32);
                        net.loc_of.push(st[0] as u32);
                        net.vals_of.push(Some(st[1..].to_vec()));
                        net.initial.push(st.as_slice() == here);
                        net.reachable.push(true);
                    }
                    net.refined.push(Some(index));
                }
                None => {
                    let l0 = sys.location(&init, c as u32);
                    for l in 0..atom.locations.len() as u32 {
                        net.comp_of.push(c as u32);
                        net.loc_of.push(l);
                        net.vals_of.push(None);
                        net.initial.push(l == l0);
                        net.reachable.push(inv.locations[l as usize]);
                    }
                    net.refined.push(None);
                }
            }
        }
        // `receiver`: a broadcast receiver, whose values the action may change when it
        // does not join
        let moves = |c: u32, port: Option<u32>, receiver: bool, net: &Net| -> Vec<(u32, u32)> {
            let comp = &sys.components[c as usize];
            let atom = &sys.atoms[comp.atom as usize];
            let inv = &ci.per_component[c as usize];
            let base = net.place_of[c as usize];
            let mut out = Vec::new();
            for &t in enc.transitions_on(c, port) {
                if !inv.live[t as usize] {
                    continue;
                }
                match (&net.refined[c as usize], &inv.graph) {
                    (Some(_), Some(g)) => {
                        out.extend(
                            g.edges[t as usize]
                                .iter()
                                .map(|&(f, to)| (base + f, base + to)),
                        );
                    }
                    _ => {
                        let tr = &atom.transitions[t as usize];
                        out.push((base + tr.from, base + tr.to));
                    }
                }
            }
            if let (true, Some(_), Some(g)) = (receiver, &net.refined[c as usize], &inv.graph) {
                let passive = &g.edges[atom.transitions.len()];
                out.extend(passive.iter().map(|&(f, to)| (base + f, base + to)));
            }
            out
        };
        for (i, inter) in sys.interactions.iter().enumerate() {
            if stop() {
                return net;
            }
            let mut ms = Vec::new();
            let mut trigger = None;
            let mut dead = false;
            for (k, p) in inter.ports.iter().enumerate() {
                let required = enc.required(i as u32, k as u32);
                let mv = moves(p.component, Some(p.port), !required, &net);
                if mv.is_empty() {
                    if required {
                        dead = true;
                        break;
                    }
                    continue; // a receiver that never joins
                }
                if required && inter.trigger.is_some() {
                    trigger = Some(ms.len() as u32);
                }
                ms.push(mv);
            }
            if !dead {
                net.push_group(ms, trigger);
            }
        }
        for c in 0..sys.components.len() as u32 {
            if stop() {
                return net;
            }
            let mv = moves(c, None, false, &net);
            if !mv.is_empty() {
                net.push_group(vec![mv], None);
            }
        }
        if stop() {
            return net;
        }
        let places = net.comp_of.len();
        net.consumers = vec![Vec::new(); places];
        net.producers = vec![Vec::new(); places];
        net.dependents = vec![Vec::new(); net.members.len()];
        for (m, member) in net.members.iter().enumerate() {
            for (k, &(f, t)) in member.moves.iter().enumerate() {
                net.consumers[f as usize].push((m as u32, k as u32));
                net.producers[t as usize].push((m as u32, k as u32));
            }
        }
        for m in 0..net.members.len() as u32 {
            for o in net.others(m) {
                net.dependents[o as usize].push(m);
            }
        }
        net
    }

    /// The place each component occupies in `state` (`None` for a component whose local
    /// state is not one of its reachable ones: the state is unreachable).
    pub fn marking(&self, enc: &Encoding<'_>, state: &State) -> Option<Vec<u32>> {
        let sys = enc.sys;
        sys.components
            .iter()
            .enumerate()
            .map(|(c, comp)| match &self.refined[c] {
                Some(index) => {
                    let start = comp.slot as usize;
                    let nv = sys.atoms[comp.atom as usize].vars.len();
                    index.get(&state.slots()[start..=start + nv]).copied()
                }
                None => Some(self.place_of[c] + sys.location(state, c as u32)),
            })
            .collect()
    }

    /// "The component of place `p` is in it", on a frame.
    pub fn at(&self, enc: &Encoding<'_>, f: &Frame, p: u32) -> Bool {
        let c = self.comp_of[p as usize];
        let here = enc.at(f, c, self.loc_of[p as usize]);
        match &self.vals_of[p as usize] {
            None => here,
            Some(vals) => {
                let comp = &enc.sys.components[c as usize];
                and(
                    std::iter::once(here).chain(vals.iter().enumerate().map(|(v, &x)| {
                        let slot = &f.slots[comp.var_slot(v as u32) as usize];
                        slot.eq_const(x)
                    })),
                )
            }
        }
    }

    fn push_group(&mut self, members: Vec<Vec<(u32, u32)>>, trigger: Option<u32>) {
        let g = self.groups.len() as u32;
        let first = self.members.len() as u32;
        let len = members.len() as u32;
        for (index, moves) in members.into_iter().enumerate() {
            self.members.push(Member {
                group: g,
                index: index as u32,
                moves,
            });
        }
        self.groups.push(Group {
            first,
            len,
            trigger,
        });
    }

    /// The members whose moves can put a token back when member `m` takes one: every other
    /// member of a rendezvous; for a broadcast, a receiver can count on the trigger (which
    /// always takes part) and the trigger on nobody (it may move alone).
    pub fn others(&self, m: u32) -> Vec<u32> {
        let member = &self.members[m as usize];
        let g = &self.groups[member.group as usize];
        match g.trigger {
            Some(t) if t == member.index => Vec::new(),
            Some(t) => vec![g.first + t],
            None => (g.first..g.first + g.len).filter(|&o| o != m).collect(),
        }
    }

    pub fn places(&self) -> usize {
        self.comp_of.len()
    }
}
