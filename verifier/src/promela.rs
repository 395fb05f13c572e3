//! The system as a Promela model for SPIN, to cross-check verdicts and state counts.
//!
//! One process loops over every step of the system; each step (an internal transition, or
//! one combination of transitions of an interaction's participants) is one guarded
//! `d_step`, so SPIN stores no intermediate state and its reachable states correspond one to
//! one to bip's. The guard of a step is what `bip-model`'s step relation checks: the
//! participants' locations and transition guards, the connector guard, for a broadcast that
//! each absent receiver cannot join, and that no higher-priority interaction is enabled
//! where a priority applies. Actions run in bip's order (connector action, then each
//! participant's action in port order, then the moves), each assignment checked against its
//! variable's range with an `assert`, so a range error is an assertion violation in SPIN.
//!
//! A state with no enabled step blocks the loop: SPIN reports it as an invalid end state,
//! which is docs/model.md's deadlock. `DeadlockFree(terminal: e)` adds a step that is enabled
//! exactly in the blocked states where `e` holds and changes nothing, so those are not
//! reported. bip's finer deadlock definition with `Time` and `Environment` connectors has no
//! counterpart here; for such models compare state counts, not deadlock verdicts.
//! Invariants and reachability properties are written as comments.
//!
//! Not exported (an error says so): variables whose range does not fit in 32 bits, family
//! indices that depend on the state (`phil[x]`), and interactions with more than
//! [`MAX_ALTERNATIVES`] combinations of transitions.

use std::collections::HashSet;
use std::fmt::Write as _;

use bip_model::eval::Expr;
use bip_model::ops::{BinOp, QuantKind};
use bip_model::{PropertyKind, Role, System, Target};

/// Bound on the number of `d_step`s of one export.
pub const MAX_ALTERNATIVES: usize = 100_000;

#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum ExportError {
    #[error("cannot export to Promela: {0}")]
    Unsupported(String),
}

/// The Promela text of `system`.
pub fn to_promela(system: &System) -> Result<String, ExportError> {
    Exporter::new(system)?.run()
}

struct Exporter<'a> {
    sys: &'a System,
    /// Promela name of each slot.
    names: Vec<String>,
}

/// One transition of one participant in a step.
#[derive(Clone, Copy)]
struct Pick {
    component: u32,
    transition: u32,
}

impl<'a> Exporter<'a> {
    fn new(sys: &'a System) -> Result<Exporter<'a>, ExportError> {
        let mut names = Vec::with_capacity(sys.slot_count());
        let mut seen = HashSet::new();
        for slot in 0..sys.slot_count() as u32 {
            let c = sys.component_of_slot(slot);
            let comp = &sys.components[c as usize];
            let base = comp.name.replace('[', "_").replace(']', "");
            let name = if slot == comp.slot {
                format!("{base}__at")
            } else {
                let atom = sys.atom_of(c);
                format!(
                    "{base}__{}",
                    atom.vars[(slot - comp.slot - 1) as usize].name
                )
            };
            if !seen.insert(name.clone()) {
                return Err(ExportError::Unsupported(format!(
                    "two state variables would both be named `{name}`"
                )));
            }
            names.push(name);
        }
        Ok(Exporter { sys, names })
    }

    fn run(&self) -> Result<String, ExportError> {
        let sys = self.sys;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "/* system `{}`, exported by bip (bip export --promela). */",
            sys.name
        );
        let _ = writeln!(
            out,
            "/* One process, one d_step per step of the system: SPIN's states are bip's states. */\n"
        );
        let init = sys.initial_state();
        for (slot, name) in self.names.iter().enumerate() {
            let (lo, hi) = sys.slot_ranges()[slot];
            let ty = promela_type(lo, hi).ok_or_else(|| {
                ExportError::Unsupported(format!(
                    "`{}` ranges over {lo}..={hi}, more than Promela's 32-bit int",
                    sys.slot_name(slot as u32)
                ))
            })?;
            let _ = writeln!(out, "{ty} {name} = {};", init.slots()[slot]);
        }
        let _ = writeln!(out);
        for p in &sys.properties {
            match &p.kind {
                PropertyKind::Invariant(e) => {
                    let _ = writeln!(
                        out,
                        "/* invariant {}: {} */",
                        p.name,
                        self.expr(e, 0, &mut Vec::new())?
                    );
                }
                PropertyKind::Reachable(e) => {
                    let _ = writeln!(
                        out,
                        "/* reachable {}: {} */",
                        p.name,
                        self.expr(e, 0, &mut Vec::new())?
                    );
                }
                PropertyKind::DeadlockFree { .. } => {}
            }
        }
        if sys.connectors.iter().any(|c| c.role != Role::Progress) {
            let _ = writeln!(
                out,
                "/* This system has Time or Environment connectors: bip's deadlocks are finer than SPIN's invalid end states. */"
            );
        }
        let mut steps = Vec::new();
        self.internal_steps(&mut steps)?;
        for i in 0..sys.interactions.len() as u32 {
            self.interaction_steps(i, &mut steps)?;
            if steps.len() > MAX_ALTERNATIVES {
                return Err(ExportError::Unsupported(format!(
                    "more than {MAX_ALTERNATIVES} combinations of transitions"
                )));
            }
        }
        let terminal = sys.properties.iter().find_map(|p| match &p.kind {
            PropertyKind::DeadlockFree { terminal: Some(e) } => Some(e),
            _ => None,
        });
        let _ = writeln!(out, "\nactive proctype system() {{\n  do");
        for (label, guard, body) in &steps {
            let _ = writeln!(
                out,
                "  :: d_step {{ /* {label} */\n       {guard} ->\n       {body}\n     }}"
            );
        }
        if let Some(t) = terminal {
            let any: Vec<&str> = steps.iter().map(|(_, g, _)| g.as_str()).collect();
            let blocked = if any.is_empty() {
                "1".to_string()
            } else {
                format!("!({})", any.join(" ||\n         "))
            };
            let _ = writeln!(
                out,
                "  :: d_step {{ /* a terminal state (DeadlockFree's terminal condition): not a deadlock */\n       ({blocked}) && ({}) -> skip\n     }}",
                self.expr(t, 0, &mut Vec::new())?
            );
        }
        let _ = writeln!(out, "  od\n}}");
        Ok(out)
    }

    fn internal_steps(&self, steps: &mut Vec<(String, String, String)>) -> Result<(), ExportError> {
        let sys = self.sys;
        for (c, comp) in sys.components.iter().enumerate() {
            let atom = sys.atom_of(c as u32);
            for (t, tr) in atom.transitions.iter().enumerate() {
                if tr.port.is_some() {
                    continue;
                }
                let pick = Pick {
                    component: c as u32,
                    transition: t as u32,
                };
                let guard = self.pick_enabled(pick)?;
                let body = self.body(None, &[pick])?;
                steps.push((format!("{}.internal", comp.name), guard, body));
            }
        }
        Ok(())
    }

    /// The steps of interaction `i`: one per combination of its participants' transitions.
    fn interaction_steps(
        &self,
        i: u32,
        steps: &mut Vec<(String, String, String)>,
    ) -> Result<(), ExportError> {
        let sys = self.sys;
        let inter = &sys.interactions[i as usize];
        // per port, the choices: Some(transition), or None for a broadcast receiver that
        // does not join (allowed only where it cannot)
        let mut options: Vec<Vec<Option<Pick>>> = Vec::new();
        for (k, pr) in inter.ports.iter().enumerate() {
            let atom = sys.atom_of(pr.component);
            let mut opts: Vec<Option<Pick>> = atom
                .transitions
                .iter()
                .enumerate()
                .filter(|(_, t)| t.port == Some(pr.port))
                .map(|(t, _)| {
                    Some(Pick {
                        component: pr.component,
                        transition: t as u32,
                    })
                })
                .collect();
            if inter.trigger.is_some_and(|tr| tr as usize != k) {
                opts.push(None);
            }
            options.push(opts);
        }
        let count = options
            .iter()
            .map(Vec::len)
            .try_fold(1usize, |a, n| a.checked_mul(n));
        if count.is_none_or(|n| n > MAX_ALTERNATIVES) {
            return Err(ExportError::Unsupported(format!(
                "interaction {} has more than {MAX_ALTERNATIVES} combinations of transitions",
                inter.name
            )));
        }
        let mut common = Vec::new();
        if let Some(g) = &inter.guard {
            common.push(self.expr(g, 0, &mut Vec::new())?);
        }
        if let Some(s) = self.suppressed(i)? {
            common.push(format!("!({s})"));
        }
        let mut cursor = vec![0usize; options.len()];
        if options.iter().any(Vec::is_empty) {
            return Ok(());
        }
        loop {
            let mut conj = Vec::new();
            let mut picks = Vec::new();
            for (k, &c) in cursor.iter().enumerate() {
                match options[k][c] {
                    Some(p) => {
                        conj.push(self.pick_enabled(p)?);
                        picks.push(p);
                    }
                    None => {
                        let pr = inter.ports[k];
                        conj.push(format!("!({})", self.port_enabled(pr.component, pr.port)?));
                    }
                }
            }
            conj.extend(common.iter().cloned());
            let body = self.body(Some(i), &picks)?;
            steps.push((inter.name.clone(), conj.join(" && "), body));
            // odometer, last port fastest, as the step relation orders combinations
            let mut k = cursor.len();
            loop {
                if k == 0 {
                    return Ok(());
                }
                k -= 1;
                cursor[k] += 1;
                if cursor[k] < options[k].len() {
                    break;
                }
                cursor[k] = 0;
            }
        }
    }

    /// The condition for a participant's transition: its location and its guard.
    fn pick_enabled(&self, p: Pick) -> Result<String, ExportError> {
        let comp = &self.sys.components[p.component as usize];
        let t = &self.sys.atom_of(p.component).transitions[p.transition as usize];
        let at = format!("({} == {})", self.names[comp.slot as usize], t.from);
        Ok(match &t.guard {
            None => at,
            Some(g) => format!(
                "({at} && {})",
                self.expr(g, comp.slot + 1, &mut Vec::new())?
            ),
        })
    }

    /// True where some transition of the component on the port is enabled.
    fn port_enabled(&self, component: u32, port: u32) -> Result<String, ExportError> {
        let atom = self.sys.atom_of(component);
        let mut any = Vec::new();
        for (t, tr) in atom.transitions.iter().enumerate() {
            if tr.port == Some(port) {
                any.push(self.pick_enabled(Pick {
                    component,
                    transition: t as u32,
                })?);
            }
        }
        Ok(if any.is_empty() {
            "0".into()
        } else {
            format!("({})", any.join(" || "))
        })
    }

    /// True where interaction `i` is enabled before priorities.
    fn interaction_enabled(&self, i: u32) -> Result<String, ExportError> {
        let inter = &self.sys.interactions[i as usize];
        let mut conj = Vec::new();
        for (k, pr) in inter.ports.iter().enumerate() {
            if inter.trigger.is_some_and(|tr| tr as usize != k) {
                continue; // a receiver never blocks
            }
            conj.push(self.port_enabled(pr.component, pr.port)?);
        }
        if let Some(g) = &inter.guard {
            conj.push(self.expr(g, 0, &mut Vec::new())?);
        }
        Ok(if conj.is_empty() {
            "1".into()
        } else {
            format!("({})", conj.join(" && "))
        })
    }

    /// The condition under which interaction `i` is suppressed by a priority, if any rule
    /// can suppress it.
    fn suppressed(&self, i: u32) -> Result<Option<String>, ExportError> {
        let mut any = Vec::new();
        for rule in &self.sys.priorities {
            if !rule.low.contains(&i) {
                continue;
            }
            let mut highs = Vec::new();
            for h in rule.high.clone() {
                highs.push(self.interaction_enabled(h)?);
            }
            let mut conj = vec![format!("({})", highs.join(" || "))];
            for w in &rule.when {
                conj.push(self.expr(w, 0, &mut Vec::new())?);
            }
            any.push(format!("({})", conj.join(" && ")));
        }
        Ok(if any.is_empty() {
            None
        } else {
            Some(any.join(" || "))
        })
    }

    /// The effects of a step, in bip's order.
    fn body(&self, interaction: Option<u32>, picks: &[Pick]) -> Result<String, ExportError> {
        let sys = self.sys;
        let mut stmts = Vec::new();
        if let Some(i) = interaction {
            for a in &sys.interactions[i as usize].action {
                stmts.extend(self.assign(a, 0)?);
            }
        }
        for p in picks {
            let comp = &sys.components[p.component as usize];
            let t = &sys.atom_of(p.component).transitions[p.transition as usize];
            for a in &t.action {
                stmts.extend(self.assign(a, comp.slot + 1)?);
            }
        }
        for p in picks {
            let comp = &sys.components[p.component as usize];
            let t = &sys.atom_of(p.component).transitions[p.transition as usize];
            stmts.push(format!("{} = {}", self.names[comp.slot as usize], t.to));
        }
        if stmts.is_empty() {
            stmts.push("skip".into());
        }
        Ok(stmts.join(";\n       "))
    }

    fn assign(&self, a: &bip_model::Assign, base: u32) -> Result<Vec<String>, ExportError> {
        let slot = match a.target {
            Target::Local(n) => base + n,
            Target::Slot(s) => s,
        };
        let (lo, hi) = self.sys.slot_ranges()[slot as usize];
        let name = &self.names[slot as usize];
        // the value is checked before it is stored (a byte would wrap); expressions have no
        // side effects, so evaluating it twice is harmless
        let value = self.expr(&a.value, base, &mut Vec::new())?;
        Ok(vec![
            format!("assert({lo} <= {value} && {value} <= {hi})"),
            format!("{name} = {value}"),
        ])
    }

    /// An expression in Promela; quantifiers are unrolled, `bound` holds the values of the
    /// quantified variables of the enclosing quantifiers.
    fn expr(&self, e: &Expr, base: u32, bound: &mut Vec<i64>) -> Result<String, ExportError> {
        Ok(match e {
            Expr::Const(v) => format!("{v}"),
            Expr::Slot(s) => self.names[*s as usize].clone(),
            Expr::Local(n) => self.names[(base + n) as usize].clone(),
            Expr::At(s, loc) => format!("({} == {loc})", self.names[*s as usize]),
            Expr::Indexed(ix) => {
                let Some(i) = const_value(&ix.index, bound) else {
                    return Err(ExportError::Unsupported(
                        "a family index that depends on the state".into(),
                    ));
                };
                if i < 0 || i >= i64::from(ix.count) {
                    return Err(ExportError::Unsupported(format!(
                        "index {i} is outside family {}",
                        self.sys.families[ix.family as usize].name
                    )));
                }
                let slot =
                    ix.first_slot as usize + i as usize * ix.stride as usize + ix.offset as usize;
                match ix.at {
                    Some(loc) => format!("({} == {loc})", self.names[slot]),
                    None => self.names[slot].clone(),
                }
            }
            Expr::Bound(d) => format!("{}", bound.get(*d as usize).copied().unwrap_or(0)),
            Expr::Not(a) => format!("(!{})", self.expr(a, base, bound)?),
            Expr::Neg(a) => format!("(-{})", self.expr(a, base, bound)?),
            Expr::Binary(op, a, b) => {
                let (a, b) = (self.expr(a, base, bound)?, self.expr(b, base, bound)?);
                match op {
                    BinOp::Implies => format!("(!{a} || {b})"),
                    op => format!("({a} {} {b})", op.symbol()),
                }
            }
            Expr::Chain(first, rest) => {
                // operators of one precedence, left-associative as in Promela
                let mut out = format!("({}", self.expr(first, base, bound)?);
                for (op, x) in rest {
                    out.push_str(&format!(" {} {}", op.symbol(), self.expr(x, base, bound)?));
                }
                out + ")"
            }
            Expr::Cond(c, a, b) => format!(
                "({} -> {} : {})",
                self.expr(c, base, bound)?,
                self.expr(a, base, bound)?,
                self.expr(b, base, bound)?
            ),
            Expr::Quant(q) => {
                let mut parts = Vec::new();
                for i in q.lo..q.hi {
                    bound.truncate(q.depth as usize);
                    bound.push(i);
                    let body = self.expr(&q.body, base, bound)?;
                    parts.push(match q.kind {
                        QuantKind::Count => format!("({body} != 0)"),
                        _ => body,
                    });
                }
                bound.truncate(q.depth as usize);
                let (op, empty) = match q.kind {
                    QuantKind::Forall => (" && ", "1"),
                    QuantKind::Exists => (" || ", "0"),
                    QuantKind::Sum | QuantKind::Count => (" + ", "0"),
                };
                if parts.is_empty() {
                    empty.to_string()
                } else {
                    format!("({})", parts.join(op))
                }
            }
        })
    }
}

/// The value of an index expression that reads only constants and quantified variables.
fn const_value(e: &Expr, bound: &[i64]) -> Option<i64> {
    match e {
        Expr::Const(v) => Some(*v),
        Expr::Bound(d) => bound.get(*d as usize).copied(),
        Expr::Neg(a) => const_value(a, bound)?.checked_neg(),
        Expr::Not(a) => Some((const_value(a, bound)? == 0) as i64),
        Expr::Binary(op, a, b) => {
            bip_model::eval::binary(*op, const_value(a, bound)?, const_value(b, bound)?).ok()
        }
        Expr::Cond(c, a, b) => {
            if const_value(c, bound)? != 0 {
                const_value(a, bound)
            } else {
                const_value(b, bound)
            }
        }
        _ => None,
    }
}

/// The smallest Promela type holding `lo..=hi`.
fn promela_type(lo: i64, hi: i64) -> Option<&'static str> {
    if lo >= 0 && hi <= 1 {
        Some("bit")
    } else if lo >= 0 && hi <= 255 {
        Some("byte")
    } else if lo >= i64::from(i16::MIN) && hi <= i64::from(i16::MAX) {
        Some("short")
    } else if lo >= i64::from(i32::MIN) && hi <= i64::from(i32::MAX) {
        Some("int")
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn types_follow_ranges() {
        assert_eq!(promela_type(0, 1), Some("bit"));
        assert_eq!(promela_type(0, 200), Some("byte"));
        assert_eq!(promela_type(-1, 1), Some("short"));
        assert_eq!(promela_type(0, 100_000), Some("int"));
        assert_eq!(promela_type(0, 1 << 40), None);
    }
}
