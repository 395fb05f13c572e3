//! What is enabled in a frame: transitions, ports and interactions before and after
//! priorities, and the condition under which computing it fails, in the evaluation order
//! of `System::enabled_steps`.

use bip_model::Role;

use z3::ast::Bool;

use crate::symbolic::term::{and, and2, err_or, err_when, ff, lit, not, or, translate, tt, Sym};

use super::{Encoding, Frame};

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

impl Encoding<'_> {
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
}
