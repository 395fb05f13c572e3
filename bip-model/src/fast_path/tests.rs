use super::*;
use crate::eval::Env;

/// No ranges known: nothing is tabulated.
const UNKNOWN: Ranges<'static> = Ranges {
    slots: &[],
    locals: &[],
};

fn b(e: Expr) -> Box<Expr> {
    Box::new(e)
}

/// Every state of two slots in -3..=3 (and the base 1 for locals).
fn states() -> impl Iterator<Item = [i64; 3]> {
    (-3..=3).flat_map(|x| (-3..=3).map(move |y| [x, y, x - y]))
}

fn agrees(e: Expr) {
    let mut code = FlatCode::default();
    let GuardCode::Tests { start, end } = code.guard(Some(&e), &UNKNOWN) else {
        panic!("{e:?} has a flat form")
    };
    for s in states() {
        let tree = e.holds(&mut Env::new(&s, 1)).expect("evaluates");
        assert_eq!(code.all_hold(start, end, &s, 1), tree, "{e:?} in {s:?}");
    }
}

#[test]
fn flat_guards_mean_what_their_trees_mean() {
    use Expr::*;
    for op in [
        BinOp::Eq,
        BinOp::Ne,
        BinOp::Lt,
        BinOp::Le,
        BinOp::Gt,
        BinOp::Ge,
    ] {
        agrees(Binary(op, b(Slot(0)), b(Const(1))));
        agrees(Binary(op, b(Const(-1)), b(Local(0))));
        agrees(Not(b(Binary(op, b(Local(1)), b(Const(0))))));
    }
    agrees(Slot(1));
    agrees(Not(b(Local(0))));
    agrees(Not(b(Not(b(Slot(0))))));
    agrees(At(0, 2));
    agrees(Not(b(At(1, 0))));
    agrees(Binary(
        BinOp::And,
        b(Binary(BinOp::And, b(Slot(0)), b(Const(1)))),
        b(Not(b(Slot(1)))),
    ));
}

#[test]
fn other_guards_become_tables_or_stack_code() {
    use Expr::*;
    let mut code = FlatCode::default();
    let others = [
        Binary(BinOp::Or, b(Slot(0)), b(Slot(1))),
        Binary(BinOp::Lt, b(Slot(0)), b(Slot(1))),
        Binary(
            BinOp::And,
            b(Slot(0)),
            b(Binary(BinOp::Or, b(Slot(0)), b(Slot(1)))),
        ),
    ];
    // without the slots' ranges, stack code
    for e in &others {
        let g = code.guard(Some(e), &UNKNOWN);
        assert!(matches!(g, GuardCode::Code { .. }), "{e:?}: {g:?}");
    }
    // with them, tables
    let ranges = Ranges {
        slots: &[(0, 3), (0, 1)],
        locals: &[],
    };
    for e in &others {
        let g = code.guard(Some(e), &ranges);
        assert!(matches!(g, GuardCode::Table(_)), "{e:?}: {g:?}");
    }
    // a constant false guard reads nothing: a table of one entry
    let g = code.guard(Some(&Const(0)), &UNKNOWN);
    assert!(matches!(g, GuardCode::Table(_)), "{g:?}");
    assert_eq!(code.decide(g, &[], 0), Some(false));
    let quantified = Quant(Box::new(crate::eval::Quant {
        kind: crate::ops::QuantKind::Exists,
        lo: 0,
        hi: 2,
        depth: 0,
        body: Bound(0),
    }));
    assert_eq!(code.guard(Some(&quantified), &UNKNOWN), GuardCode::Tree);
    assert_eq!(code.guard(Some(&Const(1)), &UNKNOWN), GuardCode::Always);
    assert_eq!(code.guard(None, &UNKNOWN), GuardCode::Always);
}

#[test]
fn flat_assignments_compute_what_their_trees_compute() {
    use Expr::*;
    let values = [
        Const(7),
        Slot(0),
        Local(1),
        Binary(BinOp::Add, b(Local(0)), b(Const(2))),
        Binary(BinOp::Add, b(Const(-2)), b(Slot(1))),
        Binary(BinOp::Sub, b(Slot(0)), b(Const(3))),
    ];
    for value in values {
        let mut code = FlatCode::default();
        let a = Assign {
            target: Target::Local(0),
            value: value.clone(),
        };
        let c = code.action(core::slice::from_ref(&a), &UNKNOWN);
        let flat = code.assigns(c)[0];
        for s in [[0, 5, -4], [i64::MAX, 1, i64::MIN], [i64::MIN, 0, i64::MAX]] {
            let tree = value.eval(&mut Env::new(&s, 1));
            let Some(r) = flat.eval(&code, &s, 1) else {
                panic!("{value:?} has a flat form")
            };
            assert_eq!(r.map(|(_, v)| v), tree, "{value:?} in {s:?}");
            assert_eq!(flat.slot(1), 1, "the target, after the base");
        }
    }
    // `x - i64::MIN` has no flat form (its negation overflows), nor has `x * 2`
    let mut code = FlatCode::default();
    let action = [
        Assign {
            target: Target::Slot(0),
            value: Binary(BinOp::Sub, b(Slot(0)), b(Const(i64::MIN))),
        },
        Assign {
            target: Target::Slot(0),
            value: Binary(BinOp::Mul, b(Slot(0)), b(Const(2))),
        },
    ];
    let c = code.action(&action, &UNKNOWN);
    let ops = code.ops.len();
    assert!(code.assigns(c)[0].eval(&code, &[1], 0).is_none());
    assert!(matches!(code.assigns(c)[1].value, Value::Code { .. }) && ops > 0);
}

/// A random expression over slots 0..3 (locals from base 1), without families or
/// quantifiers, with every operator.
fn random_expr(rng: &mut crate::Rng, depth: u32) -> Expr {
    use Expr::*;
    if depth == 0 || rng.chance(25) {
        return match rng.below(4) {
            0 => Const(rng.range(-3, 3)),
            1 => Slot(rng.below(3) as u32),
            2 => Local(rng.below(2) as u32),
            _ => At(rng.below(3) as u32, rng.below(3) as u32),
        };
    }
    let ops = [
        BinOp::Mul,
        BinOp::Div,
        BinOp::Rem,
        BinOp::Add,
        BinOp::Sub,
        BinOp::Lt,
        BinOp::Le,
        BinOp::Gt,
        BinOp::Ge,
        BinOp::Eq,
        BinOp::Ne,
        BinOp::And,
        BinOp::Or,
        BinOp::Implies,
    ];
    let groups: [&[BinOp]; 4] = [
        &[BinOp::Add, BinOp::Sub],
        &[BinOp::Mul, BinOp::Div, BinOp::Rem],
        &[BinOp::And],
        &[BinOp::Or],
    ];
    match rng.below(6) {
        5 => {
            let group = groups[rng.below(groups.len())];
            let rest = (0..2 + rng.below(3))
                .map(|_| (group[rng.below(group.len())], random_expr(rng, depth - 1)))
                .collect();
            Chain(b(random_expr(rng, depth - 1)), rest)
        }
        0 => Not(b(random_expr(rng, depth - 1))),
        1 => Neg(b(random_expr(rng, depth - 1))),
        2 => Cond(
            b(random_expr(rng, depth - 1)),
            b(random_expr(rng, depth - 1)),
            b(random_expr(rng, depth - 1)),
        ),
        _ => Binary(
            ops[rng.below(ops.len())],
            b(random_expr(rng, depth - 1)),
            b(random_expr(rng, depth - 1)),
        ),
    }
}

#[test]
fn stack_code_computes_what_the_tree_computes() {
    let mut rng = crate::Rng::new(7);
    let extremes = [i64::MIN, -1, 0, 1, 2, i64::MAX];
    let (mut failures, mut values) = (0, 0);
    for _ in 0..20_000 {
        let e = random_expr(&mut rng, 5);
        let mut code = FlatCode::default();
        let (start, end) = compile(&e, &mut code.ops).expect("no family, no quantifier");
        for _ in 0..8 {
            let mut s = [0i64; 3];
            for v in &mut s {
                *v = if rng.chance(20) {
                    extremes[rng.below(extremes.len())]
                } else {
                    rng.range(-2, 2)
                };
            }
            let tree = e.eval(&mut Env::new(&s, 1));
            let run = code.run(start, end, &s, 1);
            assert_eq!(run.ok(), tree.ok(), "{e:?} in {s:?}");
            if tree.is_err() {
                failures += 1;
            } else {
                values += 1;
            }
        }
    }
    // both outcomes were exercised
    assert!(failures > 1_000 && values > 100_000, "{failures} {values}");
}

/// Slots 0..3 with small ranges, and locals from base 3 (the slots' count).
const SMALL_SLOTS: [(i64, i64); 3] = [(-2, 2), (0, 1), (0, 2)];
const SMALL_LOCALS: [(i64, i64); 2] = [(0, 1), (-1, 1)];
const SMALL: Ranges<'static> = Ranges {
    slots: &SMALL_SLOTS,
    locals: &SMALL_LOCALS,
};

/// Every state of [`SMALL`]: the three slots, then the two locals.
fn small_states() -> impl Iterator<Item = [i64; 5]> {
    (-2..=2).flat_map(|x| {
        (0..=1).flat_map(move |y| {
            (0..=2).flat_map(move |z| {
                (0..=1).flat_map(move |l0| (-1..=1).map(move |l1| [x, y, z, l0, l1]))
            })
        })
    })
}

#[test]
fn tables_hold_what_the_tree_computes() {
    let ranges = SMALL;
    let mut rng = crate::Rng::new(11);
    let (mut tabulated, mut failures, mut values, mut outside) = (0, 0, 0, 0);
    for _ in 0..5_000 {
        let e = random_expr(&mut rng, 4);
        let mut code = FlatCode::default();
        let Some(t) = code.tabulate(&e, &ranges) else {
            continue;
        };
        tabulated += 1;
        // every state in range: the table's entry, or none where the tree fails
        for s in small_states() {
            let tree = e.eval(&mut Env::new(&s, 3));
            assert_eq!(code.lookup(t, &s, 3), tree.ok(), "{e:?} in {s:?}");
            match tree {
                Ok(_) => values += 1,
                Err(_) => failures += 1,
            }
        }
        // outside the ranges, the tree decides
        if crate::radix::key(&code.table_digits, &[0, 0, 0, 0, 0], 3).is_some()
            && crate::radix::key(&code.table_digits, &[3, 0, 0, 0, 0], 3).is_none()
        {
            assert_eq!(code.lookup(t, &[3, 0, 0, 0, 0], 3), None, "{e:?}");
            outside += 1;
        }
    }
    assert!(tabulated > 2_000 && failures > 1_000 && values > 100_000);
    assert!(
        outside > 500,
        "only {outside} tables looked up outside their ranges"
    );
    // an expression over more combinations than a table may hold is not tabulated
    let wide = [(0, 1000), (0, 1000)];
    let e = Expr::Binary(BinOp::Mul, b(Expr::Slot(0)), b(Expr::Slot(1)));
    let ranges = Ranges {
        slots: &wide,
        locals: &[],
    };
    assert_eq!(FlatCode::default().tabulate(&e, &ranges), None);
    assert!(matches!(
        FlatCode::default().guard(Some(&e), &ranges),
        GuardCode::Code { .. }
    ));
}

#[test]
fn action_tables_hold_what_the_assignments_write() {
    let (slots, locals, ranges) = (SMALL_SLOTS, SMALL_LOCALS, SMALL);
    let mut rng = crate::Rng::new(13);
    let (mut tabulated, mut failures, mut values) = (0, 0, 0);
    for _ in 0..3_000 {
        let n = 2 + rng.below(2);
        let action: Vec<Assign> = (0..n)
            .map(|_| Assign {
                target: match rng.below(2) {
                    0 => Target::Slot(rng.below(3) as u32),
                    _ => Target::Local(rng.below(2) as u32),
                },
                value: random_expr(&mut rng, 3),
            })
            .collect();
        let mut code = FlatCode::default();
        let c = code.action(&action, &ranges);
        if c.table == NO_TABLE {
            continue;
        }
        tabulated += 1;
        for start in small_states() {
            // the assignments in order, each seeing the ones before
            let mut s = start;
            let mut want = Some(Vec::new());
            for a in &action {
                let (at, (lo, hi)) = match a.target {
                    Target::Slot(k) => (k as usize, slots[k as usize]),
                    Target::Local(k) => (3 + k as usize, locals[k as usize]),
                };
                match a.value.eval(&mut Env::new(&s, 3)) {
                    Ok(v) if lo <= v && v <= hi => {
                        s[at] = v;
                        if let Some(w) = &mut want {
                            w.push(v);
                        }
                    }
                    _ => {
                        want = None;
                        break;
                    }
                }
            }
            let got = code.action_values(c, &start, 3).map(<[i64]>::to_vec);
            assert_eq!(got, want, "{action:?} from {start:?}");
            match want {
                Some(_) => values += 1,
                None => failures += 1,
            }
        }
    }
    assert!(tabulated > 1_000 && failures > 10_000 && values > 10_000);
    // one assignment has no action table (its value has its own form)
    let one = [Assign {
        target: Target::Slot(0),
        value: Expr::Binary(BinOp::Mul, b(Expr::Slot(0)), b(Expr::Slot(1))),
    }];
    let mut code = FlatCode::default();
    assert_eq!(code.action(&one, &ranges).table, NO_TABLE);
}
