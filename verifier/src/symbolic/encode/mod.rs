//! The z3 encoding of a compiled [`System`]: states as frames of terms, and the step relation
//! of docs/model.md's "Semantics: one step" as formulas.
//!
//! This is the one necessary second description of `bip-model`'s step relation (ARCHITECTURE.md, "one semantics"),
//! mirrored from `bip-model/src/step.rs` rule for rule, and cross-checked against it by a
//! property test on random systems (`verifier/src/symbolic/encoding_tests.rs`):
//!
//! - a frame holds one term per state slot: an `Int` per location and integer variable, a
//!   `Bool` per boolean variable; slots with a single possible value are numerals;
//! - [`Encoding::enabling`] gives, for a frame, which transitions, ports and interactions
//!   are enabled (before and after priorities) and the condition under which computing the
//!   enabled steps fails (a guard that cannot be evaluated), with the evaluation order of
//!   `System::enabled_steps` so that exactly the same states fail;
//! - [`Encoding::step`] encodes one step from a frame: a selector `sel` picks the
//!   interaction (or the component whose internal transition fires), one `tr` variable per
//!   component picks its transition; it yields the successor's terms, the condition that
//!   the choice is an enabled step (broadcast receivers join exactly when enabled, priorities
//!   apply) and the condition that firing it fails (a value out of range, a division by
//!   zero): connector action first, then the participants' actions in port order, then the
//!   moves.
//!
//! This module holds the encoding's tables and its frames; `enabling` encodes what is
//! enabled in a frame (priorities included), `step` one step from it.

mod enabling;
mod step;

use std::sync::Arc;

use bip_model::eval::Expr;
use bip_model::{Role, State, System, VarType};

use z3::ast::{Bool, Int};

use crate::symbolic::term::{and, ff, iff, lt_const, translate, width, Slots, Sym, Term};
use crate::watch::Watch;

pub use enabling::Enabling;
pub use step::{StepFilter, StepVars};

/// What a state slot holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SlotKind {
    /// A component's location number, `0..count`.
    Loc {
        count: u32,
    },
    Bool,
    Int {
        lo: i64,
        hi: i64,
    },
}

impl SlotKind {
    pub fn range(&self) -> (i64, i64) {
        match *self {
            SlotKind::Loc { count } => (0, i64::from(count) - 1),
            SlotKind::Bool => (0, 1),
            SlotKind::Int { lo, hi } => (lo, hi),
        }
    }
}

/// The tables the encoding needs, computed once per system.
pub struct Encoding<'s> {
    pub sys: &'s System,
    pub kinds: Vec<SlotKind>,
    /// Per atom, per port (the last index holds the internal transitions): its transitions.
    pub by_port: Vec<Vec<Vec<u32>>>,
    /// Per group of the priority graph, the priorities with it on their high side.
    pub groups_above: Vec<Vec<u32>>,
    /// Per component, the interactions it takes part in and its position in their ports.
    pub inters_of: Vec<Vec<(u32, u32)>>,
    pub roles: Vec<Role>,
    /// The run's limits: the loops over components stop (by unwinding) once it must stop,
    /// since a wide model's terms take long to build.
    pub watch: Option<Arc<Watch>>,
}

/// One state as terms: one [`Sym`] per slot.
#[derive(Clone, Debug)]
pub struct Frame {
    pub slots: Vec<Sym>,
}

impl Slots for Frame {
    fn slot(&self, slot: u32) -> Sym {
        self.slots[slot as usize].clone()
    }
}

impl<'s> Encoding<'s> {
    pub fn new(sys: &'s System) -> Encoding<'s> {
        let mut kinds = Vec::with_capacity(sys.slot_count());
        for comp in &sys.components {
            let atom = &sys.atoms[comp.atom as usize];
            kinds.push(SlotKind::Loc {
                count: atom.locations.len() as u32,
            });
            for v in &atom.vars {
                kinds.push(match v.ty {
                    VarType::Bool => SlotKind::Bool,
                    VarType::Int { lo, hi } => SlotKind::Int { lo, hi },
                });
            }
        }
        let by_port = sys
            .atoms
            .iter()
            .map(|a| {
                let mut ports = vec![Vec::new(); a.ports.len() + 1];
                for (k, t) in a.transitions.iter().enumerate() {
                    ports[t.port.map_or(a.ports.len(), |p| p as usize)].push(k as u32);
                }
                ports
            })
            .collect();
        let graph = sys.priority_graph();
        let mut groups_above = vec![Vec::new(); graph.groups() as usize];
        for p in 0..sys.priorities.len() as u32 {
            for z in graph.high_groups(p) {
                groups_above[z as usize].push(p);
            }
        }
        let mut inters_of = vec![Vec::new(); sys.components.len()];
        for (i, inter) in sys.interactions.iter().enumerate() {
            for (k, p) in inter.ports.iter().enumerate() {
                inters_of[p.component as usize].push((i as u32, k as u32));
            }
        }
        let roles = sys
            .interactions
            .iter()
            .map(|i| sys.connectors[i.connector as usize].role)
            .collect();
        Encoding {
            sys,
            kinds,
            by_port,
            groups_above,
            inters_of,
            roles,
            watch: None,
        }
    }

    /// Ends the encoding in progress if the run must stop ([`Watch::halt_if_stopped`]).
    pub fn poll(&self) {
        if let Some(w) = &self.watch {
            w.halt_if_stopped();
        }
    }

    /// Transitions of component `c` on port `port` (`None`: internal).
    pub fn transitions_on(&self, c: u32, port: Option<u32>) -> &[u32] {
        let comp = &self.sys.components[c as usize];
        let ports = &self.by_port[comp.atom as usize];
        &ports[port.map_or(ports.len() - 1, |p| p as usize)]
    }

    /// Is port `k` of interaction `i` required (a rendezvous port, or a broadcast's trigger)?
    pub fn required(&self, i: u32, k: u32) -> bool {
        self.sys.interactions[i as usize]
            .trigger
            .is_none_or(|t| t == k)
    }

    /// A frame of fresh constants named `prefix!slot`, and the constraints that keep each
    /// in its range. Slots with one possible value are numerals.
    pub fn fresh_frame(&self, prefix: &str) -> (Frame, Vec<Bool>) {
        let mut slots = Vec::with_capacity(self.kinds.len());
        let mut domain = Vec::new();
        for (s, kind) in self.kinds.iter().enumerate() {
            self.poll();
            let (lo, hi) = kind.range();
            if lo == hi {
                slots.push(Sym::int(lo));
                continue;
            }
            match kind {
                SlotKind::Bool => {
                    slots.push(Sym::of_bool(Bool::new_const(format!("{prefix}!{s}"))));
                }
                SlotKind::Loc { count } => {
                    let w = width(i128::from(hi));
                    let bits: Vec<Bool> = (0..w)
                        .map(|k| Bool::new_const(format!("{prefix}!{s}.{k}")))
                        .collect();
                    if !u64::from(*count).is_power_of_two() {
                        domain.push(lt_const(&bits, u64::from(*count)));
                    }
                    slots.push(Sym::of_bits(bits, 0, hi.into()));
                }
                SlotKind::Int { .. } => {
                    let x = Int::new_const(format!("{prefix}!{s}"));
                    domain.push(x.ge(lo));
                    domain.push(x.le(hi));
                    slots.push(Sym::of_int(x, lo.into(), hi.into()));
                }
            }
        }
        (Frame { slots }, domain)
    }

    /// A frame of numerals: the given state.
    pub fn concrete_frame(&self, state: &State) -> Frame {
        Frame {
            slots: state
                .slots()
                .iter()
                .zip(&self.kinds)
                .map(|(&v, k)| match k {
                    SlotKind::Bool => Sym::boolean(v != 0),
                    _ => Sym::int(v),
                })
                .collect(),
        }
    }

    /// The state a model gives a frame (`None` if a slot has no numeric value, which a
    /// complete model never does).
    pub fn read_state(&self, model: &z3::Model, frame: &Frame) -> Option<State> {
        let mut out = Vec::with_capacity(frame.slots.len());
        for s in &frame.slots {
            let v = match &s.term {
                Term::I(x) => model.eval(x, true)?.as_i64()?,
                Term::B(b) => i64::from(model.eval(b, true)?.as_bool()?),
                Term::Count(..) => model.eval(&s.int_term(), true)?.as_i64()?,
                Term::Bits(bits) => {
                    let mut v = 0;
                    for (k, b) in bits.iter().enumerate() {
                        if model.eval(b, true)?.as_bool()? {
                            v |= 1 << k;
                        }
                    }
                    v
                }
            };
            out.push(v);
        }
        Some(State::from_slots(out))
    }

    /// `a == b`, slot by slot.
    pub fn frames_equal(&self, a: &Frame, b: &Frame) -> Bool {
        and(a.slots.iter().zip(&b.slots).map(|(x, y)| sym_eq(x, y)))
    }

    /// The frame is the given state.
    pub fn frame_is(&self, f: &Frame, state: &State) -> Bool {
        self.frames_equal(f, &self.concrete_frame(state))
    }

    /// `loc(c) == l` in a frame.
    pub fn at(&self, f: &Frame, c: u32, l: u32) -> Bool {
        let slot = self.sys.components[c as usize].slot as usize;
        f.slots[slot].eq_const(i64::from(l))
    }

    /// Evaluates a global expression (property, terminal condition) on a frame.
    pub fn eval(&self, e: &Expr, f: &Frame) -> Sym {
        translate(e, f, 0)
    }
}

/// Two values are equal.
pub fn sym_eq(a: &Sym, b: &Sym) -> Bool {
    if let (Some(x), Some(y)) = (a.constant(), b.constant()) {
        return Bool::from_bool(x == y);
    }
    match (&a.term, &b.term) {
        (Term::B(x), Term::B(y)) => iff(x, y),
        (Term::Bits(_), _) | (_, Term::Bits(_)) if a.lo >= 0 && b.lo >= 0 => {
            let w = width(a.hi.max(b.hi));
            and(a.bits(w).iter().zip(&b.bits(w)).map(|(x, y)| iff(x, y)))
        }
        _ => {
            if a.hi < b.lo || b.hi < a.lo {
                ff()
            } else {
                a.int_term().eq(b.int_term())
            }
        }
    }
}
