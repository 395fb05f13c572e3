//! Random small systems, generated as plain Rust data and written out as RON models: the
//! shared generator of the property tests that compare the step relation with a reference
//! interpreter (`reference.rs`) and the incremental enabled set with the full relation
//! (`incremental.rs`).

#![allow(dead_code)]

// --------------------------------------------------------------------------------------
// A tiny deterministic random source, so that one `u64` seed describes a whole system.

pub use bip_model::Rng;

// --------------------------------------------------------------------------------------
// The generated system.

#[derive(Clone, Debug)]
pub enum Ex {
    Int(i64),
    Bool(bool),
    /// A variable of the atom itself (atom guards and actions).
    Local(usize),
    /// A variable of a component: family, index, variable.
    Var(usize, Idx, usize),
    /// A component at a location: family, index, location.
    At(usize, Idx, usize),
    Not(Box<Ex>),
    Bin(&'static str, Box<Ex>, Box<Ex>),
    Ite(Box<Ex>, Box<Ex>, Box<Ex>),
}

/// How a connector names a family member: a constant, or `(i + k) % count` in a `forall`.
#[derive(Clone, Copy, Debug)]
pub enum Idx {
    Single,
    Const(usize),
    Shift(usize),
}

#[derive(Clone, Debug)]
pub struct Var {
    pub lo: i64,
    pub hi: i64,
    pub is_bool: bool,
    pub init: i64,
}

#[derive(Clone, Debug)]
pub struct Tr {
    pub from: usize,
    pub port: Option<usize>,
    pub to: usize,
    pub guard: Option<Ex>,
    pub action: Vec<(usize, Ex)>,
}

#[derive(Clone, Debug)]
pub struct Atom {
    pub locs: usize,
    pub initial: usize,
    pub ports: usize,
    pub vars: Vec<Var>,
    pub trans: Vec<Tr>,
}

#[derive(Clone, Debug)]
pub struct Family {
    pub atom: usize,
    pub count: Option<usize>,
}

#[derive(Clone, Debug)]
pub struct Conn {
    /// `forall i in 0..n`
    pub forall: Option<usize>,
    /// (family, index, port)
    pub ports: Vec<(usize, Idx, usize)>,
    /// the trigger's position in `ports`, for a broadcast
    pub trigger: Option<usize>,
    pub guard: Option<Ex>,
    /// (family, index, variable) = value
    pub action: Vec<(usize, Idx, usize, Ex)>,
}

#[derive(Clone, Debug)]
pub struct Prio {
    pub low: (usize, Option<usize>),
    pub high: (usize, Option<usize>),
    pub when: Option<Ex>,
}

#[derive(Clone, Debug)]
pub struct Gen {
    pub atoms: Vec<Atom>,
    pub families: Vec<Family>,
    pub conns: Vec<Conn>,
    pub prios: Vec<Prio>,
}

pub fn gen_int(
    r: &mut Rng,
    depth: u32,
    leaf: &mut dyn FnMut(&mut Rng, bool) -> Option<Ex>,
    arith: &[&'static str],
) -> Ex {
    if depth == 0 || r.chance(40) {
        if let Some(e) = leaf(r, false) {
            if r.chance(70) {
                return e;
            }
        }
        return Ex::Int(r.range(-2, 4));
    }
    match r.below(3) {
        0 => {
            let c = gen_bool(r, depth - 1, leaf, arith);
            let a = gen_int(r, depth - 1, leaf, arith);
            let b = gen_int(r, depth - 1, leaf, arith);
            Ex::Ite(Box::new(c), Box::new(a), Box::new(b))
        }
        _ => {
            let op = arith[r.below(arith.len())];
            let a = gen_int(r, depth - 1, leaf, arith);
            let b = gen_int(r, depth - 1, leaf, arith);
            Ex::Bin(op, Box::new(a), Box::new(b))
        }
    }
}

pub fn gen_bool(
    r: &mut Rng,
    depth: u32,
    leaf: &mut dyn FnMut(&mut Rng, bool) -> Option<Ex>,
    arith: &[&'static str],
) -> Ex {
    if depth == 0 || r.chance(30) {
        if let Some(e) = leaf(r, true) {
            if r.chance(80) {
                return e;
            }
        }
        return Ex::Bool(r.chance(70));
    }
    match r.below(5) {
        0 => Ex::Not(Box::new(gen_bool(r, depth - 1, leaf, arith))),
        1 | 2 => {
            let op = ["<", "<=", "==", "!="][r.below(4)];
            let a = gen_int(r, depth - 1, leaf, arith);
            let b = gen_int(r, depth - 1, leaf, arith);
            Ex::Bin(op, Box::new(a), Box::new(b))
        }
        _ => {
            let op = ["&&", "||", "=>"][r.below(3)];
            let a = gen_bool(r, depth - 1, leaf, arith);
            let b = gen_bool(r, depth - 1, leaf, arith);
            Ex::Bin(op, Box::new(a), Box::new(b))
        }
    }
}

/// Guards use no division (their evaluation order is an implementation choice, so they
/// must not fail); actions may divide and leave ranges: those range errors must agree.
pub const GUARD_OPS: &[&str] = &["+", "-", "*"];
pub const ACTION_OPS: &[&str] = &["+", "-", "*", "/", "%"];

pub fn generate(seed: u64) -> Gen {
    let mut r = Rng(seed);
    let mut atoms = Vec::new();
    for _ in 0..1 + r.below(3) {
        let locs = 1 + r.below(3);
        let ports = 1 + r.below(3);
        let vars: Vec<Var> = (0..r.below(3))
            .map(|_| {
                if r.chance(30) {
                    Var {
                        lo: 0,
                        hi: 1,
                        is_bool: true,
                        init: r.range(0, 1),
                    }
                } else {
                    let lo = r.range(-1, 1);
                    let hi = lo + r.range(0, 3);
                    Var {
                        lo,
                        hi,
                        is_bool: false,
                        init: r.range(lo, hi),
                    }
                }
            })
            .collect();
        let mut trans = Vec::new();
        for _ in 0..r.below(7) {
            let mut leaf = |r: &mut Rng, want_bool: bool| -> Option<Ex> {
                let candidates: Vec<usize> = (0..vars.len())
                    .filter(|&v| vars[v].is_bool == want_bool)
                    .collect();
                (!candidates.is_empty()).then(|| Ex::Local(candidates[r.below(candidates.len())]))
            };
            let guard = r
                .chance(50)
                .then(|| gen_bool(&mut r, 2, &mut leaf, GUARD_OPS));
            let mut action = Vec::new();
            for (v, var) in vars.iter().enumerate() {
                if r.chance(40) {
                    let e = if var.is_bool {
                        gen_bool(&mut r, 2, &mut leaf, ACTION_OPS)
                    } else {
                        gen_int(&mut r, 2, &mut leaf, ACTION_OPS)
                    };
                    action.push((v, e));
                }
            }
            trans.push(Tr {
                from: r.below(locs),
                port: if r.chance(20) {
                    None
                } else {
                    Some(r.below(ports))
                },
                to: r.below(locs),
                guard,
                action,
            });
        }
        atoms.push(Atom {
            locs,
            initial: r.below(locs),
            ports,
            vars,
            trans,
        });
    }
    let families: Vec<Family> = (0..1 + r.below(3))
        .map(|_| Family {
            atom: r.below(atoms.len()),
            count: if r.chance(50) {
                Some(1 + r.below(3))
            } else {
                None
            },
        })
        .collect();
    let mut conns = Vec::new();
    for _ in 0..1 + r.below(4) {
        let forall = if r.chance(40) {
            Some(1 + r.below(3))
        } else {
            None
        };
        let mut ports = Vec::new();
        for _ in 0..1 + r.below(3) {
            let f = r.below(families.len());
            let idx = match (families[f].count, forall) {
                (None, _) => Idx::Single,
                (Some(c), Some(_)) if r.chance(60) => Idx::Shift(r.below(c)),
                (Some(c), _) => Idx::Const(r.below(c)),
            };
            let port = r.below(atoms[families[f].atom].ports);
            ports.push((f, idx, port));
        }
        let trigger = r.chance(30).then(|| r.below(ports.len()));
        let fams_in: Vec<(usize, Idx)> = ports.iter().map(|&(f, i, _)| (f, i)).collect();
        let mut leaf = |r: &mut Rng, want_bool: bool| -> Option<Ex> {
            // reads any component: a participant through the connector's own index, or a
            // fixed member of any family
            let (f, idx) = if r.chance(60) {
                fams_in[r.below(fams_in.len())]
            } else {
                let f = r.below(families.len());
                (
                    f,
                    families[f]
                        .count
                        .map_or(Idx::Single, |c| Idx::Const(r.below(c))),
                )
            };
            let atom = &atoms[families[f].atom];
            if r.chance(25) {
                return want_bool.then(|| Ex::At(f, idx, r.below(atom.locs)));
            }
            let c: Vec<usize> = (0..atom.vars.len())
                .filter(|&v| atom.vars[v].is_bool == want_bool)
                .collect();
            (!c.is_empty()).then(|| Ex::Var(f, idx, c[r.below(c.len())]))
        };
        let guard = r
            .chance(40)
            .then(|| gen_bool(&mut r, 2, &mut leaf, GUARD_OPS));
        let mut action = Vec::new();
        if r.chance(40) {
            let (f, idx, _) = ports[r.below(ports.len())];
            let atom = &atoms[families[f].atom];
            if !atom.vars.is_empty() {
                let v = r.below(atom.vars.len());
                let e = if atom.vars[v].is_bool {
                    gen_bool(&mut r, 2, &mut leaf, ACTION_OPS)
                } else {
                    gen_int(&mut r, 2, &mut leaf, ACTION_OPS)
                };
                action.push((f, idx, v, e));
            }
        }
        conns.push(Conn {
            forall,
            ports,
            trigger,
            guard,
            action,
        });
    }
    // a component may take part once per connector instance: drop connectors that break it
    let gen = Gen {
        atoms,
        families,
        conns,
        prios: Vec::new(),
    };
    let conns: Vec<Conn> = gen
        .conns
        .iter()
        .filter(|c| {
            instances(c).all(|i| {
                let mut comps: Vec<usize> = c
                    .ports
                    .iter()
                    .map(|&(f, idx, _)| gen.component(f, idx, i))
                    .collect();
                comps.sort();
                comps.windows(2).all(|w| w[0] != w[1])
            })
        })
        .cloned()
        .collect();
    let mut gen = Gen { conns, ..gen };
    // priorities from earlier to later connectors only, so they cannot form a cycle
    let n = gen.conns.len();
    for _ in 0..r.below(4) {
        if n < 2 {
            break;
        }
        let a = r.below(n - 1);
        let b = a + 1 + r.below(n - a - 1);
        let pick = |r: &mut Rng, c: usize| -> (usize, Option<usize>) {
            match gen.conns[c].forall {
                Some(k) if r.chance(40) => (c, Some(r.below(k))),
                _ => (c, None),
            }
        };
        let low = pick(&mut r, a);
        let high = pick(&mut r, b);
        let families = gen.families.clone();
        let atoms = gen.atoms.clone();
        let mut leaf = |r: &mut Rng, want_bool: bool| -> Option<Ex> {
            let f = r.below(families.len());
            let idx = families[f]
                .count
                .map_or(Idx::Single, |c| Idx::Const(r.below(c)));
            let atom = &atoms[families[f].atom];
            if want_bool && r.chance(40) {
                return Some(Ex::At(f, idx, r.below(atom.locs)));
            }
            let c: Vec<usize> = (0..atom.vars.len())
                .filter(|&v| atom.vars[v].is_bool == want_bool)
                .collect();
            (!c.is_empty()).then(|| Ex::Var(f, idx, c[r.below(c.len())]))
        };
        let when = r
            .chance(50)
            .then(|| gen_bool(&mut r, 1, &mut leaf, GUARD_OPS));
        gen.prios.push(Prio { low, high, when });
    }
    gen
}

pub fn instances(c: &Conn) -> impl Iterator<Item = Option<usize>> {
    let v: Vec<Option<usize>> = match c.forall {
        None => vec![None],
        Some(n) => (0..n).map(Some).collect(),
    };
    v.into_iter()
}

impl Gen {
    /// Global component number of family `f` at `idx` in instance `i` of a connector.
    pub fn component(&self, f: usize, idx: Idx, i: Option<usize>) -> usize {
        let base: usize = self.families[..f]
            .iter()
            .map(|fam| fam.count.unwrap_or(1))
            .sum();
        base + match (idx, self.families[f].count) {
            (Idx::Single, _) => 0,
            (Idx::Const(k), _) => k,
            (Idx::Shift(k), Some(c)) => (i.unwrap_or(0) + k) % c,
            (Idx::Shift(_), None) => 0,
        }
    }

    pub fn component_count(&self) -> usize {
        self.families.iter().map(|f| f.count.unwrap_or(1)).sum()
    }

    pub fn atom_of(&self, comp: usize) -> &Atom {
        let mut k = comp;
        for f in &self.families {
            let n = f.count.unwrap_or(1);
            if k < n {
                return &self.atoms[f.atom];
            }
            k -= n;
        }
        unreachable!("component {comp} out of range")
    }

    pub fn component_name(&self, comp: usize) -> String {
        let mut k = comp;
        for (fi, f) in self.families.iter().enumerate() {
            let n = f.count.unwrap_or(1);
            if k < n {
                return match f.count {
                    None => format!("f{fi}"),
                    Some(_) => format!("f{fi}[{k}]"),
                };
            }
            k -= n;
        }
        unreachable!()
    }

    // ----------------------------------------------------------------------------------
    // Writing the system as a model file.

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
        s += "  ],\n)\n";
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
