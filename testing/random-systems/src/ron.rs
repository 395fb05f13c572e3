//! Writing a generated system as a model file, so that it goes through the loader like
//! any user's model.

use crate::{Ex, Gen, Idx, Role};

impl Gen {
    pub fn to_ron(&self) -> String {
        let mut s = String::from("System(\n  name: \"generated\",\n  atoms: {\n");
        for (ai, a) in self.atoms.iter().enumerate() {
            let locs: Vec<String> = (0..a.locs).map(|l| format!("\"l{l}\"")).collect();
            let ports: Vec<String> = (0..a.ports).map(|p| format!("\"p{p}\"")).collect();
            s += &format!(
                "    \"A{ai}\": Atom(locations: [{}], initial: \"l{}\", ports: [{}],\n      vars: [",
                locs.join(", "),
                a.initial,
                ports.join(", ")
            );
            for (vi, v) in a.vars.iter().enumerate() {
                if v.is_bool {
                    s += &format!("(name: \"v{vi}\", ty: Bool, init: {}), ", v.init == 1);
                } else {
                    s += &format!(
                        "(name: \"v{vi}\", ty: Int({}, {}), init: {}), ",
                        v.lo, v.hi, v.init
                    );
                }
            }
            s += "],\n      transitions: [\n";
            for t in &a.trans {
                s += &format!("        (from: \"l{}\", to: \"l{}\"", t.from, t.to);
                if let Some(p) = t.port {
                    s += &format!(", port: \"p{p}\"");
                }
                if let Some(g) = &t.guard {
                    s += &format!(", guard: \"{}\"", self.show(g, None));
                }
                if !t.action.is_empty() {
                    let act: Vec<String> = t
                        .action
                        .iter()
                        .map(|(v, e)| format!("v{v} = {}", self.show(e, None)))
                        .collect();
                    s += &format!(", action: \"{}\"", act.join("; "));
                }
                s += "),\n";
            }
            s += "      ]),\n";
        }
        s += "  },\n  components: [\n";
        for (fi, f) in self.families.iter().enumerate() {
            s += &format!("    (name: \"f{fi}\", atom: \"A{}\"", f.atom);
            if let Some(c) = f.count {
                s += &format!(", count: {c}");
            }
            s += "),\n";
        }
        s += "  ],\n  connectors: [\n";
        for (ci, c) in self.conns.iter().enumerate() {
            let ports: Vec<String> = c
                .ports
                .iter()
                .map(|&(f, idx, p)| {
                    format!("\"{}.p{p}\"", self.show_comp(f, idx, c.forall.is_some()))
                })
                .collect();
            s += &format!("    (name: \"c{ci}\", ports: [{}]", ports.join(", "));
            if let Some(n) = c.forall {
                s += &format!(", forall: \"i in 0..{n}\"");
            }
            if let Some(t) = c.trigger {
                let (f, idx, p) = c.ports[t];
                s += &format!(
                    ", kind: Broadcast(trigger: \"{}.p{p}\")",
                    self.show_comp(f, idx, c.forall.is_some())
                );
            }
            if let Some(g) = &c.guard {
                s += &format!(", guard: \"{}\"", self.show(g, Some(c.forall.is_some())));
            }
            if !c.action.is_empty() {
                let act: Vec<String> = c
                    .action
                    .iter()
                    .map(|(f, idx, v, e)| {
                        format!(
                            "{}.v{v} = {}",
                            self.show_comp(*f, *idx, c.forall.is_some()),
                            self.show(e, Some(c.forall.is_some()))
                        )
                    })
                    .collect();
                s += &format!(", action: \"{}\"", act.join("; "));
            }
            if let Some(a) = &c.advance {
                s += &format!(", advance: \"{}\"", self.show(a, Some(c.forall.is_some())));
            }
            match c.role {
                Some(Role::Time) => s += ", role: Time",
                Some(Role::Environment) => s += ", role: Environment",
                None => {}
            }
            s += "),\n";
        }
        s += "  ],\n  priorities: [\n";
        for p in &self.prios {
            let name = |(c, i): (usize, Option<usize>)| match i {
                None => format!("c{c}"),
                Some(k) => format!("c{c}[{k}]"),
            };
            s += &format!("    (low: \"{}\", high: \"{}\"", name(p.low), name(p.high));
            if let Some(w) = &p.when {
                s += &format!(", when: \"{}\"", self.show(w, Some(false)));
            }
            s += "),\n";
        }
        s += "  ],\n";
        if let Some(p) = &self.props {
            let global = |e: &Ex| self.show(e, Some(false));
            let deadlock = match &p.terminal {
                Some(t) => format!("DeadlockFree(terminal: \"{}\")", global(t)),
                None => "DeadlockFree".into(),
            };
            let mut responses = String::new();
            if let Some((trigger, response, within)) = &p.response {
                let (t, r) = (global(trigger), global(response));
                responses += &format!(", LeadsTo(name: \"leads\", from: \"{t}\", to: \"{r}\")");
                if self.conns.iter().any(|c| c.role == Some(Role::Time)) {
                    responses += &format!(
                        ", Response(name: \"bounded\", trigger: \"{t}\", response: \"{r}\", within: {within})"
                    );
                }
            }
            s += &format!(
                "  properties: [{deadlock}, Invariant(name: \"inv\", expr: \"{}\"), \
                 Reachable(name: \"reach\", expr: \"{}\"){responses}],\n",
                global(&p.invariant),
                global(&p.reachable)
            );
        }
        s += ")\n";
        s
    }

    pub fn show_comp(&self, f: usize, idx: Idx, in_forall: bool) -> String {
        match (idx, self.families[f].count) {
            (Idx::Single, _) | (_, None) => format!("f{f}"),
            (Idx::Const(k), _) => format!("f{f}[{k}]"),
            (Idx::Shift(k), Some(c)) if in_forall => format!("f{f}[(i + {k}) % {c}]"),
            (Idx::Shift(k), Some(_)) => format!("f{f}[{k}]"),
        }
    }

    /// Fully parenthesised, so the printer never relies on precedence.
    pub fn show(&self, e: &Ex, global: Option<bool>) -> String {
        match e {
            Ex::Int(i) if *i < 0 => format!("({i})"),
            Ex::Int(i) => i.to_string(),
            Ex::Bool(b) => b.to_string(),
            Ex::Advance => "advance".into(),
            Ex::Local(v) => format!("v{v}"),
            Ex::Var(f, idx, v) => {
                format!("{}.v{v}", self.show_comp(*f, *idx, global == Some(true)))
            }
            Ex::At(f, idx, l) => format!("{}@l{l}", self.show_comp(*f, *idx, global == Some(true))),
            Ex::Not(a) => format!("!({})", self.show(a, global)),
            Ex::Bin(op, a, b) => {
                format!("({} {op} {})", self.show(a, global), self.show(b, global))
            }
            Ex::Ite(c, a, b) => format!(
                "({} ? {} : {})",
                self.show(c, global),
                self.show(a, global),
                self.show(b, global)
            ),
        }
    }
}
