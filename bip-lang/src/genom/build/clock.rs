//! The clock: one atom whose `tick` port is the trigger of the tick broadcast, with the
//! phase of the tasks' common cycle when their periods differ; and the tick connector,
//! whose action ages the ports that constraints read and clears each activity's `paused`
//! at its task's period boundaries (every period, offset by the task's `delay`). Both
//! depend on the same least common multiple of the periods (of periodic tasks only).

use super::{connector, port, text, tr, var, Builder};
use crate::diag::ModelError;
use crate::expr::BinOp;
use crate::expr::{Assign, Expr};
use crate::genom::names::*;
use crate::genom::tree::{and, assign, binary, boolean, cond, int, member};
use crate::source::{ConstExpr, Span};
use crate::syntax::{AtomDef, ConnectorDef, ConnectorKindDef, ExprDef, Role, TypeDef};

fn gcd(a: i64, b: i64) -> i64 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// The clock's phase wraps at this many ticks at most (least common multiple of periods).
const MAX_PHASE: i64 = 1 << 20;

impl<'a, 'd> Builder<'a, 'd> {
    /// The ports of module `mi` that constraints read, each with the cap of its age.
    pub(super) fn aged_ports(&self, mi: usize) -> Vec<(usize, i64)> {
        self.caps
            .iter()
            .filter(|(p, _)| p.module == mi)
            .map(|(p, &cap)| (p.port, cap))
            .collect()
    }

    /// The tick's part for module `mi`: the ports that constraints read age by one, up to
    /// their cap, where `on_tick` holds (always if `None`).
    pub(super) fn age_ports(
        &self,
        mi: usize,
        on_tick: Option<&Expr>,
        ports: &mut Vec<ExprDef>,
        action: &mut Vec<Assign>,
    ) {
        let m = &self.layer.modules[mi];
        let aged = self.aged_ports(mi);
        if aged.is_empty() {
            return;
        }
        let c = module_component(m.name);
        ports.push(port(&c, "tick"));
        for (p, cap) in aged {
            let a = member(&c, &age_var(m.ports[p]));
            let older = cond(
                binary(BinOp::Lt, a.clone(), int(cap)),
                binary(BinOp::Add, a.clone(), int(1)),
                int(cap),
            );
            let older = match on_tick {
                Some(on_tick) => cond(on_tick.clone(), older, a.clone()),
                None => older,
            };
            action.push(assign(a, older));
        }
    }

    /// The least common multiple of the periods of tasks that have activities; past
    /// [`MAX_PHASE`], the period of the task that took it there.
    fn phase_len(&self) -> (i64, Option<Span>) {
        let mut l = 1i64;
        for m in &self.layer.modules {
            for s in m.services.iter().filter(|s| s.is_activity()) {
                // an aperiodic task has no boundaries, so no part in the cycle
                if let Some((t, p)) = s.task.and_then(|t| Some((t, m.tasks[t].1?))) {
                    l = (l / gcd(l, p)).saturating_mul(p).min(MAX_PHASE + 1);
                    if l > MAX_PHASE {
                        let span = m
                            .def
                            .tasks
                            .get(t)
                            .and_then(|t| t.period.as_ref())
                            .map_or(m.def.name.span, |p| p.span);
                        return (l, Some(span));
                    }
                }
            }
        }
        (l, None)
    }

    pub(super) fn clock(&mut self) {
        // a timed model's phase counts time units (its cycle checked with the layer)
        let (l, too_long) = match self.timed {
            Some(t) => (t.hyperperiod as i64, None),
            None => self.phase_len(),
        };
        if let Some(span) = too_long {
            self.errors.push(
                ModelError::new(
                    format!("the task periods have a common cycle longer than {MAX_PHASE} ticks"),
                    span,
                )
                .with_label("with the periods before it, this period makes the cycle too long")
                .with_help("use periods with a small least common multiple"),
            );
        }
        let mut vars = if l > 1 {
            vec![var(
                PHASE,
                TypeDef::Int(ConstExpr::int(0), ConstExpr::int(l - 1)),
                Some(0),
            )]
        } else {
            Vec::new()
        };
        let mut ports = vec![TICK];
        // a timed model's boundary release is a step of its own (`timed/tick.rs`)
        if self.timed.is_some() {
            vars.push(var(DUE, TypeDef::Bool, Some(0)));
            ports.push(RELEASE);
        }
        let atom = AtomDef {
            locations: vec![text("on")],
            initial: text("on"),
            ports: ports.iter().map(|p| text(*p)).collect(),
            vars,
            transitions: ports
                .iter()
                .map(|p| tr("on", p, "on", None, Vec::new()))
                .collect(),
            task: None,
        };
        let span = self.layer_span();
        self.add_atom(CLOCK_ATOM.into(), atom, span, "the clock".into());
        self.add_component(CLOCK.into(), CLOCK_ATOM.into(), span, "the clock".into());
    }

    pub(super) fn tick(&mut self) {
        let (l, _) = self.phase_len();
        let mut ports = vec![port(CLOCK, "tick")];
        let mut action = Vec::new();
        if l > 1 {
            let phase = member(CLOCK, PHASE);
            let next = binary(BinOp::Add, phase.clone(), int(1));
            action.push(assign(phase, binary(BinOp::Rem, next, int(l))));
        }
        for (mi, m) in self.layer.modules.iter().enumerate() {
            for s in &m.services {
                let Some(task) = s.task.filter(|_| s.is_activity()) else {
                    continue;
                };
                let c = activity_component(m.name, s.name);
                ports.push(port(&c, "tick"));
                // an aperiodic task's activity is woken by its module's events, not by
                // time (`wake.rs`)
                let Some(p) = m.tasks[task].1 else {
                    continue;
                };
                let paused = member(&c, PAUSED);
                if p == 1 {
                    action.push(assign(paused, boolean(false)));
                } else {
                    // the boundaries are the ticks `delay + k * p` (the phase is the
                    // tick's number, modulo the common cycle, once incremented)
                    let off_period = binary(
                        BinOp::Ne,
                        binary(BinOp::Rem, member(CLOCK, PHASE), int(p)),
                        int(m.delays[task]),
                    );
                    action.push(assign(paused.clone(), and(paused, off_period)));
                }
            }
            self.age_ports(mi, None, &mut ports, &mut action);
        }
        self.push_tick(ports, None, action, None);
    }

    /// Where the layer's own generated names point: its first module's name.
    pub(super) fn layer_span(&self) -> Span {
        self.layer
            .modules
            .first()
            .map_or(Span::NONE, |m| m.def.name.span)
    }

    /// The clock's tick, timed or not: the clock's broadcast to `ports`, with `guard` and
    /// `action`, standing for `advance` units (one if `None`).
    pub(super) fn push_tick(
        &mut self,
        ports: Vec<ExprDef>,
        guard: Option<Expr>,
        action: Vec<Assign>,
        advance: Option<Expr>,
    ) {
        self.claim(TICK, self.layer_span(), "the clock's tick".into());
        self.connectors.push((
            ConnectorDef {
                kind: ConnectorKindDef::Broadcast {
                    trigger: port(CLOCK, "tick"),
                },
                advance: advance.map(ExprDef::Built),
                ..connector(TICK, ports, Role::Time)
            },
            guard,
            action,
        ));
    }
}
