//! Linear invariants: P-semiflows of the net (D-Finder's "linear" invariants).
//!
//! A vector `y` over places with `y · C = 0` for the net's incidence matrix `C` gives the
//! invariant `Σ y(p) · [component of p is at p] = y · M0` in every reachable state. Traps
//! say "at least one of"; semiflows say "exactly so many", as in
//! `fork[i] taken = phil[i] eating + phil[i-1] eating`, which no trap expresses.
//!
//! The net's transitions are products of the members' moves, but a semiflow only needs to
//! be orthogonal to the span of their columns, which a few generators span: for a
//! rendezvous, one combination plus, per member, the difference between each of its moves
//! and its first; for a broadcast, the trigger's likewise and each receiver move alone
//! (a receiver may or may not join). So the matrix stays linear in the model's size.
//!
//! The semiflows are found by sparse fraction-free elimination on `[C | I]` (rows are
//! places): eliminating every column, the rows whose `C` part vanishes carry semiflows in
//! their `I` part. Columns are taken sparsest first and each pivot is the shortest row,
//! which keeps the rows short on the models we know (rings of philosophers stay local).
//! A work budget bounds the elimination; the rows that vanished by then are semiflows
//! all the same.

use std::collections::{HashMap, HashSet};

use z3::ast::{Bool, Int};

use super::encode::{Encoding, Frame};
use super::net::Net;
use super::term::{and, ite_int, not, num, or};

/// `Σ coefficient · [at place] = constant`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Semiflow {
    pub terms: Vec<(u32, i64)>,
    pub constant: i64,
}

/// Entries the elimination may touch before it stops.
const WORK_BUDGET: u64 = 200_000_000;
/// Rows read between two polls of the stop.
const POLL_ROWS: usize = 1024;
/// Coefficients beyond this abandon their row (they would only give unwieldy invariants).
const MAX_COEFF: i128 = 1 << 40;

type Sparse = Vec<(u32, i128)>;

struct Row {
    c: Sparse,
    y: Sparse,
    active: bool,
}

/// The generator columns of the net, each a sparse vector over places.
fn columns(net: &Net) -> Vec<Sparse> {
    let col = |(f, t): (u32, u32)| -> Sparse {
        if f == t {
            Vec::new()
        } else {
            vec![(f, -1), (t, 1)]
        }
    };
    let mut out = Vec::new();
    for g in &net.groups {
        let members = &net.members[g.first as usize..(g.first + g.len) as usize];
        let mut base: Sparse = Vec::new();
        for (k, m) in members.iter().enumerate() {
            let first = col(m.moves[0]);
            let alone = g.trigger.is_some_and(|t| t as usize != k);
            if alone {
                for &mv in &m.moves {
                    out.push(col(mv));
                }
                continue;
            }
            base = add(&base, 1, &first, 1);
            for &mv in &m.moves[1..] {
                out.push(add(&col(mv), 1, &first, -1));
            }
        }
        out.push(base);
    }
    out.retain(|c| !c.is_empty());
    out
}

/// `a * x + b * y` on sparse vectors sorted by index.
fn add(x: &Sparse, a: i128, y: &Sparse, b: i128) -> Sparse {
    let mut out = Vec::with_capacity(x.len() + y.len());
    let (mut i, mut j) = (0, 0);
    while i < x.len() || j < y.len() {
        let (k, v) = if j >= y.len() || (i < x.len() && x[i].0 < y[j].0) {
            i += 1;
            (x[i - 1].0, a * x[i - 1].1)
        } else if i >= x.len() || y[j].0 < x[i].0 {
            j += 1;
            (y[j - 1].0, b * y[j - 1].1)
        } else {
            i += 1;
            j += 1;
            (x[i - 1].0, a * x[i - 1].1 + b * y[j - 1].1)
        };
        if v != 0 {
            out.push((k, v));
        }
    }
    out
}

fn gcd(a: i128, b: i128) -> i128 {
    let (mut a, mut b) = (a.abs(), b.abs());
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// The semiflows of the net, each normalised and none trivial (a component's locations
/// summing to one is known without them). Once `stop` says so, the elimination ends as at
/// its work budget: the semiflows found by then are semiflows still.
pub fn compute(net: &Net, stop: &dyn Fn() -> bool) -> Vec<Semiflow> {
    if stop() {
        return Vec::new();
    }
    let cols = columns(net);
    // rows: one per place touched by a column
    let mut row_of: HashMap<u32, usize> = HashMap::new();
    let mut rows: Vec<Row> = Vec::new();
    for (j, col) in cols.iter().enumerate() {
        for &(p, v) in col {
            let r = *row_of.entry(p).or_insert_with(|| {
                rows.push(Row {
                    c: Vec::new(),
                    y: vec![(p, 1)],
                    active: true,
                });
                rows.len() - 1
            });
            rows[r].c.push((j as u32, v));
        }
    }
    let mut col_rows: Vec<Vec<u32>> = vec![Vec::new(); cols.len()];
    for (r, row) in rows.iter().enumerate() {
        for &(j, _) in &row.c {
            col_rows[j as usize].push(r as u32);
        }
    }
    let mut order: Vec<usize> = (0..cols.len()).collect();
    order.sort_by_key(|&j| col_rows[j].len());
    let mut work = 0u64;
    for j in order {
        if work > WORK_BUDGET || stop() {
            tracing::debug!("semiflow elimination stopped at its work budget");
            break;
        }
        let holders: Vec<u32> = col_rows[j]
            .iter()
            .copied()
            .filter(|&r| {
                let row = &rows[r as usize];
                row.active && row.c.binary_search_by_key(&(j as u32), |e| e.0).is_ok()
            })
            .collect();
        col_rows[j].clear();
        let Some(&pivot) = holders
            .iter()
            .min_by_key(|&&r| rows[r as usize].c.len() + rows[r as usize].y.len())
        else {
            continue;
        };
        rows[pivot as usize].active = false;
        let (pc, py) = (
            rows[pivot as usize].c.clone(),
            rows[pivot as usize].y.clone(),
        );
        let pv = coefficient(&pc, j as u32);
        for &r in &holders {
            if r == pivot {
                continue;
            }
            let row = &mut rows[r as usize];
            let rv = coefficient(&row.c, j as u32);
            let c = add(&row.c, pv, &pc, -rv);
            let y = add(&row.y, pv, &py, -rv);
            work += (c.len() + y.len()) as u64;
            let g = c.iter().chain(&y).fold(0, |g, &(_, v)| gcd(g, v));
            let g = if g == 0 { 1 } else { g };
            let too_big = c.iter().chain(&y).any(|&(_, v)| (v / g).abs() > MAX_COEFF);
            if too_big {
                row.active = false;
                continue;
            }
            for &(k, _) in &c {
                if row.c.binary_search_by_key(&k, |e| e.0).is_err() {
                    col_rows[k as usize].push(r);
                }
            }
            row.c = c.into_iter().map(|(k, v)| (k, v / g)).collect();
            row.y = y.into_iter().map(|(k, v)| (k, v / g)).collect();
        }
    }
    // one row per place: the semiflows of a wide net are many, so repeats are found by
    // hashing, and the stop is polled here too
    let mut out: Vec<Semiflow> = Vec::new();
    let mut seen: HashSet<Semiflow> = HashSet::new();
    for (r, row) in rows.iter().enumerate() {
        if r % POLL_ROWS == 0 && stop() {
            break;
        }
        if !row.active || !row.c.is_empty() {
            continue;
        }
        if let Some(s) = normalise(net, &row.y) {
            if seen.insert(s.clone()) {
                out.push(s);
            }
        }
    }
    out
}

fn coefficient(v: &Sparse, k: u32) -> i128 {
    v.binary_search_by_key(&k, |e| e.0).map_or(0, |i| v[i].1)
}

/// Makes a semiflow short: per component, subtract the coefficient most of its reachable
/// places share (adding a multiple of "the component is somewhere" changes nothing), then
/// compute the constant from the initial marking. `None` if nothing is left.
fn normalise(net: &Net, y: &Sparse) -> Option<Semiflow> {
    let mut by_comp: HashMap<u32, Vec<(u32, i128)>> = HashMap::new();
    for &(p, v) in y {
        by_comp
            .entry(net.comp_of[p as usize])
            .or_default()
            .push((p, v));
    }
    let mut terms: Vec<(u32, i64)> = Vec::new();
    let mut constant: i128 = 0;
    for (c, entries) in by_comp {
        let first = net.place_of[c as usize];
        let reachable: Vec<u32> = (first..)
            .take_while(|&p| (p as usize) < net.places() && net.comp_of[p as usize] == c)
            .filter(|&p| net.reachable[p as usize])
            .collect();
        let coeff = |p: u32| entries.iter().find(|e| e.0 == p).map_or(0, |e| e.1);
        let mut counts: HashMap<i128, usize> = HashMap::new();
        for &p in &reachable {
            *counts.entry(coeff(p)).or_default() += 1;
        }
        let shift = counts
            .into_iter()
            .max_by_key(|&(v, n)| (n, v == 0))
            .map_or(0, |(v, _)| v);
        for &p in &reachable {
            let v = coeff(p) - shift;
            if v != 0 {
                terms.push((p, i64::try_from(v).ok()?));
            }
            if net.initial[p as usize] {
                constant += v;
            }
        }
    }
    if terms.is_empty() {
        return None;
    }
    terms.sort_unstable();
    let g = terms.iter().fold(0i128, |g, &(_, v)| gcd(g, v.into()));
    let g = gcd(g, constant).max(1);
    Some(Semiflow {
        terms: terms.iter().map(|&(p, v)| (p, v / g as i64)).collect(),
        constant: i64::try_from(constant / g).ok()?,
    })
}

/// Semiflows over at most this many location combinations are written as clauses (each
/// combination that breaks the equation is forbidden), which keeps location-only models
/// propositional; larger ones are linear equations over 0/1 terms.
const MAX_TABLE: usize = 256;

impl Semiflow {
    /// The invariant on a frame.
    pub fn constraint(&self, enc: &Encoding<'_>, net: &Net, f: &Frame) -> Bool {
        // per component: its places with a coefficient
        let mut per_comp: Vec<(u32, Vec<(u32, i64)>)> = Vec::new();
        for &(p, v) in &self.terms {
            let c = net.comp_of[p as usize];
            match per_comp.last_mut() {
                Some((k, list)) if *k == c => list.push((p, v)),
                _ => per_comp.push((c, vec![(p, v)])),
            }
        }
        // each component contributes one of its coefficients, or 0 elsewhere
        let combos = per_comp
            .iter()
            .try_fold(1usize, |n, (_, list)| n.checked_mul(list.len() + 1));
        if combos.is_some_and(|n| n <= MAX_TABLE) {
            let mut clauses = Vec::new();
            let mut pick = vec![0usize; per_comp.len()];
            loop {
                let sum: i64 = per_comp
                    .iter()
                    .zip(&pick)
                    .map(|((_, list), &k)| list.get(k).map_or(0, |e| e.1))
                    .sum();
                if sum != self.constant {
                    // forbid this combination
                    clauses.push(or(per_comp.iter().zip(&pick).map(
                        |((_, list), &k)| match list.get(k) {
                            Some(&(p, _)) => not(&net.at(enc, f, p)),
                            None => or(list.iter().map(|&(p, _)| net.at(enc, f, p))),
                        },
                    )));
                }
                let mut i = 0;
                loop {
                    if i == pick.len() {
                        return and(clauses);
                    }
                    pick[i] += 1;
                    if pick[i] <= per_comp[i].1.len() {
                        break;
                    }
                    pick[i] = 0;
                    i += 1;
                }
            }
        }
        self.linear(enc, net, &per_comp, f)
    }

    /// `Σ coefficient · [at location] == constant`, as arithmetic.
    fn linear(
        &self,
        enc: &Encoding<'_>,
        net: &Net,
        per_comp: &[(u32, Vec<(u32, i64)>)],
        f: &Frame,
    ) -> Bool {
        let sum: Vec<Int> = per_comp
            .iter()
            .map(|(_, list)| {
                let mut t = num(0);
                for &(p, v) in list.iter().rev() {
                    t = ite_int(&net.at(enc, f, p), &num(v), &t);
                }
                t
            })
            .collect();
        let total = if sum.len() == 1 {
            sum[0].clone()
        } else {
            Int::add(&sum)
        };
        match total.as_i64() {
            Some(v) => Bool::from_bool(v == self.constant),
            None => total.eq(self.constant),
        }
    }
}
