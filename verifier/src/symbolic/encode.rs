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

use std::sync::Arc;

use bip_model::eval::Expr;
use bip_model::{Assign, Label, Role, State, System, Target, VarType};

use z3::ast::{Bool, Int};

use super::term::{
    and, and2, err_formula, err_or, err_when, ff, iff, implies, lit, lt_const, not, or, translate,
    tt, width, Choice, Slots, Sym, Term,
};
use crate::watch::Watch;

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

/// A frame seen through assignments made so far (an action in progress).
struct Overlay<'a> {
    base: &'a dyn Slots,
    written: Vec<(u32, Sym)>,
}

impl Slots for Overlay<'_> {
    fn slot(&self, slot: u32) -> Sym {
        match self.written.iter().rev().find(|(s, _)| *s == slot) {
            Some((_, v)) => v.clone(),
            None => self.base.slot(slot),
        }
    }
}

/// What is enabled in a frame.
pub struct Enabling {
    /// Per component, per transition of its atom: it leaves the current location and its
    /// guard holds.
    pub trans_en: Vec<Vec<Bool>>,
    /// Per component, per port (the last index: internal): some transition on it is enabled.
    pub port_en: Vec<Vec<Bool>>,
    /// Per interaction: enabled before priorities. Read by no query, but held as long as
    /// the rest: z3 gives the ids of freed terms to new ones, and the ids order its search,
    /// so freeing these earlier changes which of equally short traces a proof reports.
    #[allow(dead_code)]
    inter_en: Vec<Bool>,
    /// Per interaction: enabled and not suppressed by a priority.
    pub allowed: Vec<Bool>,
    /// Computing the enabled steps fails: a guard, connector guard or priority condition
    /// that must be evaluated cannot be.
    pub guard_error: Bool,
}

/// Which steps a step encoding may choose.
#[derive(Clone, Debug)]
pub struct StepFilter {
    pub interactions: Vec<bool>,
    pub internal: bool,
}

impl StepFilter {
    pub fn all(sys: &System) -> StepFilter {
        StepFilter {
            interactions: vec![true; sys.interactions.len()],
            internal: true,
        }
    }

    /// Only the interactions of connectors with role `role` (no internal transitions
    /// unless the role is progress).
    pub fn role(enc: &Encoding<'_>, role: Role) -> StepFilter {
        StepFilter {
            interactions: enc.roles.iter().map(|r| *r == role).collect(),
            internal: role == Role::Progress,
        }
    }
}

/// The choice variables of one step.
pub struct StepVars {
    /// The step's label: the interactions the filter lets through and that may be allowed,
    /// in order, then the components that may take an internal transition (as
    /// [`Encoding::step`] numbers them).
    pub sel: Choice,
    /// Per component: the transition it takes, if it takes part.
    pub tr: Vec<Choice>,
}

impl StepVars {
    pub fn fresh(sys: &System, prefix: &str) -> StepVars {
        StepVars {
            sel: Choice::fresh(
                &format!("{prefix}!sel"),
                sys.interactions.len() + sys.components.len(),
            ),
            tr: sys
                .components
                .iter()
                .enumerate()
                .map(|(c, comp)| {
                    let n = sys.atoms[comp.atom as usize].transitions.len();
                    Choice::fresh(&format!("{prefix}!tr{c}"), n)
                })
                .collect(),
        }
    }
}

/// One step from a frame.
pub struct StepEnc {
    /// The choice is a step enabled in the frame (after priorities), broadcast receivers
    /// included exactly when enabled.
    pub valid: Bool,
    /// Firing the chosen step fails (a range error).
    pub fire_err: Bool,
    /// The successor's slots.
    pub next: Vec<Sym>,
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

    pub fn enabling(&self, f: &Frame) -> Enabling {
        let sys = self.sys;
        let mut trans_en = Vec::with_capacity(sys.components.len());
        let mut port_en = Vec::with_capacity(sys.components.len());
        let mut port_here = Vec::with_capacity(sys.components.len());
        let mut port_err = Vec::with_capacity(sys.components.len());
        for comp in &sys.components {
            self.poll();
            let atom = &sys.atoms[comp.atom as usize];
            let loc = &f.slots[comp.slot as usize];
            let base = comp.slot + 1;
            let mut en = Vec::with_capacity(atom.transitions.len());
            let mut here = Vec::with_capacity(atom.transitions.len());
            let mut errs = Vec::with_capacity(atom.transitions.len());
            for t in &atom.transitions {
                let h = loc.eq_const(i64::from(t.from));
                let (val, err) = match (&t.guard, lit(&h)) {
                    (_, Some(false)) | (None, _) => (tt(), None),
                    (Some(g), _) => {
                        let s = translate(g, f, base);
                        (s.bool_term(), s.err)
                    }
                };
                en.push(and2(&h, &val));
                errs.push(err_when(&h, err));
                here.push(h);
            }
            let ports = &self.by_port[comp.atom as usize];
            port_en.push(
                ports
                    .iter()
                    .map(|ts| or(ts.iter().map(|&t| en[t as usize].clone())))
                    .collect::<Vec<_>>(),
            );
            port_here.push(
                ports
                    .iter()
                    .map(|ts| or(ts.iter().map(|&t| here[t as usize].clone())))
                    .collect::<Vec<_>>(),
            );
            port_err.push(
                ports
                    .iter()
                    .map(|ts| {
                        ts.iter()
                            .fold(None, |acc, &t| err_or(acc, errs[t as usize].clone()))
                    })
                    .collect::<Vec<_>>(),
            );
            trans_en.push(en);
        }
        let mut errors: Vec<Bool> = Vec::new();
        // internal transitions: every guard from the current location is evaluated
        for (c, comp) in sys.components.iter().enumerate() {
            let internal = self.by_port[comp.atom as usize].len() - 1;
            if let Some(e) = &port_err[c][internal] {
                errors.push(e.clone());
            }
        }
        let mut inter_en = Vec::with_capacity(sys.interactions.len());
        for (i, inter) in sys.interactions.iter().enumerate() {
            let port = |k: usize| {
                let p = inter.ports[k];
                (p.component as usize, p.port as usize)
            };
            let required: Vec<bool> = (0..inter.ports.len())
                .map(|k| self.required(i as u32, k as u32))
                .collect();
            // rejected on locations alone: nothing is evaluated
            let pre = and((0..inter.ports.len()).filter(|&k| required[k]).map(|k| {
                let (c, p) = port(k);
                port_here[c][p].clone()
            }));
            if lit(&pre) == Some(false) {
                inter_en.push(ff());
                continue;
            }
            // ports in order: each one's guards are evaluated once every required port
            // before it has an enabled transition
            let mut prefix = tt();
            let mut err: Option<Bool> = None;
            for (k, &req) in required.iter().enumerate() {
                let (c, p) = port(k);
                err = err_or(err, err_when(&prefix, port_err[c][p].clone()));
                if req {
                    prefix = and2(&prefix, &port_en[c][p]);
                }
            }
            let en = match &inter.guard {
                None => prefix,
                Some(g) => {
                    let s = translate(g, f, 0);
                    err = err_or(err, err_when(&prefix, s.err.clone()));
                    and2(&prefix, &s.bool_term())
                }
            };
            if let Some(e) = err_when(&pre, err) {
                errors.push(e);
            }
            inter_en.push(en);
        }
        let mut allowed = inter_en.clone();
        if !sys.priorities.is_empty() {
            let (suppressed, err) = self.priorities(f, &inter_en);
            if let Some(e) = err {
                errors.push(e);
            }
            for (i, a) in allowed.iter_mut().enumerate() {
                if let Some(s) = sys
                    .priority_graph()
                    .group_of(i as u32)
                    .map(|g| &suppressed[g as usize])
                {
                    if lit(a) != Some(false) {
                        *a = and2(a, &not(s));
                    }
                }
            }
        }
        Enabling {
            trans_en,
            port_en,
            inter_en,
            allowed,
            guard_error: or(errors),
        }
    }

    /// Priorities as bip-model's suppression search decides them (see its
    /// `suppression.rs`), over the groups of the priority graph, highest first: per group,
    /// whether a path of priorities whose `when`s hold leads up from it to an enabled
    /// interaction; and the condition under which a `when` that must be evaluated fails
    /// (docs/model.md, "Priorities": one is evaluated when its priority's low side is
    /// reached from an enabled interaction, through priorities whose `when`s hold and
    /// interactions that no path of priorities without `when` suppresses, and its high side
    /// leads to an enabled interaction through any priorities).
    fn priorities(&self, f: &Frame, inter_en: &[Bool]) -> (Vec<Bool>, Option<Bool>) {
        let sys = self.sys;
        let graph = sys.priority_graph();
        let groups = graph.groups() as usize;
        let en: Vec<Bool> = (0..groups as u32)
            .map(|z| or(graph.interactions(z).map(|i| inter_en[i as usize].clone())))
            .collect();
        let whens: Vec<Option<Sym>> = sys
            .priorities
            .iter()
            .map(|p| p.when.as_ref().map(|w| translate(w, f, 0)))
            .collect();
        // up from each group: through any priorities (`live`), through those whose `when`
        // holds where it is evaluated (`active`), through those without `when` (`plain`)
        let mut live = vec![ff(); groups];
        let mut active = vec![ff(); groups];
        let mut plain = vec![ff(); groups];
        let mut live_p: Vec<Option<Bool>> = vec![None; sys.priorities.len()];
        let mut pass: Vec<Option<Bool>> = vec![None; sys.priorities.len()];
        for &g in graph.order() {
            let mut any = Vec::new();
            let mut act = Vec::new();
            let mut pl = Vec::new();
            for &p in graph.below(g) {
                let highs = graph.high_groups(p);
                let lp = live_p[p as usize]
                    .get_or_insert_with(|| {
                        or(highs.clone().map(|z| {
                            let z = z as usize;
                            or([en[z].clone(), live[z].clone()])
                        }))
                    })
                    .clone();
                let carries = pass[p as usize]
                    .get_or_insert_with(|| match &whens[p as usize] {
                        None => tt(),
                        Some(w) => and2(&lp, &w.bool_term()),
                    })
                    .clone();
                any.push(lp);
                if whens[p as usize].is_none() {
                    pl.push(or(highs.clone().map(|z| {
                        let z = z as usize;
                        or([en[z].clone(), plain[z].clone()])
                    })));
                }
                let up = or(highs.map(|z| {
                    let z = z as usize;
                    or([en[z].clone(), active[z].clone()])
                }));
                act.push(and2(&carries, &up));
            }
            live[g as usize] = or(any);
            active[g as usize] = or(act);
            plain[g as usize] = or(pl);
        }
        // down from the enabled interactions, lowest group first: the groups reached
        // through priorities whose `when` holds and not suppressed by a plain path (the
        // search goes on from those only), and the `when`s evaluated on the way
        let mut reached = vec![ff(); groups];
        let mut low_reached: Vec<Option<Bool>> = vec![None; sys.priorities.len()];
        let mut err: Option<Bool> = None;
        for &g in graph.order().iter().rev() {
            let mut from = vec![en[g as usize].clone()];
            for &p in &self.groups_above[g as usize] {
                let r = self.low_reached(p, &reached, &mut low_reached);
                if let Some(carries) = &pass[p as usize] {
                    from.push(and2(&r, carries));
                }
            }
            reached[g as usize] = and2(&or(from), &not(&plain[g as usize]));
        }
        for (p, w) in whens.iter().enumerate() {
            let (Some(w), Some(lp)) = (w, &live_p[p]) else {
                continue;
            };
            let r = self.low_reached(p as u32, &reached, &mut low_reached);
            err = err_or(err, err_when(&and2(&r, lp), w.err.clone()));
        }
        (active, err)
    }

    /// Some group of priority `p`'s low side is reached.
    fn low_reached(&self, p: u32, reached: &[Bool], memo: &mut [Option<Bool>]) -> Bool {
        let graph = self.sys.priority_graph();
        memo[p as usize]
            .get_or_insert_with(|| or(graph.low_groups(p).map(|x| reached[x as usize].clone())))
            .clone()
    }

    /// No progress step is enabled in the frame (after priorities), and its enabled steps
    /// can be computed. Without `Time` and `Environment` connectors: no step is enabled.
    pub fn no_progress(&self, en: &Enabling) -> Bool {
        let mut parts = vec![not(&en.guard_error)];
        for (i, a) in en.allowed.iter().enumerate() {
            if self.roles[i] == Role::Progress {
                parts.push(not(a));
            }
        }
        for (c, comp) in self.sys.components.iter().enumerate() {
            self.poll();
            let internal = self.by_port[comp.atom as usize].len() - 1;
            parts.push(not(&en.port_en[c][internal]));
        }
        and(parts)
    }

    /// Some step of the given role is enabled (after priorities).
    pub fn some_allowed(&self, en: &Enabling, role: Role) -> Bool {
        or(en
            .allowed
            .iter()
            .enumerate()
            .filter(|(i, _)| self.roles[*i] == role)
            .map(|(_, a)| a.clone()))
    }

    /// One step from frame `f`, chosen by `v` among the steps `filter` allows.
    pub fn step(&self, f: &Frame, en: &Enabling, v: &StepVars, filter: &StepFilter) -> StepEnc {
        let sys = self.sys;
        let mut labels = Vec::new();
        let mut label_of_inter = vec![None; sys.interactions.len()];
        for (i, &ok) in filter.interactions.iter().enumerate() {
            if ok && lit(&en.allowed[i]) != Some(false) {
                label_of_inter[i] = Some(labels.len() as i64);
                labels.push(Label::Interaction(i as u32));
            }
        }
        let mut label_of_internal = vec![None; sys.components.len()];
        if filter.internal {
            for (c, comp) in sys.components.iter().enumerate() {
                let internal = self.by_port[comp.atom as usize].len() - 1;
                if lit(&en.port_en[c][internal]) != Some(false) {
                    label_of_internal[c] = Some(labels.len() as i64);
                    labels.push(Label::Internal {
                        component: c as u32,
                    });
                }
            }
        }
        if labels.is_empty() {
            return StepEnc {
                valid: ff(),
                fire_err: ff(),
                next: f.slots.clone(),
            };
        }
        let sel_is = |k: i64| v.sel.is(k);
        let choose = |c: u32, port: Option<u32>| -> Bool {
            or(self.transitions_on(c, port).iter().map(|&t| {
                and2(
                    &v.tr[c as usize].is(i64::from(t)),
                    &en.trans_en[c as usize][t as usize],
                )
            }))
        };
        let mut valid = vec![v.sel.below(labels.len() as u64)];
        for (i, inter) in sys.interactions.iter().enumerate() {
            let Some(k) = label_of_inter[i] else { continue };
            let mut cond = vec![en.allowed[i].clone()];
            for (pk, p) in inter.ports.iter().enumerate() {
                let pick = choose(p.component, Some(p.port));
                if self.required(i as u32, pk as u32) {
                    cond.push(pick);
                } else {
                    let joins = &en.port_en[p.component as usize][p.port as usize];
                    cond.push(implies(joins, &pick));
                }
            }
            valid.push(implies(&sel_is(k), &and(cond)));
        }
        for (c, k) in label_of_internal.iter().enumerate() {
            if let Some(k) = k {
                valid.push(implies(&sel_is(*k), &choose(c as u32, None)));
            }
        }
        // connector actions, on the frame
        let mut fire_errs = Vec::new();
        let mut conn_writes: Vec<Vec<(u32, Sym)>> = vec![Vec::new(); sys.interactions.len()];
        for (i, inter) in sys.interactions.iter().enumerate() {
            let Some(k) = label_of_inter[i] else { continue };
            if inter.action.is_empty() {
                continue;
            }
            let (written, err) = self.run_action(&inter.action, f, 0);
            if let Some(e) = err_when(&sel_is(k), err) {
                fire_errs.push(e);
            }
            conn_writes[i] = written;
        }
        let mut next = f.slots.clone();
        for (c, comp) in sys.components.iter().enumerate() {
            self.poll();
            let atom = &sys.atoms[comp.atom as usize];
            let mut joins = Vec::new();
            let mut ports: Vec<Option<u32>> = Vec::new();
            let mut pre = Overlay {
                base: f,
                written: Vec::new(),
            };
            for &(i, pk) in &self.inters_of[c] {
                let Some(k) = label_of_inter[i as usize] else {
                    continue;
                };
                let p = sys.interactions[i as usize].ports[pk as usize];
                let s = sel_is(k);
                if self.required(i, pk) {
                    joins.push(s.clone());
                } else {
                    joins.push(and2(&s, &en.port_en[c][p.port as usize]));
                }
                if !ports.contains(&Some(p.port)) {
                    ports.push(Some(p.port));
                }
                // the connector's action may write this component's variables
                for (slot, val) in &conn_writes[i as usize] {
                    if sys.component_of_slot(*slot) as usize == c {
                        let old = pre.slot(*slot);
                        pre.written.push((*slot, choose_sym(&s, val, &old)));
                    }
                }
            }
            if let Some(k) = label_of_internal[c] {
                joins.push(sel_is(k));
                ports.push(None);
            }
            // the variables before this component's own action
            for v in 0..atom.vars.len() as u32 {
                let slot = comp.var_slot(v);
                next[slot as usize] = pre.slot(slot);
            }
            if joins.is_empty() {
                continue;
            }
            let moves = or(joins);
            let tr = &v.tr[c];
            let relevant: Vec<u32> = ports
                .iter()
                .flat_map(|&p| self.transitions_on(c as u32, p).iter().copied())
                .collect();
            if relevant.is_empty() {
                continue;
            }
            // location: the chosen transition's target, bit by bit
            let slot = comp.slot as usize;
            let (_, hi) = self.kinds[slot].range();
            let w = width(i128::from(hi));
            let dest: Vec<Bool> = (0..w)
                .map(|k| {
                    or(relevant
                        .iter()
                        .filter(|&&t| atom.transitions[t as usize].to >> k & 1 == 1)
                        .map(|&t| tr.is(i64::from(t))))
                })
                .collect();
            let dest = Sym::of_bits(dest, 0, hi.into());
            next[slot] = choose_sym(&moves, &dest, &f.slots[slot]);
            // variables: the chosen transition's action, on the values the connector left
            let mut per_var: Vec<Vec<(i64, Sym)>> = vec![Vec::new(); atom.vars.len()];
            let mut errs = Vec::new();
            for &t in &relevant {
                let action = &atom.transitions[t as usize].action;
                if action.is_empty() {
                    continue;
                }
                let (written, err) = self.run_action(action, &pre, comp.slot + 1);
                let picked = tr.is(i64::from(t));
                if let Some(e) = err_when(&picked, err) {
                    errs.push(e);
                }
                for (s, val) in written {
                    per_var[(s - comp.slot - 1) as usize].push((i64::from(t), val));
                }
            }
            if let Some(e) = err_when(&moves, (!errs.is_empty()).then(|| or(errs))) {
                fire_errs.push(e);
            }
            for (vi, options) in per_var.into_iter().enumerate() {
                if options.is_empty() {
                    continue;
                }
                let slot = comp.var_slot(vi as u32) as usize;
                let before = next[slot].clone();
                let mut val = before.clone();
                for (t, x) in options.iter().rev() {
                    val = choose_sym(&tr.is(*t), x, &val);
                }
                next[slot] = choose_sym(&moves, &val, &before);
            }
        }
        StepEnc {
            valid: and(valid),
            fire_err: or(fire_errs),
            next,
        }
    }

    /// Runs assignments left to right on `view` (slot base `base` for local targets):
    /// the final value of each written slot, and the condition under which one fails
    /// (its value cannot be computed, or is outside the slot's range).
    fn run_action(
        &self,
        action: &[Assign],
        view: &dyn Slots,
        base: u32,
    ) -> (Vec<(u32, Sym)>, Option<Bool>) {
        let mut ov = Overlay {
            base: view,
            written: Vec::new(),
        };
        let mut err: Option<Bool> = None;
        let mut ok = tt();
        for a in action {
            let slot = match a.target {
                Target::Local(n) => base + n,
                Target::Slot(s) => s,
            };
            let v = translate(&a.value, &ov, base);
            let (lo, hi) = self.kinds[slot as usize].range();
            let (lo, hi) = (i128::from(lo), i128::from(hi));
            let out = (v.lo < lo || v.hi > hi).then(|| {
                let x = v.int_term();
                or([x.lt(lo as i64), x.gt(hi as i64)])
            });
            // an assignment is reached only if the ones before it did not fail
            err = err_or(err, err_when(&ok, err_or(v.err.clone(), out)));
            ok = and2(&ok, &not(&err_formula(&err)));
            let stored = match self.kinds[slot as usize] {
                SlotKind::Bool => Sym::of_bool(v.bool_term()),
                _ => {
                    let mut s = Sym::of_int(v.int_term(), v.lo.max(lo), v.hi.min(hi));
                    if s.lo > s.hi {
                        // always out of range: any value will do, the failure is recorded
                        s = Sym::int(lo as i64);
                    }
                    s
                }
            };
            ov.written.push((slot, stored));
        }
        let mut finals: Vec<(u32, Sym)> = Vec::new();
        for (slot, v) in ov.written.into_iter().rev() {
            if !finals.iter().any(|(s, _)| *s == slot) {
                finals.push((slot, v));
            }
        }
        finals.reverse();
        (finals, err)
    }

    /// `T(f, g)`: `g` is the successor of `f` by the step chosen by `v` among `filter`, and
    /// neither computing the enabled steps of `f` nor firing the step fails.
    pub fn transition(
        &self,
        f: &Frame,
        en: &Enabling,
        v: &StepVars,
        filter: &StepFilter,
        g: &Frame,
    ) -> Bool {
        let s = self.step(f, en, v, filter);
        let mut parts = vec![not(&en.guard_error), s.valid, not(&s.fire_err)];
        parts.extend(g.slots.iter().zip(&s.next).map(|(a, b)| sym_eq(a, b)));
        and(parts)
    }

    /// Some enabled step of `f` fails to fire, or its enabled steps cannot be computed:
    /// a range error (the step is chosen by `v`).
    pub fn range_error(&self, f: &Frame, en: &Enabling, v: &StepVars) -> Bool {
        let s = self.step(f, en, v, &StepFilter::all(self.sys));
        or([en.guard_error.clone(), and2(&s.valid, &s.fire_err)])
    }
}

/// `c ? a : b` on values of either kind (for the successor's slots).
fn choose_sym(c: &Bool, a: &Sym, b: &Sym) -> Sym {
    super::term::choose(c, a, b)
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
