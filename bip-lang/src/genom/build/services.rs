//! A service's connectors and its part of the engine's map: the request (with the
//! interrupts it sends and the `after` it waits for), an activity's interrupts sent again
//! while it is pending, and for each codel its run and its
//! error path, guarded by the constraints that apply to it. The same conditions go to the
//! recipe, each with its reason, so that the engine says why a request is refused or a
//! codel held.

use super::{connector, port, Builder, Cond, UserTexts};
use crate::expr::{Assign, BinOp, Expr};
use crate::genom::check::{ConstraintKind, PortRef, ServiceRef, ETHER, VALIDATE};
use crate::genom::names::*;
use crate::genom::recipe::{RecipeCodel, RecipeCondition, RecipeService};
use crate::genom::tree::{all, and, assign, at, binary, chain, cond, int, member, not, or};
use crate::syntax::Role;
use bip_model::genom::map::Reason;

impl<'a, 'd> Builder<'a, 'd> {
    /// The conditions on starting activity `r` (waiting for what it interrupts, Exclusive,
    /// AtMost) and on running its codels (Requires, Fresh, Guard).
    fn conditions(&self, r: ServiceRef, user: &UserTexts) -> (Vec<Cond>, Vec<Cond>) {
        let mut start = Vec::new();
        let mut run = Vec::new();
        let s = self.service(r);
        let m = self.module_name(r);
        if s.is_activity() {
            for &x in s.interrupts.iter().filter(|&&x| x != r.service) {
                let target = ServiceRef {
                    module: r.module,
                    service: x,
                };
                start.push(Cond {
                    reason: Reason::Interrupting {
                        service: format!("{m}.{}", self.service(target).name),
                    },
                    expr: at(&self.comp(target), ETHER),
                });
            }
        }
        for (ci, c) in self.layer.constraints.iter().enumerate() {
            let reason = c.reason.clone();
            let others = |list: &[ServiceRef], f: &dyn Fn(ServiceRef) -> Expr| -> Vec<Expr> {
                list.iter().filter(|&&y| y != r).map(|&y| f(y)).collect()
            };
            let expr = match &c.kind {
                ConstraintKind::Exclusive(list) if list.contains(&r) => {
                    all(others(list, &|y| self.inactive(y)))
                }
                ConstraintKind::AtMost { max, services } if services.contains(&r) => {
                    let active = |y: ServiceRef| cond(self.inactive(y), int(0), int(1));
                    chain(BinOp::Add, others(services, &active))
                        .map(|count| binary(BinOp::Lt, count, int(*max)))
                }
                ConstraintKind::Requires { service, active } if *service == r => {
                    all(active.iter().map(|&y| not(at(&self.comp(y), ETHER))))
                }
                ConstraintKind::Fresh {
                    service,
                    port,
                    max_age,
                } if *service == r => {
                    let pm = &self.layer.modules[port.module];
                    let age = member(&module_component(pm.name), &age_var(pm.ports[port.port]));
                    Some(binary(BinOp::Le, age, int(*max_age)))
                }
                ConstraintKind::Guard { service, .. } if *service == r => {
                    user.guards.get(&ci).cloned()
                }
                _ => None,
            };
            let Some(expr) = expr else { continue };
            let cond = Cond { reason, expr };
            match &c.kind {
                ConstraintKind::Exclusive(_) | ConstraintKind::AtMost { .. } => start.push(cond),
                _ => run.push(cond),
            }
        }
        (start, run)
    }

    /// Activity `y` is neither active nor starting: at `ether`, and in a timed model its
    /// `start` codel not running on another core (two activities of an `Exclusive` started
    /// at once on two cores would both become active).
    fn inactive(&self, y: ServiceRef) -> Expr {
        let idle = at(&self.comp(y), ETHER);
        match self.activity_starting(y) {
            Some(starting) => and(idle, not(starting)),
            None => idle,
        }
    }

    pub(super) fn service_connectors(&mut self, r: ServiceRef, user: &UserTexts) {
        let s = self.service(r);
        let m = self.module_name(r);
        let (start_conds, run_conds) = self.conditions(r, user);
        // the request (a task's machine has none: it starts with the component)
        let request = (!s.machine).then(|| self.request_connector(r, &run_conds));
        let interrupt = self.interrupt_connector(r);
        let (function, validate) = match &request {
            Some((name, _)) => self.request_codels(r, name),
            None => (None, None),
        };
        let mut service = RecipeService {
            name: s.name.to_string(),
            kind: s.kind,
            task: s.task,
            component: s.is_activity().then(|| self.comp(r)),
            request: request.as_ref().map(|(name, _)| name.clone()),
            interrupt,
            owned_by_model: false,
            refusals: request.map(|(_, refusals)| refusals).unwrap_or_default(),
            codels: Vec::new(),
            function,
            validate,
            args: s.args.clone(),
            output: s.output.clone(),
            interrupts: s
                .interrupts
                .iter()
                .map(|&x| self.layer.modules[r.module].services[x].name.to_string())
                .collect(),
        };
        // the codels
        let comp = self.comp(r);
        let start_is_location = s.is_location("start");
        for (ci, c) in s.codels.iter().enumerate() {
            let mut holds = Vec::new();
            if c.state == "start" {
                for sc in &start_conds {
                    // a start condition applies to starting, not to re-entering `start`
                    let expr = if start_is_location {
                        or(not(at(&comp, ETHER)), sc.expr.clone())
                    } else {
                        sc.expr.clone()
                    };
                    holds.push(Cond {
                        reason: sc.reason.clone(),
                        expr,
                    });
                }
            }
            for rc in &run_conds {
                // the stop path is not gated
                let expr = if s.stop.is_some() {
                    or(member(&comp, STOPPING), rc.expr.clone())
                } else {
                    rc.expr.clone()
                };
                holds.push(Cond {
                    reason: rc.reason.clone(),
                    expr,
                });
            }
            let mut guard = all(holds.iter().map(|h| h.expr.clone()));
            if self.timed.is_some() {
                // a timed codel's conditions gate its start (`timed/codel.rs`)
                self.holds.insert((r, ci), guard.take());
            }
            // so do an async codel's (`async_codels.rs`)
            let apart = c
                .def
                .asynchronous
                .then(|| self.async_connectors(r, c.state, c.def.state.span, guard.take()));
            let mut ports = vec![port(&comp, c.state)];
            let mi = r.module;
            let action = self.age_resets(mi, &c.writes);
            if !c.ids.is_empty() {
                ports.push(port(&module_component(m), &ids_port(s.name, c.state)));
            } else if !action.is_empty() {
                ports.push(port(&module_component(m), "write"));
            }
            let run = codel_connector(m, s.name, c.state);
            let span = c.def.state.span;
            self.claim(
                &run,
                span,
                format!("codel `{}` of `{m}.{}`", c.state, s.name),
            );
            self.connectors.push((
                connector(&run, ports, Role::Progress),
                guard.clone(),
                action,
            ));
            let fail = fail_connector(m, s.name, c.state);
            self.claim(
                &fail,
                span,
                format!("error path of codel `{}` of `{m}.{}`", c.state, s.name),
            );
            let fail_ports = vec![port(&comp, &fail_port(c.state))];
            self.connectors.push((
                connector(&fail, fail_ports, Role::Progress),
                guard,
                Vec::new(),
            ));
            let holds = holds.into_iter().map(RecipeCondition::from).collect();
            service.codels.push(RecipeCodel {
                state: c.state.to_string(),
                run,
                fail,
                yields: c.def.yields.iter().map(|y| y.value.clone()).collect(),
                from_ether: c.state == "start",
                from_location: s.is_location(c.state),
                throws: c.throws.iter().map(|t| t.to_string()).collect(),
                writes: c
                    .writes
                    .iter()
                    .map(|&w| self.layer.modules[mi].ports[w].to_string())
                    .collect(),
                ids: c
                    .ids
                    .iter()
                    .map(|&k| self.layer.modules[mi].ids[k].0.to_string())
                    .collect(),
                ids_port: (!c.ids.is_empty()).then(|| ids_port(s.name, c.state)),
                holds,
                apart,
            });
        }
        let recipe_module = self.recipe_module(r.module);
        recipe_module.services.push(service);
    }

    /// The connector by which pending activity `r` interrupts again the activities it
    /// interrupts (other than itself) once one of them has been requested since its own
    /// request: GenoM3's control task sends a waiting activity's interrupts again until it
    /// starts (docs/genom.md, "Interrupts"). `None` if `r` interrupts no other activity.
    fn interrupt_connector(&mut self, r: ServiceRef) -> Option<String> {
        let s = self.service(r);
        if !s.is_activity() || s.machine {
            return None;
        }
        let m = self.module_name(r);
        let victims: Vec<ServiceRef> = s
            .interrupts
            .iter()
            .filter(|&&x| x != r.service)
            .map(|&x| ServiceRef {
                module: r.module,
                service: x,
            })
            .collect();
        // a victim to interrupt: requested, or running outside its stop path (the request
        // of `r` left every victim at rest or stopping)
        let to_interrupt = chain(
            BinOp::Or,
            victims.iter().map(|&x| {
                let c = self.comp(x);
                let running = not(at(&c, ETHER));
                let running = if self.service(x).stop.is_some() {
                    and(running, not(member(&c, STOPPING)))
                } else {
                    running
                };
                or(member(&c, REQ), running)
            }),
        )?;
        let comp = self.comp(r);
        let pending = and(at(&comp, ETHER), member(&comp, REQ));
        let ports = victims
            .iter()
            .map(|&x| port(&self.comp(x), "interrupt"))
            .collect();
        let name = interrupt_connector(m, s.name);
        self.claim(
            &name,
            s.def.name.span,
            format!("the interrupts of pending `{m}.{}`", s.name),
        );
        self.connectors.push((
            connector(&name, ports, Role::Progress),
            Some(and(pending, to_interrupt)),
            Vec::new(),
        ));
        Some(name)
    }

    /// The request connector of service `r` (with the interrupts it sends and the `after`
    /// it waits for), and the conditions that refuse a request.
    fn request_connector(
        &mut self,
        r: ServiceRef,
        run_conds: &[Cond],
    ) -> (String, Vec<RecipeCondition>) {
        let s = self.service(r);
        let m = self.module_name(r);
        let mut ports = Vec::new();
        let mut refusals = Vec::new();
        if s.is_activity() {
            let comp = self.comp(r);
            ports.push(port(&comp, "request"));
            if !s.interrupts_itself(r.service) {
                refusals.push(Cond {
                    reason: Reason::AlreadyRequested,
                    expr: and(at(&comp, ETHER), not(member(&comp, REQ))),
                });
            }
        } else {
            ports.push(port(&module_component(m), s.name));
        }
        for &x in s.interrupts.iter().filter(|&&x| x != r.service) {
            let target = ServiceRef {
                module: r.module,
                service: x,
            };
            ports.push(port(&self.comp(target), "interrupt"));
        }
        if !s.is_activity() {
            ports.extend(self.sleeper_ports(r.module, &s.interrupts));
        }
        for &a in &s.after {
            let target = ServiceRef {
                module: r.module,
                service: a,
            };
            let t = self.service(target);
            let flag = if t.is_activity() {
                member(&self.comp(target), DONE)
            } else {
                member(&module_component(m), &done_var(t.name))
            };
            refusals.push(Cond {
                reason: Reason::After {
                    service: format!("{m}.{}", t.name),
                },
                expr: flag,
            });
        }
        if !s.is_activity() {
            refusals.extend(run_conds.iter().cloned());
        }
        // the request port's own guards say "already requested"; the others guard the
        // connector
        let guard = all(refusals
            .iter()
            .filter(|c| c.reason != Reason::AlreadyRequested)
            .map(|c| c.expr.clone()));
        let name = request_connector(m, s.name);
        self.claim(
            &name,
            s.def.name.span,
            format!("requests of `{m}.{}`", s.name),
        );
        // a function's codel fails: the same request, its reply an exception (the module
        // port that marks a success is the failure's instead)
        if let Some(c) = &s.function {
            let mut fail_ports = ports.clone();
            fail_ports[0] = port(&module_component(m), &request_fail_port(s.name, c.state));
            let fail = fail_connector(m, s.name, c.state);
            self.claim(
                &fail,
                c.def.state.span,
                format!("error path of the codel of `{m}.{}`", s.name),
            );
            self.connectors.push((
                connector(&fail, fail_ports, Role::Environment),
                guard.clone(),
                Vec::new(),
            ));
        }
        // a `validate` codel refuses the request: nothing else happens, and only where
        // the request could be accepted
        if s.validate.is_some() {
            let refuse = fail_connector(m, s.name, VALIDATE);
            self.claim(
                &refuse,
                s.def.name.span,
                format!("refusals of `{m}.{}` by its `validate` codel", s.name),
            );
            let ports = vec![port(
                &module_component(m),
                &request_fail_port(s.name, VALIDATE),
            )];
            let refused = all(refusals.iter().map(|c| c.expr.clone()));
            self.connectors.push((
                connector(&refuse, ports, Role::Environment),
                refused,
                Vec::new(),
            ));
        }
        let mut action = Vec::new();
        if let Some(c) = &s.function {
            action = self.age_resets(r.module, &c.writes);
        }
        self.connectors
            .push((connector(&name, ports, Role::Environment), guard, action));
        (
            name,
            refusals.into_iter().map(RecipeCondition::from).collect(),
        )
    }

    /// `m.age_p = 0` for each port of `written` whose age is tracked.
    fn age_resets(&self, mi: usize, written: &[usize]) -> Vec<Assign> {
        let m = self.layer.modules[mi].name;
        written
            .iter()
            .filter(|&&w| {
                self.caps.contains_key(&PortRef {
                    module: mi,
                    port: w,
                })
            })
            .map(|&w| {
                let age = age_var(self.layer.modules[mi].ports[w]);
                assign(member(&module_component(m), &age), int(0))
            })
            .collect()
    }

    /// The recipe of the codels that run at a request of `r`: a function's codel (its
    /// normal outcome is the request connector `request`) and a `validate` codel (its
    /// success is the request, its failure a refusal).
    fn request_codels(
        &mut self,
        r: ServiceRef,
        request: &str,
    ) -> (Option<RecipeCodel>, Option<RecipeCodel>) {
        let s = self.service(r);
        let m = self.module_name(r);
        let module = &self.layer.modules[r.module];
        let function = s.function.as_ref().map(|c| RecipeCodel {
            state: c.state.to_string(),
            run: request.to_string(),
            fail: fail_connector(m, s.name, c.state),
            yields: vec![ETHER.to_string()],
            from_ether: false,
            from_location: false,
            throws: c.throws.iter().map(|t| t.to_string()).collect(),
            writes: c
                .writes
                .iter()
                .map(|&w| module.ports[w].to_string())
                .collect(),
            ids: c.ids.iter().map(|&k| module.ids[k].0.to_string()).collect(),
            ids_port: (!c.ids.is_empty()).then(|| s.name.to_string()),
            holds: Vec::new(),
            apart: None,
        });
        let validate = s.validate.as_ref().map(|throws| RecipeCodel {
            state: VALIDATE.to_string(),
            run: request.to_string(),
            fail: fail_connector(m, s.name, VALIDATE),
            yields: vec![ETHER.to_string()],
            from_ether: false,
            from_location: false,
            throws: throws.iter().map(|t| t.to_string()).collect(),
            writes: Vec::new(),
            ids: Vec::new(),
            ids_port: None,
            holds: Vec::new(),
            apart: None,
        });
        (function, validate)
    }
}
