//! The step relation's flat index of transitions, built once with the system: which
//! transitions each port of each component offers from each location, the compiled code
//! of every guard and action, and the step tables.

#[allow(unused_imports)]
use crate::prelude::*;

use crate::fast_path::{ActionCode, FlatCode, GuardCode, Ranges, ValueCode};

/// Flat tables for finding enabled transitions quickly: the transitions of a component from
/// its current location on a port are `cells[port.base + location * port.stride]`, without
/// going through the component and its atom. Built once when the system is compiled.
#[derive(Clone, Debug, Default)]
pub(crate) struct EnableIndex {
    /// Every atom's `by_loc_port`, concatenated, as `(start, end)`.
    pub(crate) cells: Vec<(u32, u32)>,
    /// The ports of each interaction: `ports[inter_ports[i]]`.
    pub(crate) inter_ports: Vec<(u32, u32)>,
    pub(crate) ports: Vec<PortCell>,
    /// One per component: where its internal transitions are.
    pub(crate) internal: Vec<PortCell>,
    /// The flat forms of the guards and actions: per atom, from its components'
    /// `comp_code` on, one per transition; per interaction, its connector's.
    pub(crate) flat: FlatCode,
    pub(crate) guards: Vec<GuardCode>,
    pub(crate) actions: Vec<ActionCode>,
    /// Per transition (indexed like `actions`), the location it moves to, or [`STAYS`].
    pub(crate) moves: Vec<u32>,
    /// Per component, where its atom's transitions start in `guards`, `actions` and `moves`,
    /// and its location slot.
    pub(crate) comp_code: Vec<(u32, u32)>,
    pub(crate) inter_guards: Vec<GuardCode>,
    pub(crate) inter_actions: Vec<ActionCode>,
    /// Each interaction's `advance`, if it has one.
    pub(crate) inter_advance: Vec<Option<ValueCode>>,
    /// The interactions' steps tabulated over their arguments (filled once the system
    /// exists, since the relation computes them).
    pub(crate) tables: crate::step_tables::StepTables,
}

/// A transition that stays where it is.
pub(crate) const STAYS: u32 = u32::MAX;

/// Why the steps of an interaction read a slot ([`System::interaction_reads`]).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Read {
    /// The location of the participant at port `port` (the position in the interaction's
    /// ports).
    Location { port: usize },
    /// A guard of that participant's transition on its port that starts at `from`.
    Guard { port: usize, from: u32 },
    /// The connector's guard.
    Connector,
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct PortCell {
    pub(crate) component: u32,
    /// The component's location slot.
    pub(crate) slot: u32,
    pub(crate) base: u32,
    pub(crate) stride: u32,
    /// A broadcast receiver, which does not block the interaction.
    pub(crate) optional: bool,
    /// Where the atom's transitions start in the flat code tables.
    pub(crate) code: u32,
    /// The slot of the component's first variable (what `Local` reads are relative to).
    pub(crate) vars: u32,
}

impl EnableIndex {
    pub(crate) fn new(
        atoms: &[crate::model::Atom],
        components: &[crate::model::Component],
        interactions: &[crate::model::Interaction],
        slot_ranges: &[(i64, i64)],
    ) -> EnableIndex {
        let mut cells = Vec::new();
        let mut atom_base = Vec::with_capacity(atoms.len());
        let mut flat = FlatCode::default();
        let (mut atom_code, mut guards, mut actions) = (Vec::new(), Vec::new(), Vec::new());
        let mut moves = Vec::new();
        let mut locals = Vec::new();
        for a in atoms {
            atom_base.push(cells.len() as u32);
            cells.extend(a.by_loc_port.iter().map(|r| (r.start, r.end)));
            atom_code.push(guards.len() as u32);
            locals.clear();
            locals.extend(a.vars.iter().map(|v| v.ty.range()));
            let ranges = Ranges {
                slots: slot_ranges,
                locals: &locals,
            };
            for t in &a.transitions {
                guards.push(flat.guard(t.guard.as_ref(), &ranges));
                actions.push(flat.action(&t.action, &ranges));
                moves.push(if t.to == t.from { STAYS } else { t.to });
            }
        }
        let ranges = Ranges {
            slots: slot_ranges,
            locals: &[],
        };
        let inter_guards = interactions
            .iter()
            .map(|i| flat.guard(i.guard.as_ref(), &ranges))
            .collect();
        let inter_actions = interactions
            .iter()
            .map(|i| flat.action(&i.action, &ranges))
            .collect();
        let inter_advance = interactions
            .iter()
            .map(|i| i.advance.as_ref().map(|e| flat.value(e, &ranges)))
            .collect();
        flat.done();
        let cell = |component: u32, col: usize, optional: bool| {
            let comp = &components[component as usize];
            let atom = &atoms[comp.atom as usize];
            PortCell {
                component,
                slot: comp.slot,
                base: atom_base[comp.atom as usize] + col as u32,
                stride: atom.ports.len() as u32 + 1,
                optional,
                code: atom_code[comp.atom as usize],
                vars: comp.slot + 1,
            }
        };
        let mut ports = Vec::new();
        let mut inter_ports = Vec::with_capacity(interactions.len());
        for inter in interactions {
            let start = ports.len() as u32;
            for (k, pr) in inter.ports.iter().enumerate() {
                let optional = inter.trigger.is_some_and(|tr| tr as usize != k);
                ports.push(cell(pr.component, pr.port as usize, optional));
            }
            inter_ports.push((start, ports.len() as u32));
        }
        let comp_code = components
            .iter()
            .map(|c| (atom_code[c.atom as usize], c.slot))
            .collect();
        let internal = (0..components.len() as u32)
            .map(|c| {
                let ports = atoms[components[c as usize].atom as usize].ports.len();
                cell(c, ports, false)
            })
            .collect();
        EnableIndex {
            cells,
            inter_ports,
            ports,
            internal,
            flat,
            guards,
            actions,
            moves,
            comp_code,
            inter_guards,
            inter_actions,
            inter_advance,
            tables: Default::default(),
        }
    }

    #[inline]
    pub(crate) fn transitions(&self, port: &PortCell, slots: &[i64]) -> (u32, u32) {
        let loc = slots[port.slot as usize] as u32;
        self.cells[(port.base + loc * port.stride) as usize]
    }
}
