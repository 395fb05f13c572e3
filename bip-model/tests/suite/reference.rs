//! The compiled step relation against a deliberately naive reference interpreter.
//!
//! A random small system is generated as plain Rust data, written out as a RON model and
//! loaded by bip-model. The reference interpreter below reads the same data and applies
//! docs/model.md's "Semantics: one step" word for word: no indices, no closure tables, no
//! folding. Along random walks, every state's successors must agree exactly (as multisets
//! of interaction name and successor state), and so must range errors.
//!
//! The oracle lives only here.

use std::collections::HashMap;

use bip_lang::load_str;
use bip_model::{State, Steps, System};
use proptest::prelude::*;

use bip_random_systems::*;

// --------------------------------------------------------------------------------------
// The reference interpreter.

/// A global state: per component, its location and its variables.
type RState = Vec<(usize, Vec<i64>)>;

#[derive(Debug)]
struct Failure;

/// The interpreter reads the generated data itself.
struct Reference<'g>(&'g Gen);

impl std::ops::Deref for Reference<'_> {
    type Target = Gen;
    fn deref(&self) -> &Gen {
        self.0
    }
}

impl Reference<'_> {
    fn initial(&self) -> RState {
        (0..self.component_count())
            .map(|c| {
                let a = self.atom_of(c);
                (a.initial, a.vars.iter().map(|v| v.init).collect())
            })
            .collect()
    }

    /// Evaluates an expression. `me` is the component whose own variables `Local` reads;
    /// `inst` the connector instance's `i`.
    fn eval(&self, e: &Ex, s: &RState, me: usize, inst: Option<usize>) -> Result<i64, Failure> {
        Ok(match e {
            Ex::Int(i) => *i,
            Ex::Bool(b) => *b as i64,
            Ex::Local(v) => s[me].1[*v],
            Ex::Var(f, idx, v) => s[self.component(*f, *idx, inst)].1[*v],
            Ex::At(f, idx, l) => (s[self.component(*f, *idx, inst)].0 == *l) as i64,
            Ex::Not(a) => (self.eval(a, s, me, inst)? == 0) as i64,
            Ex::Ite(c, a, b) => {
                if self.eval(c, s, me, inst)? != 0 {
                    self.eval(a, s, me, inst)?
                } else {
                    self.eval(b, s, me, inst)?
                }
            }
            Ex::Bin(op, a, b) => {
                let x = self.eval(a, s, me, inst)?;
                match *op {
                    "&&" if x == 0 => return Ok(0),
                    "||" if x != 0 => return Ok(1),
                    "=>" if x == 0 => return Ok(1),
                    _ => {}
                }
                let y = self.eval(b, s, me, inst)?;
                match *op {
                    "+" => x.checked_add(y).ok_or(Failure)?,
                    "-" => x.checked_sub(y).ok_or(Failure)?,
                    "*" => x.checked_mul(y).ok_or(Failure)?,
                    "/" => x.checked_div(y).ok_or(Failure)?,
                    "%" => x.checked_rem(y).ok_or(Failure)?,
                    "<" => (x < y) as i64,
                    "<=" => (x <= y) as i64,
                    "==" => (x == y) as i64,
                    "!=" => (x != y) as i64,
                    ">" => (x > y) as i64,
                    "&&" | "||" | "=>" => (y != 0) as i64,
                    other => unreachable!("operator {other}"),
                }
            }
            // read only through `with_advance`, which replaces it by the step's value
            Ex::Advance => unreachable!("`advance` outside a time step's action"),
        })
    }

    /// "A `Time` connector's `advance` is evaluated on the state the step leaves, and its
    /// action reads it as `advance`": the expression with `advance` replaced by its value.
    fn with_advance(e: &Ex, value: i64) -> Ex {
        let sub = |x: &Ex| Box::new(Self::with_advance(x, value));
        match e {
            Ex::Advance => Ex::Int(value),
            Ex::Not(a) => Ex::Not(sub(a)),
            Ex::Bin(op, a, b) => Ex::Bin(op, sub(a), sub(b)),
            Ex::Ite(c, a, b) => Ex::Ite(sub(c), sub(a), sub(b)),
            leaf => leaf.clone(),
        }
    }

    /// "a port is enabled if its component has a transition from its current location on
    /// that port whose guard holds": the list of such transitions.
    fn enabled_on(
        &self,
        s: &RState,
        comp: usize,
        port: Option<usize>,
    ) -> Result<Vec<usize>, Failure> {
        let a = self.atom_of(comp);
        let mut out = Vec::new();
        for (k, t) in a.trans.iter().enumerate() {
            if t.from == s[comp].0 && t.port == port {
                let ok = match &t.guard {
                    None => true,
                    Some(g) => self.eval(g, s, comp, None)? != 0,
                };
                if ok {
                    out.push(k);
                }
            }
        }
        Ok(out)
    }

    /// The enabled steps: (name, connector instance or None, [(component, transition)]).
    #[allow(clippy::type_complexity)]
    fn steps(
        &self,
        s: &RState,
    ) -> Result<Vec<(String, Option<(usize, Option<usize>)>, Vec<(usize, usize)>)>, Failure> {
        let mut out = Vec::new();
        // 1. each enabled internal transition of any component (fires alone)
        for c in 0..self.component_count() {
            for t in self.enabled_on(s, c, None)? {
                out.push((
                    format!("{}.internal", self.component_name(c)),
                    None,
                    vec![(c, t)],
                ));
            }
        }
        // 2. each connector interaction whose ports are all enabled and whose guard holds;
        //    one successor per combination of enabled transitions of the participants
        for (ci, conn) in self.conns.iter().enumerate() {
            for inst in instances(conn) {
                let mut options: Vec<Vec<(usize, usize)>> = Vec::new();
                let mut ok = true;
                for (k, &(f, idx, p)) in conn.ports.iter().enumerate() {
                    let comp = self.component(f, idx, inst);
                    let ts = self.enabled_on(s, comp, Some(p))?;
                    let is_receiver = conn.trigger.is_some_and(|t| t != k);
                    if ts.is_empty() {
                        if is_receiver {
                            continue; // a receiver never blocks the trigger
                        }
                        ok = false;
                        break;
                    }
                    options.push(ts.into_iter().map(|t| (comp, t)).collect());
                }
                if !ok {
                    continue;
                }
                if let Some(g) = &conn.guard {
                    if self.eval(g, s, 0, inst)? == 0 {
                        continue;
                    }
                }
                // the broadcast's trigger goes first in the compiled port order only if it
                // was not listed; here it is always listed, so port order is as written
                let name = match inst {
                    Some(i) => format!("c{ci}[{i}]"),
                    None => format!("c{ci}"),
                };
                let mut combos: Vec<Vec<(usize, usize)>> = vec![Vec::new()];
                for opts in &options {
                    combos = combos
                        .into_iter()
                        .flat_map(|pre| {
                            opts.iter().map(move |o| {
                                let mut v = pre.clone();
                                v.push(*o);
                                v
                            })
                        })
                        .collect();
                }
                for picks in combos {
                    out.push((name.clone(), Some((ci, inst)), picks));
                }
            }
        }
        // 3. minus the interactions suppressed by priorities: an interaction is suppressed
        //    if one of a higher connector (transitively, under the conjunction of the
        //    `when`s) is enabled
        if self.prios.is_empty() {
            return Ok(out);
        }
        let enabled: Vec<(usize, Option<usize>)> =
            out.iter().filter_map(|(_, ci, _)| *ci).collect();
        let mut suppressed = HashMap::new();
        for &(ci, inst) in &enabled {
            let key = (ci, inst);
            if suppressed.contains_key(&key) {
                continue;
            }
            let v = self.reaches_enabled(s, (ci, inst), &enabled)?;
            suppressed.insert(key, v);
        }
        Ok(out
            .into_iter()
            .filter(|(_, ci, _)| ci.is_none_or(|k| !suppressed[&k]))
            .collect())
    }

    /// Depth-first search along declared priority edges whose `when` holds now.
    fn reaches_enabled(
        &self,
        s: &RState,
        from: (usize, Option<usize>),
        enabled: &[(usize, Option<usize>)],
    ) -> Result<bool, Failure> {
        let covers = |(c, k): (usize, Option<usize>), (ci, inst): (usize, Option<usize>)| {
            c == ci && (k.is_none() || k == inst)
        };
        let mut stack = vec![from];
        let mut seen = vec![from];
        while let Some(cur) = stack.pop() {
            for p in &self.prios {
                if !covers(p.low, cur) {
                    continue;
                }
                if let Some(w) = &p.when {
                    if self.eval(w, s, 0, None)? == 0 {
                        continue;
                    }
                }
                let (hc, hk) = p.high;
                let targets: Vec<(usize, Option<usize>)> = match (hk, self.conns[hc].forall) {
                    (Some(k), _) => vec![(hc, Some(k))],
                    (None, Some(n)) => (0..n).map(|i| (hc, Some(i))).collect(),
                    (None, None) => vec![(hc, None)],
                };
                for t in targets {
                    if enabled.contains(&t) {
                        return Ok(true);
                    }
                    if !seen.contains(&t) {
                        seen.push(t);
                        stack.push(t);
                    }
                }
            }
        }
        Ok(false)
    }

    /// "Firing a step runs the actions and moves the participants": the connector action
    /// first, then each participant's transition action in port order.
    fn fire(
        &self,
        s: &RState,
        conn: Option<(usize, Option<usize>)>,
        picks: &[(usize, usize)],
    ) -> Result<RState, Failure> {
        let mut n = s.clone();
        let assign = |n: &mut RState, comp: usize, v: usize, value: i64| -> Result<(), Failure> {
            let var = &self.atom_of(comp).vars[v];
            if value < var.lo || value > var.hi {
                return Err(Failure);
            }
            n[comp].1[v] = value;
            Ok(())
        };
        if let Some((ci, inst)) = conn {
            // a time step stands for its `advance` units (1 by default), at least 1, and
            // that value is computed before anything changes
            let advance = match &self.conns[ci].advance {
                Some(e) => self.eval(e, s, 0, inst)?,
                None => 1,
            };
            if advance < 1 {
                return Err(Failure);
            }
            for (f, idx, v, e) in &self.conns[ci].action {
                let value = self.eval(&Self::with_advance(e, advance), &n, 0, inst)?;
                assign(&mut n, self.component(*f, *idx, inst), *v, value)?;
            }
        }
        for &(comp, t) in picks {
            for (v, e) in &self.atom_of(comp).trans[t].action {
                let value = self.eval(e, &n, comp, None)?;
                assign(&mut n, comp, *v, value)?;
            }
        }
        for &(comp, t) in picks {
            n[comp].0 = self.atom_of(comp).trans[t].to;
        }
        Ok(n)
    }
}

/// The compiled state as the reference's representation (same component and variable
/// order by construction).
fn to_ref(sys: &System, s: &State) -> RState {
    sys.components
        .iter()
        .map(|c| {
            let nvars = sys.atoms[c.atom as usize].vars.len();
            let slots = s.slots();
            (
                slots[c.slot as usize] as usize,
                (0..nvars).map(|v| slots[c.slot as usize + 1 + v]).collect(),
            )
        })
        .collect()
}

/// Successors by the compiled relation, as (name, reference state or error) sorted.
fn compiled_successors(
    sys: &System,
    s: &State,
    steps: &mut Steps,
) -> Result<Vec<(String, Option<RState>)>, Failure> {
    sys.enabled_steps(s, steps).map_err(|_| Failure)?;
    let mut out: Vec<(String, Option<RState>)> = steps
        .iter()
        .map(|st| {
            let mut next = s.clone();
            let r = sys.fire(s, st, &mut next).ok().map(|()| to_ref(sys, &next));
            (sys.label_name(st.label), r)
        })
        .collect();
    out.sort();
    Ok(out)
}

fn reference_successors(
    g: &Reference,
    s: &RState,
) -> Result<Vec<(String, Option<RState>)>, Failure> {
    let mut out: Vec<(String, Option<RState>)> = g
        .steps(s)?
        .into_iter()
        .map(|(name, conn, picks)| (name, g.fire(s, conn, &picks).ok()))
        .collect();
    out.sort();
    Ok(out)
}

/// The systems compared. Roles only decide which states are deadlocks (docs/model.md,
/// "Deadlocks, time and the environment"): one step ignores them, and so does the
/// interpreter, so connectors with roles check that the compiled relation does too.
fn reference_system(seed: u64) -> Gen {
    generate_with(
        seed,
        &Options {
            roles: true,
            advance: true,
            ..Options::default()
        },
    )
}

/// Runs random walks on one generated system; returns the number of states compared.
fn check_system(seed: u64) -> Result<usize, TestCaseError> {
    let gen = reference_system(seed);
    let g = Reference(&gen);
    let text = g.to_ron();
    let mut sys = load_str("generated.ron", &text).map_err(|e| {
        TestCaseError::fail(format!(
            "generated model does not load: {}\n{text}",
            e.summary()
        ))
    })?;
    // steps from the step tables, or computed from the state (every other seed)
    if seed % 2 == 1 {
        sys.drop_step_tables(|_| true);
    }
    prop_assert_eq!(
        to_ref(&sys, &sys.initial_state()),
        g.initial(),
        "initial states\n{}",
        text
    );
    let mut rng = Rng(seed ^ 0x5555);
    let mut steps = Steps::new();
    let mut compared = 0;
    for _walk in 0..3 {
        let mut s = sys.initial_state();
        for _ in 0..25 {
            let rs = to_ref(&sys, &s);
            let compiled = compiled_successors(&sys, &s, &mut steps);
            let reference = reference_successors(&g, &rs);
            compared += 1;
            match (compiled, reference) {
                (Ok(c), Ok(r)) => {
                    prop_assert_eq!(&c, &r, "successors of {:?} differ in\n{}", rs, text);
                    let ok: Vec<&RState> = c.iter().filter_map(|(_, n)| n.as_ref()).collect();
                    if ok.is_empty() {
                        break;
                    }
                    // continue from a random non-failing successor (via the compiled steps)
                    let pick = rng.below(ok.len());
                    let target = ok[pick].clone();
                    sys.enabled_steps(&s, &mut steps)
                        .map_err(|e| TestCaseError::fail(e.to_string()))?;
                    let mut next = s.clone();
                    let mut found = false;
                    for st in steps.iter() {
                        if sys.fire(&s, st, &mut next).is_ok() && to_ref(&sys, &next) == target {
                            found = true;
                            break;
                        }
                    }
                    prop_assert!(found);
                    s = next;
                }
                (Err(_), Err(_)) => break,
                (c, r) => {
                    return Err(TestCaseError::fail(format!(
                    "one side fails to evaluate in {rs:?}: compiled {:?}, reference {:?}\n{text}",
                    c.is_ok(),
                    r.is_ok()
                )))
                }
            }
        }
    }
    Ok(compared)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, ..ProptestConfig::default() })]

    #[test]
    fn compiled_step_relation_matches_the_reference(seed in any::<u64>()) {
        check_system(seed)?;
    }
}

/// The generator must produce systems that exercise every rule, or the comparison above
/// proves little: count the features over a fixed set of seeds.
#[test]
fn generator_covers_every_rule() {
    let mut broadcast = 0;
    let mut forall = 0;
    let mut priorities = 0;
    let mut when = 0;
    let mut internal = 0;
    let mut nondeterministic = 0;
    let mut range_errors = 0;
    let mut compared = 0;
    let mut roles = 0;
    let mut advances = 0;
    for seed in 0..400u64 {
        let g = reference_system(seed);
        roles += g.conns.iter().filter(|c| c.role.is_some()).count();
        advances += g.conns.iter().filter(|c| c.advance.is_some()).count();
        broadcast += g.conns.iter().filter(|c| c.trigger.is_some()).count();
        forall += g.conns.iter().filter(|c| c.forall.is_some()).count();
        priorities += g.prios.len();
        when += g.prios.iter().filter(|p| p.when.is_some()).count();
        internal += g
            .atoms
            .iter()
            .flat_map(|a| &a.trans)
            .filter(|t| t.port.is_none())
            .count();
        nondeterministic += g
            .atoms
            .iter()
            .filter(|a| {
                a.trans.iter().enumerate().any(|(i, t)| {
                    a.trans[..i]
                        .iter()
                        .any(|u| u.from == t.from && u.port == t.port)
                })
            })
            .count();
        let sys = load_str("g.ron", &g.to_ron()).expect("loads");
        let mut steps = Steps::new();
        if sys.enabled_steps(&sys.initial_state(), &mut steps).is_ok() {
            for st in steps.iter() {
                let mut n = sys.initial_state();
                if sys.fire(&sys.initial_state(), st, &mut n).is_err() {
                    range_errors += 1;
                }
            }
        }
        compared += check_system(seed).expect("agrees");
    }
    for (what, n) in [
        ("broadcasts", broadcast),
        ("forall connectors", forall),
        ("priorities", priorities),
        ("guarded priorities", when),
        ("internal transitions", internal),
        ("non-deterministic atoms", nondeterministic),
        ("range errors at the initial state", range_errors),
        ("connectors with a role", roles),
        ("time connectors with an advance", advances),
    ] {
        assert!(n >= 20, "only {n} {what} in 400 systems");
    }
    assert!(compared > 10_000, "only {compared} states compared");
}
