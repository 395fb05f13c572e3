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
//! The over-approximation (all receiver subsets, data ignored, priorities ignored) is
//! sound: every step the system takes is a transition of this net, so traps and
//! semiflows of the net are invariants of the system.

use super::encode::Encoding;
use super::invariants::ComponentInvariants;

pub struct Net {
    /// First place of each component (its location 0).
    pub place_of: Vec<u32>,
    /// Per place: component and location.
    pub comp_of: Vec<u32>,
    pub loc_of: Vec<u32>,
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
    pub fn new(enc: &Encoding<'_>, ci: &ComponentInvariants) -> Net {
        let sys = enc.sys;
        let init = sys.initial_state();
        let mut place_of = Vec::with_capacity(sys.components.len());
        let (mut comp_of, mut loc_of, mut initial, mut reachable) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (c, comp) in sys.components.iter().enumerate() {
            let atom = &sys.atoms[comp.atom as usize];
            place_of.push(comp_of.len() as u32);
            let l0 = sys.location(&init, c as u32);
            for l in 0..atom.locations.len() as u32 {
                comp_of.push(c as u32);
                loc_of.push(l);
                initial.push(l == l0);
                reachable.push(ci.per_component[c].locations[l as usize]);
            }
        }
        let mut net = Net {
            place_of,
            comp_of,
            loc_of,
            initial,
            reachable,
            groups: Vec::new(),
            members: Vec::new(),
            dependents: Vec::new(),
            consumers: Vec::new(),
            producers: Vec::new(),
        };
        let moves = |c: u32, port: Option<u32>, net: &Net| -> Vec<(u32, u32)> {
            let comp = &sys.components[c as usize];
            let atom = &sys.atoms[comp.atom as usize];
            let base = net.place_of[c as usize];
            enc.transitions_on(c, port)
                .iter()
                .filter(|&&t| ci.per_component[c as usize].live[t as usize])
                .map(|&t| {
                    let tr = &atom.transitions[t as usize];
                    (base + tr.from, base + tr.to)
                })
                .collect()
        };
        for (i, inter) in sys.interactions.iter().enumerate() {
            let mut ms = Vec::new();
            let mut trigger = None;
            let mut dead = false;
            for (k, p) in inter.ports.iter().enumerate() {
                let mv = moves(p.component, Some(p.port), &net);
                let required = enc.required(i as u32, k as u32);
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
            let mv = moves(c, None, &net);
            if !mv.is_empty() {
                net.push_group(vec![mv], None);
            }
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
