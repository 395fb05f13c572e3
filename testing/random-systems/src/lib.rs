//! Random small systems for the property tests, generated as plain Rust data (which
//! bip-model's reference interpreter reads) and written out as model files (which go
//! through the loader like any user's model).
//!
//! One generator serves every suite: the step relation against the reference interpreter,
//! the incremental enabled set, the state cache and the gate (bip-model), and the symbolic
//! encoding and verdicts against the explicit ones (bip-verifier). What only some suites
//! can take (roles, guards that fail, properties) is behind [`Options`].
//!
//! [`timed`] draws timed task sets instead, with the naive interpreter of the timed
//! semantics that answers for them; [`genom_async`] GenoM layers with async codels, with
//! theirs.

pub mod genom_async;
mod ron;
pub mod timed;

pub use bip_model::Rng;

/// What the generator may produce beyond the plain step relation.
///
/// The default is what bip-model's reference interpreter checks: its guards must not fail,
/// since which guard is evaluated first is an implementation choice, and it has no notion
/// of roles or properties.
#[derive(Clone, Copy, Debug, Default)]
pub struct Options {
    /// Connectors may have the Time or Environment role.
    pub roles: bool,
    /// Atom and connector guards may divide, and so fail; and wherever expressions may
    /// divide, they divide more often ([`FAILING_OPS`]).
    pub failing_guards: bool,
    /// A deadlock-freedom (sometimes with a terminal condition), an invariant and a
    /// reachability property over the components' values; their expressions may divide.
    pub properties: bool,
    /// With `properties`: a `LeadsTo` and, if a connector has the Time role, a bounded
    /// `Response`, between two conditions over the components' values.
    pub responses: bool,
    /// With `roles`: Time connectors may have an `advance` (which may fail or be below 1)
    /// and read it in their action, after an assignment that may change what it reads.
    /// Drawn after everything else, so that the rest of each system is the same without.
    pub advance: bool,
}

impl Options {
    /// Everything the verifier must handle: the encoding mirrors failures exactly, and
    /// roles change which states are deadlocks.
    pub fn verifier(roles: bool) -> Options {
        Options {
            roles,
            failing_guards: true,
            properties: true,
            responses: false,
            advance: false,
        }
    }
}

/// A random model file with everything the verifier must handle (see [`Options::verifier`]).
pub fn model(seed: u64, with_roles: bool) -> String {
    generate_with(seed, &Options::verifier(with_roles)).to_ron()
}

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
    /// `advance`, in a Time connector's action.
    Advance,
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

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    Time,
    Environment,
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
    pub role: Option<Role>,
    /// Of a Time connector ([`Options::advance`]).
    pub advance: Option<Ex>,
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
    /// With [`Options::properties`].
    pub props: Option<Props>,
}

/// Properties over fixed components (no connector index in scope).
#[derive(Clone, Debug)]
pub struct Props {
    /// `DeadlockFree`, with this terminal condition if any.
    pub terminal: Option<Ex>,
    pub invariant: Ex,
    pub reachable: Ex,
    /// With [`Options::responses`]: trigger, response, and the bound of the `Response`
    /// (written only if a connector has the Time role).
    pub response: Option<(Ex, Ex, u64)>,
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
            let op = ["<", "<=", "==", "!=", ">"][r.below(5)];
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

/// By default guards use no division (their evaluation order is an implementation choice,
/// so they must not fail); actions may divide and leave ranges: those range errors must
/// agree.
pub const GUARD_OPS: &[&str] = &["+", "-", "*"];
pub const ACTION_OPS: &[&str] = &["+", "-", "*", "/", "%"];
/// Where failures are the point (the verifier's encoding must mirror each one), division
/// and remainder come twice as often.
pub const FAILING_OPS: &[&str] = &["+", "-", "*", "/", "%", "/", "%"];

/// A random system with the default [`Options`].
pub fn generate(seed: u64) -> Gen {
    generate_with(seed, &Options::default())
}

/// Guards divide, when they may, in this many percent of the cases, so that most guards
/// still succeed and the steps behind them get exercised.
const FAILING_GUARD_CHANCE: u64 = 50;

fn guard_ops(r: &mut Rng, opts: &Options) -> &'static [&'static str] {
    if opts.failing_guards && r.chance(FAILING_GUARD_CHANCE) {
        FAILING_OPS
    } else {
        GUARD_OPS
    }
}

fn action_ops(opts: &Options) -> &'static [&'static str] {
    if opts.failing_guards {
        FAILING_OPS
    } else {
        ACTION_OPS
    }
}

/// A leaf reading a fixed member of any family: what priorities and properties can read.
fn global_leaf(r: &mut Rng, atoms: &[Atom], families: &[Family], want_bool: bool) -> Option<Ex> {
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
}

pub fn generate_with(seed: u64, opts: &Options) -> Gen {
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
            let ops = guard_ops(&mut r, opts);
            let guard = r.chance(50).then(|| gen_bool(&mut r, 2, &mut leaf, ops));
            let mut action = Vec::new();
            for (v, var) in vars.iter().enumerate() {
                if r.chance(40) {
                    let e = if var.is_bool {
                        gen_bool(&mut r, 2, &mut leaf, action_ops(opts))
                    } else {
                        gen_int(&mut r, 2, &mut leaf, action_ops(opts))
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
        let ops = guard_ops(&mut r, opts);
        let guard = r.chance(40).then(|| gen_bool(&mut r, 2, &mut leaf, ops));
        let mut action = Vec::new();
        if r.chance(40) {
            let (f, idx, _) = ports[r.below(ports.len())];
            let atom = &atoms[families[f].atom];
            if !atom.vars.is_empty() {
                let v = r.below(atom.vars.len());
                let e = if atom.vars[v].is_bool {
                    gen_bool(&mut r, 2, &mut leaf, action_ops(opts))
                } else {
                    gen_int(&mut r, 2, &mut leaf, action_ops(opts))
                };
                action.push((f, idx, v, e));
            }
        }
        let role = if opts.roles {
            match r.below(10) {
                0 => Some(Role::Time),
                1 => Some(Role::Environment),
                _ => None,
            }
        } else {
            None
        };
        conns.push(Conn {
            forall,
            ports,
            trigger,
            guard,
            action,
            role,
            advance: None,
        });
    }
    // a component may take part once per connector instance: drop connectors that break it
    let gen = Gen {
        atoms,
        families,
        conns,
        prios: Vec::new(),
        props: None,
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
        let (atoms, families) = (&gen.atoms, &gen.families);
        let mut leaf = |r: &mut Rng, want_bool: bool| global_leaf(r, atoms, families, want_bool);
        let when = r
            .chance(50)
            .then(|| gen_bool(&mut r, 1, &mut leaf, GUARD_OPS));
        gen.prios.push(Prio { low, high, when });
    }
    // a quarter of the systems get a long chain of priorities, through connectors of one
    // port added for it: the closure is then deep, and its `when`s lie along paths
    if r.chance(25) {
        let first = gen.conns.len();
        for _ in 0..3 + r.below(6) {
            let forall = r.chance(30).then(|| 1 + r.below(3));
            let f = r.below(gen.families.len());
            let idx = match (gen.families[f].count, forall) {
                (None, _) => Idx::Single,
                (Some(c), Some(_)) => Idx::Shift(r.below(c)),
                (Some(c), None) => Idx::Const(r.below(c)),
            };
            let port = r.below(gen.atoms[gen.families[f].atom].ports);
            gen.conns.push(Conn {
                forall,
                ports: vec![(f, idx, port)],
                trigger: None,
                guard: None,
                action: Vec::new(),
                role: None,
                advance: None,
            });
        }
        // from the last connector of the system before them (if any) up through the new ones
        let from = first.saturating_sub(1);
        for c in from..gen.conns.len() - 1 {
            let pick = |r: &mut Rng, c: usize| -> (usize, Option<usize>) {
                match gen.conns[c].forall {
                    Some(k) if r.chance(30) => (c, Some(r.below(k))),
                    _ => (c, None),
                }
            };
            let low = pick(&mut r, c);
            let high = pick(&mut r, c + 1);
            let (atoms, families) = (&gen.atoms, &gen.families);
            let mut leaf =
                |r: &mut Rng, want_bool: bool| global_leaf(r, atoms, families, want_bool);
            let when = r
                .chance(25)
                .then(|| gen_bool(&mut r, 1, &mut leaf, GUARD_OPS));
            gen.prios.push(Prio { low, high, when });
        }
        // and a shortcut along it now and then
        if r.chance(50) && gen.conns.len() - from > 2 {
            gen.prios.push(Prio {
                low: (from, None),
                high: (gen.conns.len() - 1, None),
                when: None,
            });
        }
    }
    if opts.advance {
        add_advances(&mut r, &mut gen);
    }
    if opts.properties {
        let (atoms, families) = (&gen.atoms, &gen.families);
        let mut leaf = |r: &mut Rng, want_bool: bool| global_leaf(r, atoms, families, want_bool);
        let ops = if r.chance(30) { FAILING_OPS } else { GUARD_OPS };
        let invariant = gen_bool(&mut r, 2, &mut leaf, ops);
        let reachable = gen_bool(&mut r, 2, &mut leaf, ops);
        let terminal = r.chance(30).then(|| gen_bool(&mut r, 1, &mut leaf, ops));
        let response = opts.responses.then(|| {
            let trigger = gen_bool(&mut r, 1, &mut leaf, ops);
            let response = gen_bool(&mut r, 1, &mut leaf, ops);
            (trigger, response, r.below(4) as u64)
        });
        gen.props = Some(Props {
            terminal,
            invariant,
            reachable,
            response,
        });
    }
    gen
}

/// Gives Time connectors an `advance` over their participants' variables (it may divide,
/// so fail, and it may be below 1), and an assignment reading it after their action.
fn add_advances(r: &mut Rng, gen: &mut Gen) {
    for ci in 0..gen.conns.len() {
        if gen.conns[ci].role != Some(Role::Time) || !r.chance(70) {
            continue;
        }
        let ports = gen.conns[ci].ports.clone();
        let (atoms, families) = (&gen.atoms, &gen.families);
        let int_vars = |f: usize| -> Vec<usize> {
            let atom = &atoms[families[f].atom];
            (0..atom.vars.len())
                .filter(|&v| !atom.vars[v].is_bool)
                .collect()
        };
        let mut leaf = |r: &mut Rng, want_bool: bool| -> Option<Ex> {
            let (f, idx, _) = ports[r.below(ports.len())];
            if want_bool {
                return Some(Ex::At(f, idx, r.below(atoms[families[f].atom].locs)));
            }
            let vars = int_vars(f);
            (!vars.is_empty()).then(|| Ex::Var(f, idx, vars[r.below(vars.len())]))
        };
        // mostly small positive values, so that most time steps fire; one that reads no
        // variable is a positive constant (a constant below 1 is a load error)
        let advance = match leaf(r, false) {
            Some(var) => {
                let op = ACTION_OPS[r.below(ACTION_OPS.len())];
                let other = gen_int(r, 1, &mut leaf, ACTION_OPS);
                let e = Ex::Bin(op, Box::new(var), Box::new(other));
                Ex::Bin("+", Box::new(Ex::Int(2)), Box::new(e))
            }
            None => Ex::Int(1 + r.below(3) as i64),
        };
        let (f, idx, _) = ports[r.below(ports.len())];
        let vars = int_vars(f);
        let reads = (!vars.is_empty() && r.chance(80)).then(|| {
            let v = vars[r.below(vars.len())];
            let e = Ex::Bin("-", Box::new(Ex::Advance), Box::new(Ex::Int(2)));
            (
                f,
                idx,
                v,
                Ex::Bin("+", Box::new(Ex::Var(f, idx, v)), Box::new(e)),
            )
        });
        let c = &mut gen.conns[ci];
        c.advance = Some(advance);
        c.action.extend(reads);
    }
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
}
