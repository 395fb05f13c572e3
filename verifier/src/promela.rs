//! The system as a Promela model for SPIN, to cross-check verdicts and state counts.
//!
//! One process loops over the steps of the system: one guarded statement per interaction
//! and per internal transition. An interaction's guard is what `bip-model`'s step relation
//! checks: each participant that must join has an enabled transition on its port (its
//! location and transition guard), the connector guard holds, and no higher-priority
//! interaction is enabled where a priority applies (the higher ones' enabledness is one
//! macro each, `enabled_N`; whether some interaction above a group of interactions is
//! enabled, under the `when`s on the way, is one macro per group, `above_G`, written with
//! those of the groups above it, so the text grows with the priorities declared, not with
//! their closure). Inside, each participant's transition is chosen among its
//! enabled ones, every choice in the state before the step (into `hidden` variables, not
//! part of SPIN's state); a broadcast receiver that can take none does not join. Then the
//! actions run in bip's order (connector action, each participant's action in port order,
//! the moves), each assignment checked against its variable's range with an `assert`, so a
//! range error is an assertion violation. A statement with a real choice is `atomic` (SPIN
//! explores every choice and stores no state inside it), one without is a `d_step`: either
//! way SPIN's stored states are bip's states.
//!
//! A state with no enabled step blocks the loop: SPIN reports it as an invalid end state,
//! which is docs/model.md's deadlock. `DeadlockFree(terminal: e)` adds a step that is enabled
//! exactly in the blocked states where `e` holds and changes nothing, so those are not
//! reported. bip's finer deadlock definition with `Time` and `Environment` connectors has no
//! counterpart here; for such models compare state counts, not deadlock verdicts.
//! Invariants are assertions in a second process, `properties`, that loops at an `end`
//! label waiting for a state that breaks one (its one location adds no state); a `Reachable`
//! property is an assertion that fails where it holds, switched on by `spin -DREACH_name`
//! (its witness ends SPIN's search, so each is checked in a run of its own).
//!
//! Not exported (an error says so): variables whose range does not fit in 32 bits, family
//! indices that depend on the state (`phil[x]`), and quantifiers that unroll into more than
//! [`MAX_QUANTIFIER_TERMS`] terms.

use std::cell::Cell;
use std::collections::HashSet;
use std::fmt::Write as _;

use bip_model::eval::Expr;
use bip_model::ops::{BinOp, QuantKind};
use bip_model::{PropertyKind, Role, System, Target};

/// Bound on the quantifier terms of one export, all quantifiers together.
pub const MAX_QUANTIFIER_TERMS: u64 = 1_000_000;

/// Bound on the terms of the condition under which one interaction is suppressed by
/// priorities, once SPIN's preprocessor has expanded the `above_G` macros in it (where
/// `when`s lie above, a priority graph with many paths between two groups expands each).
const MAX_SUPPRESSION_TERMS: u64 = 100_000;

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
    /// Quantifier terms written so far (Promela has no quantifiers: each is spelt out).
    terms: Cell<u64>,
}

/// One transition of one participant in a step.
#[derive(Clone, Copy)]
struct Pick {
    component: u32,
    transition: u32,
}

impl<'a> Exporter<'a> {
    fn new(sys: &'a System) -> Result<Exporter<'a>, ExportError> {
        if sys.has_advance() {
            return Err(ExportError::Unsupported(
                "a time step of more than one unit (`advance`)".into(),
            ));
        }
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
        Ok(Exporter {
            sys,
            names,
            terms: Cell::new(0),
        })
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
            "/* One process, one atomic statement per interaction (its participants' choices inside)\n   and per internal transition: SPIN's stored states are bip's states. Compile with\n   `spin -o2 -a`. Invariants are assertions of the process `properties`; a reachability\n   property is checked with `spin -DREACH_<name>` (an assertion that fails where it holds). */\n"
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
        // the transition each participant takes, chosen before any action runs; hidden:
        // not part of SPIN's state
        let widest = sys
            .interactions
            .iter()
            .map(|i| i.ports.len())
            .max()
            .unwrap_or(0);
        let most = sys
            .atoms
            .iter()
            .map(|a| a.transitions.len() as i64)
            .max()
            .unwrap_or(0);
        if widest > 0 {
            // SPIN hides no `bit` variable: a byte at least
            let ty = promela_type(0, most.max(2)).unwrap_or("int");
            let chosen: Vec<String> = (0..widest).map(|k| format!("chosen_{k}")).collect();
            let _ = writeln!(out, "hidden {ty} {};", chosen.join(", "));
        }
        let _ = writeln!(out);
        if sys.connectors.iter().any(|c| c.role != Role::Progress) {
            let _ = writeln!(
                out,
                "/* This system has Time or Environment connectors: bip's deadlocks are finer than SPIN's invalid end states. */"
            );
        }
        // each interaction's enabledness before priorities, for the priorities that read it
        let mut highs = vec![false; sys.interactions.len()];
        for rule in &sys.priorities {
            for h in rule.high.clone() {
                highs[h as usize] = true;
            }
        }
        for (i, used) in highs.iter().enumerate() {
            if *used {
                let _ = writeln!(
                    out,
                    "#define enabled_{i} {} /* {} */",
                    self.interaction_enabled(i as u32)?,
                    sys.interactions[i].name
                );
            }
        }
        let above = self.priority_macros(&mut out)?;
        let mut guards = Vec::new();
        let mut statements = Vec::new();
        self.internal_steps(&mut guards, &mut statements)?;
        for i in 0..sys.interactions.len() as u32 {
            self.interaction_step(i, &above, &mut guards, &mut statements)?;
        }
        for (k, g) in guards.iter().enumerate() {
            let _ = writeln!(out, "#define step_{k} {g}");
        }
        let terminal = sys.properties.iter().find_map(|p| match &p.kind {
            PropertyKind::DeadlockFree { terminal: Some(e) } => Some(e),
            _ => None,
        });
        let _ = writeln!(out, "\nactive proctype system() {{\n  do");
        for s in &statements {
            let _ = writeln!(out, "{s}");
        }
        if let Some(t) = terminal {
            let any: Vec<String> = (0..guards.len()).map(|k| format!("step_{k}")).collect();
            let blocked = if any.is_empty() {
                "1".to_string()
            } else {
                format!("!({})", any.join(" || "))
            };
            let _ = writeln!(
                out,
                "  :: d_step {{ /* a terminal state (DeadlockFree's terminal condition): not a deadlock */\n       ({blocked}) && ({}) -> skip\n     }}",
                self.expr(t, 0, &mut Vec::new())?
            );
        }
        let _ = writeln!(out, "  od\n}}");
        self.properties(&mut out)?;
        Ok(out)
    }

    /// The invariants as assertions, and the reachability properties as assertions that
    /// fail where they hold (each under its `REACH_` switch, since a witness ends SPIN's
    /// search), in a second process whose one location SPIN does not count as a state
    /// of its own: its guards wait for a state that breaks a property, in every state, and
    /// a check that fails comes back to that location (`pan -c0` goes on with the same
    /// states).
    fn properties(&self, out: &mut String) -> Result<(), ExportError> {
        let mut invariants = Vec::new();
        let mut reachables = Vec::new();
        let mut defines = Vec::new();
        for p in &self.sys.properties {
            let id = identifier(&p.name);
            match &p.kind {
                PropertyKind::Invariant(e) => {
                    let m = format!("invariant_{id}");
                    defines.push(format!(
                        "/* invariant {} */\n#define {m} {}",
                        p.name,
                        self.expr(e, 0, &mut Vec::new())?
                    ));
                    invariants.push(format!("     :: atomic {{ !{m} -> assert({m}) }}"));
                }
                PropertyKind::Reachable(e) => {
                    let m = format!("reachable_{id}");
                    defines.push(format!(
                        "/* reachable {}: with `spin -DREACH_{id}`, a state where it holds is an assertion violation (the witness) */\n#define {m} {}\n#ifdef REACH_{id}\n#define REACHABILITY_RUN\n#endif",
                        p.name,
                        self.expr(e, 0, &mut Vec::new())?
                    ));
                    reachables.push(format!(
                        "#ifdef REACH_{id}\n     :: atomic {{ {m} -> assert(!{m}) }}\n#endif"
                    ));
                }
                PropertyKind::DeadlockFree { .. } => {}
                PropertyKind::Response { .. } => {
                    let _ = writeln!(
                        out,
                        "/* response property {}: not exported (`bip verify` checks it) */",
                        p.name
                    );
                }
            }
        }
        if invariants.is_empty() && reachables.is_empty() {
            return Ok(());
        }
        let _ = writeln!(out);
        for d in &defines {
            let _ = writeln!(out, "{d}");
        }
        let mut options = Vec::new();
        if !invariants.is_empty() {
            // a run for a witness checks only that witness
            options.push(format!(
                "#ifndef REACHABILITY_RUN\n{}\n#endif",
                invariants.join("\n")
            ));
        }
        options.extend(reachables);
        let _ = writeln!(
            out,
            "\nactive proctype properties() {{\nend: do\n{}\n     :: false /* no property switched on */\n   od\n}}",
            options.join("\n")
        );
        Ok(())
    }

    fn internal_steps(
        &self,
        guards: &mut Vec<String>,
        statements: &mut Vec<String>,
    ) -> Result<(), ExportError> {
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
                let k = guards.len();
                guards.push(self.pick_enabled(pick)?);
                let mut stmts = self.actions(pick)?;
                stmts.push(self.moves(pick));
                statements.push(format!(
                    "  :: d_step {{ /* {}.internal */\n       step_{k} ->\n       {}\n     }}",
                    comp.name,
                    stmts.join(";\n       ")
                ));
            }
        }
        Ok(())
    }

    /// The statement of interaction `i`: its guard (each participant can take a
    /// transition on its port, the connector guard, no priority suppresses it), then the
    /// choice of each participant's transition among those enabled (all choices are made in
    /// the state before the step, as the step relation makes them), then the actions in
    /// bip's order and the moves. Where a participant has several transitions on its port
    /// the choice is nondeterministic, so the statement is `atomic` (SPIN explores every
    /// choice and stores no state inside); otherwise it is a `d_step`.
    fn interaction_step(
        &self,
        i: u32,
        above: &[u64],
        guards: &mut Vec<String>,
        statements: &mut Vec<String>,
    ) -> Result<(), ExportError> {
        let sys = self.sys;
        let inter = &sys.interactions[i as usize];
        let mut options: Vec<Vec<Pick>> = Vec::new();
        for pr in &inter.ports {
            let atom = sys.atom_of(pr.component);
            options.push(
                atom.transitions
                    .iter()
                    .enumerate()
                    .filter(|(_, t)| t.port == Some(pr.port))
                    .map(|(t, _)| Pick {
                        component: pr.component,
                        transition: t as u32,
                    })
                    .collect(),
            );
        }
        let receiver = |k: usize| inter.trigger.is_some_and(|tr| tr as usize != k);
        if options
            .iter()
            .enumerate()
            .any(|(k, o)| o.is_empty() && !receiver(k))
        {
            return Ok(()); // a participant without a transition on its port: never enabled
        }
        let mut guard = vec![self.interaction_enabled(i)?];
        if let Some(s) = self.suppressed(i, above)? {
            guard.push(format!("!{s}"));
        }
        let k = guards.len();
        guards.push(format!("({})", guard.join(" && ")));
        let nondeterministic = options.iter().any(|o| o.len() > 1);
        let mut stmts = Vec::new();
        for (k, opts) in options.iter().enumerate() {
            if opts.len() == 1 && !receiver(k) {
                continue; // no choice: the guard says it is enabled
            }
            let mut alts = Vec::new();
            for (n, p) in opts.iter().enumerate() {
                alts.push(format!(":: {} -> chosen_{k} = {n}", self.pick_enabled(*p)?));
            }
            if receiver(k) {
                // a receiver that can take no transition does not join
                alts.push(format!(":: else -> chosen_{k} = {}", opts.len()));
            }
            stmts.push(format!("if {} fi", alts.join(" ")));
        }
        for a in &inter.action {
            stmts.extend(self.assign(a, 0)?);
        }
        let fixed = |k: usize| opts_fixed(&options[k], receiver(k));
        for (k, opts) in options.iter().enumerate() {
            if let Some(p) = fixed(k) {
                stmts.extend(self.actions(p)?);
                continue;
            }
            let mut alts = Vec::new();
            for (n, p) in opts.iter().enumerate() {
                let body = self.actions(*p)?;
                if !body.is_empty() {
                    alts.push(format!(":: chosen_{k} == {n} -> {}", body.join("; ")));
                }
            }
            if !alts.is_empty() {
                stmts.push(format!("if {} :: else fi", alts.join(" ")));
            }
        }
        for (k, opts) in options.iter().enumerate() {
            if let Some(p) = fixed(k) {
                stmts.push(self.moves(p));
                continue;
            }
            let alts: Vec<String> = opts
                .iter()
                .enumerate()
                .map(|(n, p)| format!(":: chosen_{k} == {n} -> {}", self.moves(*p)))
                .collect();
            stmts.push(format!("if {} :: else fi", alts.join(" ")));
        }
        let kind = if nondeterministic { "atomic" } else { "d_step" };
        statements.push(format!(
            "  :: {kind} {{ /* {} */\n       step_{k} ->\n       {}\n     }}",
            inter.name,
            stmts.join(";\n       ")
        ));
        Ok(())
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

    /// The macros of the priorities. Per group of interactions on a priority's high side,
    /// `group_G`: one of its interactions is enabled. Per group with priorities above it,
    /// `above_G`: a path of priorities whose `when`s hold leads up from it to an enabled
    /// interaction (the closure of docs/model.md, never listed). Where no `when` lies
    /// above the group, that is some group it reaches enabled: `above_G` lists those
    /// groups once each (SPIN's preprocessor would expand a nested form once per path,
    /// and a GenoM layer's priorities have many). Otherwise `above_G` is, per priority
    /// above it, its `when` and some group of its high side enabled or with its own
    /// `above_` holding; by induction on the (acyclic) graph this is the closure. Returns,
    /// per group, how many terms its `above_` macro expands into (saturating).
    fn priority_macros(&self, out: &mut String) -> Result<Vec<u64>, ExportError> {
        let sys = self.sys;
        let graph = sys.priority_graph();
        let groups = graph.groups() as usize;
        let mut high_side = vec![false; groups];
        for p in 0..sys.priorities.len() as u32 {
            for z in graph.high_groups(p) {
                high_side[z as usize] = true;
            }
        }
        for &g in graph.order() {
            if high_side[g as usize] {
                let any: Vec<String> = graph
                    .interactions(g)
                    .map(|h| format!("enabled_{h}"))
                    .collect();
                let _ = writeln!(out, "#define group_{g} ({})", any.join(" || "));
            }
        }
        // highest groups first (the compiler rejects cycles, so every group is in the
        // order): whether a `when` lies above, and the expanded sizes
        let size = |z: u32| graph.interactions(z).len() as u64;
        let mut plain = vec![true; groups];
        let mut above = vec![0u64; groups];
        let mut reached = vec![u32::MAX; groups];
        for &g in graph.order() {
            let below = graph.below(g);
            if below.is_empty() {
                continue;
            }
            plain[g as usize] = below.iter().all(|&p| {
                sys.priorities[p as usize].when.is_none()
                    && graph.high_groups(p).all(|z| plain[z as usize])
            });
            let mut any = Vec::new();
            let mut terms = 0u64;
            if plain[g as usize] {
                // the groups reached, each once
                let mut stack = vec![g];
                while let Some(x) = stack.pop() {
                    for &p in graph.below(x) {
                        for z in graph.high_groups(p) {
                            if reached[z as usize] != g {
                                reached[z as usize] = g;
                                stack.push(z);
                                any.push(format!("group_{z}"));
                                terms = terms.saturating_add(size(z));
                            }
                        }
                    }
                }
            } else {
                for &p in below {
                    let mut highs = Vec::new();
                    for z in graph.high_groups(p) {
                        terms = terms.saturating_add(size(z));
                        if graph.below(z).is_empty() {
                            highs.push(format!("group_{z}"));
                        } else {
                            terms = terms.saturating_add(above[z as usize]);
                            highs.push(format!("group_{z} || above_{z}"));
                        }
                    }
                    let highs = format!("({})", highs.join(" || "));
                    any.push(match &sys.priorities[p as usize].when {
                        Some(w) => {
                            terms = terms.saturating_add(1);
                            format!("({} && {highs})", self.expr(w, 0, &mut Vec::new())?)
                        }
                        None => highs,
                    });
                }
            }
            above[g as usize] = terms;
            if terms <= MAX_SUPPRESSION_TERMS {
                let _ = writeln!(out, "#define above_{g} ({})", any.join(" || "));
            }
        }
        Ok(above)
    }

    /// The condition under which interaction `i` is suppressed by priorities, if any can
    /// suppress it: its group's `above_` macro. `above` holds the macros' expanded sizes.
    fn suppressed(&self, i: u32, above: &[u64]) -> Result<Option<String>, ExportError> {
        let graph = self.sys.priority_graph();
        let Some(g) = graph.group_of(i) else {
            return Ok(None);
        };
        if graph.below(g).is_empty() {
            return Ok(None);
        }
        if above[g as usize] > MAX_SUPPRESSION_TERMS {
            return Err(ExportError::Unsupported(format!(
                "the priorities above {} expand into more than {MAX_SUPPRESSION_TERMS} \
                 terms (a path of priorities is written out for each way up)",
                self.sys.interactions[i as usize].name
            )));
        }
        Ok(Some(format!("above_{g}")))
    }

    /// A participant's transition's action, as statements.
    fn actions(&self, p: Pick) -> Result<Vec<String>, ExportError> {
        let comp = &self.sys.components[p.component as usize];
        let t = &self.sys.atom_of(p.component).transitions[p.transition as usize];
        let mut stmts = Vec::new();
        for a in &t.action {
            stmts.extend(self.assign(a, comp.slot + 1)?);
        }
        Ok(stmts)
    }

    /// A participant's move to its transition's target.
    fn moves(&self, p: Pick) -> String {
        let comp = &self.sys.components[p.component as usize];
        let t = &self.sys.atom_of(p.component).transitions[p.transition as usize];
        format!("{} = {}", self.names[comp.slot as usize], t.to)
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
            // without any `advance` (refused above), every time step is one unit
            Expr::Advance => "1".into(),
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
                let width = q.hi.saturating_sub(q.lo).max(0) as u64;
                let terms = self.terms.get().saturating_add(width);
                if terms > MAX_QUANTIFIER_TERMS {
                    return Err(ExportError::Unsupported(format!(
                        "the quantifiers unroll into more than {MAX_QUANTIFIER_TERMS} terms (Promela has no quantifiers: each is written out term by term)"
                    )));
                }
                self.terms.set(terms);
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

/// The one transition a participant takes without a choice: the only one on its port, for
/// a participant that must join.
fn opts_fixed(options: &[Pick], receiver: bool) -> Option<Pick> {
    match options {
        [only] if !receiver => Some(*only),
        _ => None,
    }
}

/// A Promela identifier for a property's name.
fn identifier(name: &str) -> String {
    name.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
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
