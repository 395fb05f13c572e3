//! Tests of the expansion, checked by exploring the expanded systems with the one step
//! relation (`enabled_steps`, `fire`) and the one deadlock definition (`liveness`).

use std::collections::{HashMap, VecDeque};

use crate::state::State;
use crate::step::Steps;
use crate::syntax::{PropertyDef, SystemDef};
use crate::system::{PropertyKind, System};
use crate::{load_str, Liveness, LivenessChecker};

/// What a breadth-first exploration found.
struct Explored {
    states: Vec<State>,
    /// For each state, its parent and the step name that led to it.
    parent: Vec<Option<(usize, String)>>,
    /// Deadlocks not excused by a `DeadlockFree` terminal condition.
    deadlocks: Vec<usize>,
    /// Invariants violated, with the first state violating each.
    violations: Vec<(String, usize)>,
    transitions: usize,
}

impl Explored {
    fn trace(&self, mut k: usize) -> Vec<String> {
        let mut out = Vec::new();
        while let Some((p, step)) = &self.parent[k] {
            out.push(step.clone());
            k = *p;
        }
        out.reverse();
        out
    }

    fn any(&self, sys: &System, expr: &str) -> bool {
        let e = compile_expr(sys, expr);
        self.states
            .iter()
            .any(|s| sys.eval(&e, s).expect("evaluates") != 0)
    }

    fn all(&self, sys: &System, expr: &str) -> bool {
        let e = compile_expr(sys, expr);
        self.states
            .iter()
            .all(|s| sys.eval(&e, s).expect("evaluates") != 0)
    }
}

/// Compiles a global expression, GenoM names allowed, over the model `sys` was loaded
/// from: it is added to the model as an invariant, which the expansion rewrites.
fn compile_expr(sys: &System, expr: &str) -> crate::eval::Expr {
    let mut def = MODELS
        .with(|d| d.borrow().get(&sys.name).cloned())
        .expect("the model was loaded with `load`");
    def.properties.push(PropertyDef::Invariant {
        name: "question".into(),
        expr: expr.into(),
    });
    let mut asked = crate::compile(&def).unwrap_or_else(|e| panic!("`{expr}`: {e:?}"));
    match asked.properties.pop().map(|p| p.kind) {
        Some(PropertyKind::Invariant(e)) => e,
        _ => unreachable!("the question is the last property"),
    }
}

thread_local! {
    static MODELS: std::cell::RefCell<HashMap<String, SystemDef>> =
        std::cell::RefCell::new(HashMap::new());
}

/// Loads a model (expanding its GenoM layer) and remembers it for `compile_expr`.
fn load(text: &str) -> System {
    let sys = load_str("test.ron", text).unwrap_or_else(|e| panic!("{}", e.summary()));
    let def = crate::parse_str("test.ron", text).expect("parses");
    MODELS.with(|d| d.borrow_mut().insert(sys.name.clone(), def));
    sys
}

fn explore(sys: &System) -> Explored {
    let mut index: HashMap<State, usize> = HashMap::new();
    let mut ex = Explored {
        states: Vec::new(),
        parent: Vec::new(),
        deadlocks: Vec::new(),
        violations: Vec::new(),
        transitions: 0,
    };
    let init = sys.initial_state();
    index.insert(init.clone(), 0);
    ex.states.push(init);
    ex.parent.push(None);
    let mut queue = VecDeque::from([0usize]);
    let mut steps = Steps::new();
    let mut checker = LivenessChecker::default();
    let mut next = sys.initial_state();
    while let Some(k) = queue.pop_front() {
        let s = ex.states[k].clone();
        for p in &sys.properties {
            if let PropertyKind::Invariant(e) = &p.kind {
                if !sys.holds(e, &s, &p.name).expect("evaluates")
                    && !ex.violations.iter().any(|v| v.0 == p.name)
                {
                    ex.violations.push((p.name.clone(), k));
                }
            }
        }
        sys.enabled_steps(&s, &mut steps).expect("no range error");
        if sys
            .liveness(&s, &steps, &mut checker)
            .expect("no range error")
            == Liveness::Deadlock
        {
            let excused = sys.properties.iter().any(|p| match &p.kind {
                PropertyKind::DeadlockFree { terminal: Some(t) } => {
                    sys.holds(t, &s, "terminal").expect("evaluates")
                }
                _ => false,
            });
            if !excused {
                ex.deadlocks.push(k);
            }
        }
        for step in steps.iter() {
            sys.fire(&s, step, &mut next).expect("no range error");
            ex.transitions += 1;
            if !index.contains_key(&next) {
                let n = ex.states.len();
                index.insert(next.clone(), n);
                ex.states.push(next.clone());
                ex.parent.push(Some((k, sys.label_name(step.label))));
                queue.push_back(n);
            }
        }
    }
    ex
}

const MINI: &str = include_str!("../../../robots/tests/mini.ron");

#[test]
fn model_md_example_expands_and_holds() {
    let sys = load(MINI);
    let ex = explore(&sys);
    eprintln!(
        "mini: {} states, {} transitions",
        ex.states.len(),
        ex.transitions
    );
    assert!(ex.violations.is_empty(), "{:?}", ex.violations);
    assert!(
        ex.deadlocks.is_empty(),
        "{:?}",
        ex.deadlocks
            .iter()
            .map(|&d| ex.trace(d))
            .collect::<Vec<_>>()
    );
    assert!(ex.any(&sys, "rflex.TrackSpeed@main"));
}
