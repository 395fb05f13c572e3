//! Async codels (docs/genom.md, "Async codels"): GenoM3 runs one apart from its task,
//! which goes on with its other activities meanwhile. Its activity stays at the codel's
//! state while it runs. The codel is three steps: its start (`m_S_s_start`, urgent and
//! gated by the codel's conditions, as a synchronous codel is), its return
//! (`m_S_s_return`, whenever the world lets it, below every codel step as a request is,
//! so that ticks pass while it runs), and its outcome, today's codel connector and error
//! path, which the task takes up at its next cycle (its next period boundary; at once in
//! an aperiodic task). No other codel of the activity runs meanwhile. An interrupt or
//! abort cannot cancel a running codel: the activity takes its stop path at once, whose
//! codels wait for the return, and the outcome is dropped.

use super::{connector, port, set, text, tr, var, Builder};
use crate::expr::{Assign, BinOp, Expr};
use crate::genom::check::{ServiceRef, ETHER};
use crate::genom::names::*;
use crate::genom::tree::{and, assign, binary, int, name, not};
use crate::source::ConstExpr;
use crate::syntax::{Role, TransitionDef, TypeDef, VarDef};

/// An activity's variables for its `apart` async codels (none without one).
pub(super) fn async_vars(apart: usize) -> Vec<VarDef> {
    if apart == 0 {
        return Vec::new();
    }
    vec![
        var(
            BUSY,
            TypeDef::Int(ConstExpr::int(0), ConstExpr::int(apart as i64)),
            Some(0),
        ),
        var(RETURNED, TypeDef::Bool, Some(0)),
    ]
}

/// No async codel of the activity runs.
pub(super) fn none_apart() -> Expr {
    busy_is(0)
}

fn busy_is(n: i64) -> Expr {
    binary(BinOp::Eq, name(BUSY), int(n))
}

/// The start and return transitions of async codel `state`, number `n`, of an activity
/// whose locations (but `ether`) are `locs`.
pub(super) fn start_and_return(
    state: &str,
    n: i64,
    locs: &[&str],
    aperiodic: bool,
    ports: &mut Vec<crate::syntax::Text>,
    t: &mut Vec<TransitionDef>,
) {
    let start = start_port(state);
    let ret = return_port(state);
    ports.push(text(&start));
    ports.push(text(&ret));
    let run = assign(name(BUSY), int(n));
    if state == "start" {
        t.push(tr(
            ETHER,
            &start,
            state,
            Some(and(and(name(REQ), not(name(PAUSED))), none_apart())),
            vec![set(REQ, false), run.clone()],
        ));
    }
    t.push(tr(
        state,
        &start,
        state,
        Some(and(
            and(not(name(PAUSED)), none_apart()),
            not(name(RETURNED)),
        )),
        vec![run],
    ));
    // the return: where the activity still waits for it, its outcome waits for the
    // task's next cycle; anywhere else (interrupted, aborted) it is dropped
    let done = assign(name(BUSY), int(0));
    for l in std::iter::once(ETHER).chain(locs.iter().copied()) {
        let mut action: Vec<Assign> = vec![done.clone()];
        if l == state {
            action.push(set(RETURNED, true));
            action.push(set(PAUSED, !aperiodic));
        }
        t.push(tr(l, &ret, l, Some(busy_is(n)), action));
    }
}

impl<'a, 'd> Builder<'a, 'd> {
    /// The start and return connectors of async codel `state` of activity `r`: the start
    /// takes the codel's conditions `guard`, the return nothing. Returns their names.
    pub(super) fn async_connectors(
        &mut self,
        r: ServiceRef,
        state: &str,
        span: crate::source::Span,
        guard: Option<Expr>,
    ) -> (String, String) {
        let s = self.service(r);
        let m = self.module_name(r);
        let comp = self.comp(r);
        let start = start_connector(m, s.name, state);
        self.claim(
            &start,
            span,
            format!("the start of async codel `{state}` of `{m}.{}`", s.name),
        );
        self.connectors.push((
            connector(
                &start,
                vec![port(&comp, &start_port(state))],
                Role::Progress,
            ),
            guard,
            Vec::new(),
        ));
        let ret = return_connector(m, s.name, state);
        self.claim(
            &ret,
            span,
            format!("the return of async codel `{state}` of `{m}.{}`", s.name),
        );
        self.connectors.push((
            connector(&ret, vec![port(&comp, &return_port(state))], Role::Progress),
            None,
            Vec::new(),
        ));
        (start, ret)
    }
}
