//! Random small models for the symbolic method's property tests, written as model files
//! so that they go through the loader like any user's model.
//!
//! They exercise what the encoding must mirror: families, non-deterministic and internal
//! transitions, guards and actions that can fail (division, values out of range),
//! rendezvous and broadcast connectors with guards reading any component and actions
//! writing participants, priorities with conditions, and time and environment roles.

#![allow(dead_code)]

pub use bip_model::Rng;

#[derive(Clone)]
struct Var {
    name: String,
    is_bool: bool,
    lo: i64,
    hi: i64,
}

struct Atom {
    locs: usize,
    ports: usize,
    vars: Vec<Var>,
}

/// What expressions may read.
struct Scope<'a> {
    /// (text, is_bool) leaves.
    leaves: Vec<(String, bool)>,
    /// Allow `/` and `%` (which can fail).
    divide: bool,
    rng: &'a mut Rng,
}

impl Scope<'_> {
    fn int(&mut self, depth: u32) -> String {
        if depth == 0 || self.rng.chance(35) {
            let ints: Vec<String> = self
                .leaves
                .iter()
                .filter(|l| !l.1)
                .map(|l| l.0.clone())
                .collect();
            if !ints.is_empty() && self.rng.chance(70) {
                return ints[self.rng.below(ints.len())].clone();
            }
            return self.rng.range(-2, 4).to_string();
        }
        if self.rng.chance(15) {
            let c = self.boolean(depth - 1);
            let a = self.int(depth - 1);
            let b = self.int(depth - 1);
            return format!("({c} ? {a} : {b})");
        }
        let ops: &[&str] = if self.divide {
            &["+", "-", "*", "/", "%", "/", "%"]
        } else {
            &["+", "-", "*"]
        };
        let op = ops[self.rng.below(ops.len())];
        let a = self.int(depth - 1);
        let b = self.int(depth - 1);
        format!("({a} {op} {b})")
    }

    fn boolean(&mut self, depth: u32) -> String {
        if depth == 0 || self.rng.chance(30) {
            let bools: Vec<String> = self
                .leaves
                .iter()
                .filter(|l| l.1)
                .map(|l| l.0.clone())
                .collect();
            if !bools.is_empty() && self.rng.chance(75) {
                return bools[self.rng.below(bools.len())].clone();
            }
            return if self.rng.chance(70) { "true" } else { "false" }.into();
        }
        match self.rng.below(5) {
            0 => format!("!{}", self.boolean(depth - 1)),
            1 | 2 => {
                let op = ["<", "<=", "==", "!=", ">"][self.rng.below(5)];
                let a = self.int(depth - 1);
                let b = self.int(depth - 1);
                format!("({a} {op} {b})")
            }
            _ => {
                let op = ["&&", "||", "=>"][self.rng.below(3)];
                let a = self.boolean(depth - 1);
                let b = self.boolean(depth - 1);
                format!("({a} {op} {b})")
            }
        }
    }
}

/// A random model file. `properties` are appended as written.
pub fn model(seed: u64, with_roles: bool) -> String {
    let mut r = Rng(seed);
    let mut atoms = Vec::new();
    let mut atom_text = Vec::new();
    for a in 0..1 + r.below(3) {
        let locs = 1 + r.below(3);
        let ports = 1 + r.below(3);
        let vars: Vec<Var> = (0..r.below(3))
            .map(|k| {
                if r.chance(30) {
                    Var {
                        name: format!("v{k}"),
                        is_bool: true,
                        lo: 0,
                        hi: 1,
                    }
                } else {
                    let lo = r.range(-1, 1);
                    Var {
                        name: format!("v{k}"),
                        is_bool: false,
                        lo,
                        hi: lo + r.range(0, 3),
                    }
                }
            })
            .collect();
        let mut trans = Vec::new();
        for _ in 0..r.below(7) {
            let from = r.below(locs);
            let to = r.below(locs);
            let port = (!r.chance(20)).then(|| r.below(ports));
            let leaves: Vec<(String, bool)> =
                vars.iter().map(|v| (v.name.clone(), v.is_bool)).collect();
            let mut sc = Scope {
                leaves,
                divide: r.chance(50),
                rng: &mut r,
            };
            let guard = sc.rng.chance(50).then(|| sc.boolean(2));
            let mut action = Vec::new();
            for v in &vars {
                if sc.rng.chance(40) {
                    let e = if v.is_bool { sc.boolean(2) } else { sc.int(2) };
                    action.push(format!("{} = {e}", v.name));
                }
            }
            let mut t = format!("(from: \"l{from}\", to: \"l{to}\"");
            if let Some(p) = port {
                t += &format!(", port: \"p{p}\"");
            }
            if let Some(g) = guard {
                t += &format!(", guard: \"{g}\"");
            }
            if !action.is_empty() {
                t += &format!(", action: \"{}\"", action.join("; "));
            }
            trans.push(t + ")");
        }
        let vars_text: Vec<String> = vars
            .iter()
            .map(|v| {
                if v.is_bool {
                    format!("(name: \"{}\", ty: Bool, init: {})", v.name, r.chance(50))
                } else {
                    format!(
                        "(name: \"{}\", ty: Int({}, {}), init: {})",
                        v.name,
                        v.lo,
                        v.hi,
                        r.range(v.lo, v.hi)
                    )
                }
            })
            .collect();
        let locs_text: Vec<String> = (0..locs).map(|l| format!("\"l{l}\"")).collect();
        let ports_text: Vec<String> = (0..ports).map(|p| format!("\"p{p}\"")).collect();
        atom_text.push(format!(
            "\"A{a}\": Atom(locations: [{}], initial: \"l{}\", ports: [{}], vars: [{}], transitions: [{}])",
            locs_text.join(", "),
            r.below(locs),
            ports_text.join(", "),
            vars_text.join(", "),
            trans.join(", ")
        ));
        atoms.push(Atom { locs, ports, vars });
    }
    // components: families of 1 to 2 members, or single ones
    let mut comps: Vec<(String, usize)> = Vec::new(); // (name, atom)
    let mut comp_text = Vec::new();
    for f in 0..1 + r.below(3) {
        let atom = r.below(atoms.len());
        if r.chance(40) {
            let n = 1 + r.below(2);
            comp_text.push(format!("(name: \"f{f}\", atom: \"A{atom}\", count: {n})"));
            for k in 0..n {
                comps.push((format!("f{f}[{k}]"), atom));
            }
        } else {
            comp_text.push(format!("(name: \"f{f}\", atom: \"A{atom}\")"));
            comps.push((format!("f{f}"), atom));
        }
    }
    let global_leaves = |comps: &[(String, usize)]| -> Vec<(String, bool)> {
        let mut out = Vec::new();
        for (name, a) in comps {
            for v in &atoms[*a].vars {
                out.push((format!("{name}.{}", v.name), v.is_bool));
            }
            for l in 0..atoms[*a].locs {
                out.push((format!("{name}@l{l}"), true));
            }
        }
        out
    };
    let all_leaves = global_leaves(&comps);
    let mut conn_text = Vec::new();
    let nconn = 1 + r.below(4);
    for k in 0..nconn {
        let mut members: Vec<usize> = Vec::new();
        for _ in 0..1 + r.below(3) {
            let c = r.below(comps.len());
            if !members.contains(&c) {
                members.push(c);
            }
        }
        let ports: Vec<String> = members
            .iter()
            .map(|&c| format!("\"{}.p{}\"", comps[c].0, r.below(atoms[comps[c].1].ports)))
            .collect();
        let mut t = format!("(name: \"k{k}\", ports: [{}]", ports.join(", "));
        if members.len() > 1 && r.chance(30) {
            t += &format!(", kind: Broadcast(trigger: {})", ports[0]);
        }
        let mut sc = Scope {
            leaves: all_leaves.clone(),
            divide: r.chance(40),
            rng: &mut r,
        };
        if sc.rng.chance(40) {
            t += &format!(", guard: \"{}\"", sc.boolean(2));
        }
        if sc.rng.chance(40) {
            let c = members[sc.rng.below(members.len())];
            let vars = &atoms[comps[c].1].vars;
            if !vars.is_empty() {
                let v = &vars[sc.rng.below(vars.len())];
                let e = if v.is_bool { sc.boolean(2) } else { sc.int(2) };
                t += &format!(", action: \"{}.{} = {e}\"", comps[c].0, v.name);
            }
        }
        if with_roles {
            match r.below(10) {
                0 => t += ", role: Time",
                1 => t += ", role: Environment",
                _ => {}
            }
        }
        conn_text.push(t + ")");
    }
    // priorities from earlier to later connectors: no cycle
    let mut prio_text = Vec::new();
    for _ in 0..r.below(3) {
        if nconn < 2 {
            break;
        }
        let lo = r.below(nconn - 1);
        let hi = lo + 1 + r.below(nconn - lo - 1);
        let mut t = format!("(low: \"k{lo}\", high: \"k{hi}\"");
        let mut sc = Scope {
            leaves: all_leaves.clone(),
            divide: false,
            rng: &mut r,
        };
        if sc.rng.chance(50) {
            t += &format!(", when: \"{}\"", sc.boolean(1));
        }
        prio_text.push(t + ")");
    }
    // properties over the components' values
    let mut sc = Scope {
        leaves: all_leaves.clone(),
        divide: r.chance(30),
        rng: &mut r,
    };
    let inv = sc.boolean(2);
    let reach = sc.boolean(2);
    let terminal = sc.boolean(1);
    let deadlock = if sc.rng.chance(30) {
        format!("DeadlockFree(terminal: \"{terminal}\")")
    } else {
        "DeadlockFree".into()
    };
    format!(
        "System(name: \"random\", atoms: {{ {} }}, components: [{}], connectors: [{}], priorities: [{}],
         properties: [{deadlock}, Invariant(name: \"inv\", expr: \"{inv}\"), Reachable(name: \"reach\", expr: \"{reach}\")])",
        atom_text.join(",\n"),
        comp_text.join(", "),
        conn_text.join(",\n"),
        prio_text.join(", ")
    )
}
