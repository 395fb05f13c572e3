//! One step from a frame: the selector and transition variables, the successor's terms,
//! the condition that the choice is an enabled step and the condition that firing it
//! fails.

use std::collections::HashMap;

use bip_model::{Assign, Label, Role, System, Target};

use z3::ast::Bool;

use crate::symbolic::term::{
    and, and2, err_formula, err_or, err_when, ff, implies, lit, not, or, translate,
    translate_in_step, tt, width, Choice, Slots, Sym,
};

use super::{sym_eq, Enabling, Encoding, Frame, SlotKind};

/// A frame seen through assignments made so far (an action in progress): per slot
/// written, its last value and the position of its last assignment, found in constant time
/// (an action may be long).
struct Overlay<'a> {
    base: &'a dyn Slots,
    written: HashMap<u32, (usize, Sym)>,
}

impl Slots for Overlay<'_> {
    fn slot(&self, slot: u32) -> Sym {
        match self.written.get(&slot) {
            Some((_, v)) => v.clone(),
            None => self.base.slot(slot),
        }
    }
}

/// Assignments of one action run between two polls of the run's limits.
const POLL_ASSIGNMENTS: usize = 256;

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
    /// The labels the selector numbers: `sel == k` chooses `labels[k]`.
    pub labels: Vec<Label>,
}

impl Encoding<'_> {
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
                labels,
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
            // a time step's advance, evaluated on the frame it leaves: at least 1
            let advance = inter.advance.as_ref().map(|e| {
                let a = translate(e, f, 0);
                let below = (a.lo < 1).then(|| a.int_term().lt(1i64));
                if let Some(e) = err_when(&sel_is(k), err_or(a.err.clone(), below)) {
                    fire_errs.push(e);
                }
                a
            });
            if inter.action.is_empty() {
                continue;
            }
            let (written, err) = self.run_action(&inter.action, f, 0, advance.as_ref());
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
                written: HashMap::new(),
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
                        pre.written.insert(*slot, (0, choose_sym(&s, val, &old)));
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
                let (written, err) = self.run_action(action, &pre, comp.slot + 1, None);
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
            labels,
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
        advance: Option<&Sym>,
    ) -> (Vec<(u32, Sym)>, Option<Bool>) {
        let mut ov = Overlay {
            base: view,
            written: HashMap::new(),
        };
        let mut err: Option<Bool> = None;
        let mut ok = tt();
        for (k, a) in action.iter().enumerate() {
            if k % POLL_ASSIGNMENTS == POLL_ASSIGNMENTS - 1 {
                self.poll();
            }
            let slot = match a.target {
                Target::Local(n) => base + n,
                Target::Slot(s) => s,
            };
            let v = translate_in_step(&a.value, &ov, base, advance);
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
            ov.written.insert(slot, (k, stored));
        }
        // in the order of each slot's last assignment
        let mut finals: Vec<(usize, u32, Sym)> = ov
            .written
            .into_iter()
            .map(|(slot, (k, v))| (k, slot, v))
            .collect();
        finals.sort_unstable_by_key(|&(k, _, _)| k);
        (
            finals.into_iter().map(|(_, slot, v)| (slot, v)).collect(),
            err,
        )
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
        self.transition_labelled(f, en, v, filter, g).0
    }

    /// [`Encoding::transition`], with the labels `v.sel` numbers (for observers of steps).
    pub fn transition_labelled(
        &self,
        f: &Frame,
        en: &Enabling,
        v: &StepVars,
        filter: &StepFilter,
        g: &Frame,
    ) -> (Bool, Vec<Label>) {
        let s = self.step(f, en, v, filter);
        let mut parts = vec![not(&en.guard_error), s.valid, not(&s.fire_err)];
        parts.extend(g.slots.iter().zip(&s.next).map(|(a, b)| sym_eq(a, b)));
        (and(parts), s.labels)
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
    crate::symbolic::term::choose(c, a, b)
}
