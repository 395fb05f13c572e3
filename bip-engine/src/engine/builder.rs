//! Building an engine: binding codels, choosing a clock, a policy, recording, the cache.

use alloc::collections::VecDeque;

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::{Gate, System};

use super::{Budgets, Engine, EventQueue, HeldReports, Inbox, Runner, Schedule, Stats, Time};
use crate::bind::Tables;
use crate::budgets::{CodelTime, CodelTimes, SimulatedCpus, SimulatedTask, TaskClock};
use crate::chosen::Chosen;
use crate::clock::Clock;
use crate::codel::{Body, CodelFn, Ctx, DefaultCodels, ModuleFn, Next};
use crate::error::BuildError;
use crate::event::{Event, EventFn};
use crate::per_state::PerState;
use crate::policy::{Chooser, Policy, Rng};
use crate::ports::PortStore;
use crate::record::Recording;
use crate::signature::{CodelSignature, ModuleTypes};

/// How many states [`EngineBuilder::state_cache`] remembers by default: about 1.5 MiB
/// for a model the size of robots/rover.ron, at the 1.5 KiB per state measured there
/// (docs/engine-internals.md, "The state cache").
pub const DEFAULT_STATE_CACHE: usize = 1024;

/// Builds an [`Engine`]: bind codels, choose a clock, a policy, recording.
pub struct EngineBuilder {
    system: System,
    bindings: Vec<((String, String, String), CodelFn)>,
    modules: Vec<(String, &'static [CodelSignature], ModuleFn)>,
    /// Codels of module objects bound to closures of their own: (module, the codel's
    /// number in its object, the closure).
    apart: Vec<(String, usize, CodelFn)>,
    typed: Vec<(String, &'static ModuleTypes)>,
    defaults: Option<DefaultCodels>,
    clock: Option<Box<dyn Clock>>,
    policy: Policy,
    tick_us: Option<u64>,
    record: Option<Recording>,
    event_capacity: usize,
    on_event: Option<EventFn>,
    threads: bool,
    state_cache: usize,
    codel_time: CodelTime,
}

impl EngineBuilder {
    /// The model, and the object bound to module `module` (taken away), for
    /// [`crate::HostedModule`].
    pub(crate) fn take_module(
        &mut self,
        module: &str,
    ) -> (&System, Option<(&'static [CodelSignature], ModuleFn)>) {
        let k = self.modules.iter().position(|m| m.0 == module);
        let taken = k.map(|k| {
            let (_, signature, f) = self.modules.swap_remove(k);
            let mut apart: Vec<(usize, CodelFn)> = Vec::new();
            let mut j = 0;
            while j < self.apart.len() {
                if self.apart[j].0 == module {
                    let (_, local, g) = self.apart.swap_remove(j);
                    apart.push((local, g));
                } else {
                    j += 1;
                }
            }
            (signature, with_apart(f, apart))
        });
        (&self.system, taken)
    }

    /// Binds codel `state` of service `service` of module `module`.
    pub fn codel(
        mut self,
        (module, service, state): (&str, &str, &str),
        f: impl FnMut(&mut Ctx<'_>) -> Next + Send + 'static,
    ) -> Self {
        self.bindings
            .push(((module.into(), service.into(), state.into()), Box::new(f)));
        self
    }

    /// How long unbound codels take (default: as early as the model allows). In a timed
    /// model, when each finishes after its start: at its BCET, its WCET, or in between
    /// (docs/engine.md, "Codel times"). In an untimed one, with a simulated time, the
    /// tasks' work runs on CPUs scheduled as `bip sched` assumes, and a deadline is judged
    /// when the work ends there.
    pub fn codel_time(mut self, t: CodelTime) -> Self {
        self.codel_time = t;
        self
    }

    /// Binds every codel of module `module` to one object: `f(k, ctx)` runs the module's
    /// `k`-th codel, in the GenoM map's order (its services, then their codels, as
    /// declared), which `codels` names with their outcomes: the build fails if the model
    /// says otherwise. This is how generated bindings bind a module (docs/codegen.md): one
    /// object serves all its codels, with no lock, since the engine calls one codel at a
    /// time. With [`EngineBuilder::threads`], a module whose codels run on several tasks
    /// is called from their threads one at a time, behind a lock; so is an object that runs
    /// an async codel itself, whose other codels then wait while it runs (bind it with
    /// [`EngineBuilder::apart`] instead).
    pub fn module(
        mut self,
        module: &str,
        codels: &'static [CodelSignature],
        f: impl FnMut(usize, &mut Ctx<'_>) -> Next + Send + 'static,
    ) -> Self {
        self.modules.push((module.into(), codels, Box::new(f)));
        self
    }

    /// Binds codel `k` of module `module`'s object (numbered as [`EngineBuilder::module`]
    /// numbers them) to a closure of its own, which the object is then never asked to
    /// run. This is how generated bindings bind an async codel: it runs on a thread of
    /// its own without borrowing the module object, which serves the module's other
    /// codels meanwhile (docs/engine.md, "Threads"). A codel the model does not make
    /// async runs as any closure bound with [`EngineBuilder::codel`].
    pub fn apart(
        mut self,
        module: &str,
        k: usize,
        f: impl FnMut(&mut Ctx<'_>) -> Next + Send + 'static,
    ) -> Self {
        self.apart.push((module.into(), k, Box::new(f)));
        self
    }

    /// Declares the data types of module `module` that typed code assumes (generated
    /// bindings do, for every module): the build fails if the model declares others.
    pub fn typed_as(mut self, module: &str, types: &'static ModuleTypes) -> Self {
        self.typed.push((module.into(), types));
        self
    }

    /// Runs unbound codels with a default instead of refusing to build.
    pub fn default_codels(mut self, d: DefaultCodels) -> Self {
        self.defaults = Some(d);
        self
    }

    /// The clock (default: a [`crate::VirtualClock`]).
    pub fn clock(mut self, c: impl Clock + 'static) -> Self {
        self.clock = Some(Box::new(c));
        self
    }

    pub fn policy(mut self, p: Policy) -> Self {
        self.policy = p;
        self
    }

    /// The length of a tick (default: the model's `tick_ms`, else 1 ms).
    pub fn tick_us(mut self, us: u64) -> Self {
        self.tick_us = Some(us.max(1));
        self
    }

    /// Records the steps for [`Engine::record`], with room for `capacity` steps before
    /// the recording allocates.
    pub fn record(mut self, capacity: usize) -> Self {
        self.record = Some(Recording::with_capacity(capacity));
        self
    }

    /// Records only the last `window` to `2 * window` steps, in constant memory, for
    /// [`Engine::record_window`] and [`Engine::take_record`].
    pub fn record_window(mut self, window: usize) -> Self {
        self.record = Some(Recording::window(window));
        self
    }

    /// How many events the engine keeps for [`Engine::events`] (default 1024; the oldest
    /// are dropped and counted in [`Stats::events_dropped`]).
    pub fn event_capacity(mut self, n: usize) -> Self {
        self.event_capacity = n;
        self
    }

    /// Calls `f` with every event as it happens (besides queueing it).
    pub fn on_event(mut self, f: impl FnMut(&Event) + Send + 'static) -> Self {
        self.on_event = Some(Box::new(f));
        self
    }

    /// Runs the codels of each task on a thread of their own (docs/engine.md, "Threads").
    pub fn threads(mut self, on: bool) -> Self {
        self.threads = on;
        self
    }

    /// Remembers up to `states` states of the model, with their enabled steps and the
    /// steps between them, so that a step taken before from the same state is looked up
    /// rather than computed (default [`DEFAULT_STATE_CACHE`]; 0: none). See
    /// docs/engine-internals.md, "The state cache", and [`crate::Inspect::cache_stats`].
    pub fn state_cache(mut self, states: usize) -> Self {
        self.state_cache = states;
        self
    }

    pub fn build(mut self) -> Result<Engine, BuildError> {
        let system = self.system;
        let unit_us = system.genom.as_ref().and_then(|g| g.time_unit_us);
        // a request that a component of the model sends takes its step without the
        // engine, which could not run its codels at the request first
        if let Some(genom) = &system.genom {
            for m in &genom.modules {
                for s in m.services.iter().filter(|s| s.owned_by_model) {
                    if let Some(c) = s.validate.as_ref().or(s.function.as_ref()) {
                        return Err(BuildError::AtRequest(
                            m.name.clone(),
                            s.name.clone(),
                            c.state.clone(),
                        ));
                    }
                }
            }
        }
        #[cfg(not(feature = "std"))]
        if let Some(genom) = &system.genom {
            for m in &genom.modules {
                for s in &m.services {
                    if let Some(c) = s.codels.iter().find(|c| c.apart.is_some()) {
                        return Err(BuildError::Async(
                            m.name.clone(),
                            s.name.clone(),
                            c.state.clone(),
                        ));
                    }
                }
            }
        }
        let mut t = Tables::new(&system)?;
        if !self.bindings.is_empty() && system.genom.is_none() {
            return Err(BuildError::NoGenomLayer);
        }
        let mut bodies: Vec<Option<Body>> = t.codels.iter().map(|_| None).collect();
        for ((m, s, c), f) in self.bindings {
            let Some(k) = t.codel_index(&m, &s, &c) else {
                return Err(BuildError::UnknownCodel(m, s, c));
            };
            if bodies[k].is_some() {
                return Err(BuildError::BoundTwice(m, s, c));
            }
            bodies[k] = Some(Body::Bound(f));
        }
        for (m, types) in &self.typed {
            let Some(map) = system.genom.as_ref().and_then(|g| g.module(m)) else {
                return Err(BuildError::NoSuchModule(m.clone()));
            };
            if let Some(difference) = crate::signature::types_difference(types, map) {
                return Err(BuildError::OtherModel {
                    module: m.clone(),
                    difference,
                });
            }
        }
        let mut modules = Vec::with_capacity(self.modules.len());
        for (m, signature, f) in self.modules {
            let codels: Vec<usize> = (0..t.codels.len())
                .filter(|&k| t.codels[k].info.module == m)
                .collect();
            let map = system.genom.as_ref().and_then(|g| g.module(&m));
            let (false, Some(map)) = (codels.is_empty(), map) else {
                return Err(BuildError::UnknownModule(m));
            };
            if let Some(difference) = crate::signature::difference(signature, map) {
                return Err(BuildError::OtherModel {
                    module: m,
                    difference,
                });
            }
            for (local, &k) in codels.iter().enumerate() {
                let own = self
                    .apart
                    .iter()
                    .position(|(am, al, _)| *am == m && *al == local)
                    .map(|j| self.apart.swap_remove(j).2);
                if bodies[k].is_some() {
                    let i = &t.codels[k].info;
                    return Err(BuildError::BoundTwice(
                        i.module.clone(),
                        i.service.clone(),
                        i.state.clone(),
                    ));
                }
                bodies[k] = Some(match own {
                    Some(f) => Body::Bound(f),
                    None => Body::Module {
                        module: modules.len(),
                        local,
                    },
                });
            }
            modules.push(f);
        }
        // a closure for a codel no module object of the model has
        if let Some((m, local, _)) = self.apart.first() {
            return Err(BuildError::UnknownApart(m.clone(), *local));
        }
        let mut out = Vec::with_capacity(bodies.len());
        for (k, b) in bodies.into_iter().enumerate() {
            match (b, self.defaults) {
                (Some(b), _) => out.push(b),
                (None, Some(_)) => out.push(Body::Default),
                (None, None) => {
                    let i = &t.codels[k].info;
                    return Err(BuildError::Unbound(
                        i.module.clone(),
                        i.service.clone(),
                        i.state.clone(),
                    ));
                }
            }
        }
        let clock = match self.clock {
            Some(c) => c,
            None => default_clock()?,
        };
        let tick_us = self
            .tick_us
            .or(system.tick_ms.map(|ms| ms.saturating_mul(1000)))
            .unwrap_or(1000)
            .max(1);
        // a timed model's codels take their time in the model itself
        let cpus = (self.codel_time != CodelTime::Zero && unit_us.is_none()).then(|| {
            let tasks = system.genom.iter().flat_map(|g| &g.modules);
            SimulatedCpus::new(
                tasks
                    .flat_map(|m| &m.tasks)
                    .map(|k| SimulatedTask {
                        cpu: k.cpu,
                        priority: k.priority,
                        period_ticks: crate::bind::period_ticks(k),
                        deadline_us: k.deadline_us.unwrap_or_else(|| {
                            crate::bind::period_ticks(k).saturating_mul(tick_us)
                        }),
                    })
                    .collect(),
            )
        });
        // a range error in the initial state is the run's first finding, as in a step: the
        // engine is built, stopped by it
        let (gate, mut stopped) = Gate::at_initial(system, self.state_cache);
        let monitor = match super::monitor::Monitor::new(gate.system(), gate.state()) {
            Ok(m) => m,
            Err(e) => {
                stopped.get_or_insert(e);
                super::monitor::Monitor::none()
            }
        };
        let timed = unit_us.map(|unit_us| {
            let deadlines = t.tasks.iter().map(|&(period_ticks, deadline)| {
                deadline.unwrap_or_else(|| period_ticks.saturating_mul(tick_us))
            });
            let tasks = t
                .timed_tasks
                .iter()
                .zip(deadlines)
                .map(|((name, map), d)| (alloc::sync::Arc::clone(name), *map, d));
            Box::new(super::timed::Timed::new(unit_us, clock.now_us(), tasks))
        });
        let monitor = monitor.with_deadlines(
            timed
                .as_ref()
                .is_some_and(|t| t.deadlines().next().is_some()),
        );
        let pool = gate.enabled().pool();
        let plan_moves = gate
            .plans()
            .steps()
            .map(|(i, at, width)| {
                t.step_moves_request(i, &pool[at as usize..(at + width) as usize])
            })
            .collect();
        let ports = PortStore::new(
            core::mem::take(&mut t.ports),
            core::mem::take(&mut t.port_types),
            core::mem::take(&mut t.port_links),
        );
        let max_fields = t.codels.iter().map(|c| c.info.fields.len()).max();
        let activities = t.activities.len();
        // an async codel runs on a thread of its own, beside its module's other codels
        #[cfg(feature = "std")]
        let apart = {
            let module_apart = out
                .iter()
                .enumerate()
                .any(|(k, b)| matches!(b, Body::Module { .. }) && t.codels[k].map.apart.is_some());
            if module_apart {
                crate::threads::share_modules(&mut out, core::mem::take(&mut modules));
            }
            super::apart::Apart::spawn(&t, &mut out)
        };
        #[cfg(feature = "std")]
        let workers = if self.threads {
            crate::threads::share_modules(&mut out, core::mem::take(&mut modules));
            Some(crate::threads::Workers::spawn(&t, &mut out))
        } else {
            None
        };
        #[cfg(not(feature = "std"))]
        if self.threads {
            return Err(BuildError::NoThreads);
        }
        let now = clock.now_us();
        let budgets = Budgets {
            times: vec![CodelTimes::default(); t.codels.len()],
            tasks: t
                .tasks
                .iter()
                .map(|&(period_ticks, deadline)| {
                    let deadline_us =
                        deadline.unwrap_or_else(|| period_ticks.saturating_mul(tick_us));
                    TaskClock::new(period_ticks, deadline_us, now)
                })
                .collect(),
            codel_time: self.codel_time,
            cpus,
            rng: Rng::new(match self.codel_time {
                CodelTime::Random(seed) => seed,
                _ => 0,
            }),
        };
        Ok(Engine {
            gate,
            t,
            plan_moves,
            chosen: Chosen::with_capacity(16),
            forced: Vec::with_capacity(16),
            runner: Runner {
                bodies: out,
                modules,
                ports,
                ids: Vec::with_capacity(max_fields.unwrap_or(0)),
                written: 0,
                fault: None,
                defaults: self.defaults.unwrap_or(DefaultCodels::FirstYield),
                rng: Rng::new(match self.defaults {
                    Some(DefaultCodels::Random(s)) => s,
                    _ => 0,
                }),
                #[cfg(feature = "std")]
                workers,
                request_args: None,
                request_output: None,
            },
            time: Time {
                clock,
                tick_us,
                next_tick_us: now + tick_us,
            },
            sched: Schedule {
                chooser: Chooser::new(self.policy),
                candidates: Vec::with_capacity(16),
                known_candidates: PerState::new(),
                codel_stamp: Vec::new(),
            },
            held: HeldReports {
                known: PerState::new(),
                now: Vec::with_capacity(activities),
                dirty: true,
            },
            requests: Inbox {
                inbox: VecDeque::with_capacity(16),
                next_ticket: 0,
            },
            events: EventQueue {
                queue: VecDeque::with_capacity(self.event_capacity.min(4096)),
                capacity: self.event_capacity,
                on_event: self.on_event,
            },
            recording: self.record,
            stats: Stats::default(),
            budgets,
            stopped,
            monitor,
            timed,
            #[cfg(feature = "std")]
            remote: None,
            #[cfg(feature = "std")]
            apart,
        })
    }
}

#[cfg(target_has_atomic = "64")]
fn default_clock() -> Result<Box<dyn Clock>, BuildError> {
    Ok(Box::new(crate::clock::VirtualClock::new()))
}

#[cfg(not(target_has_atomic = "64"))]
fn default_clock() -> Result<Box<dyn Clock>, BuildError> {
    Err(BuildError::NoClock)
}

impl Engine {
    /// Starts building an engine for `system`.
    pub fn builder(system: System) -> EngineBuilder {
        EngineBuilder {
            system,
            bindings: Vec::new(),
            modules: Vec::new(),
            apart: Vec::new(),
            typed: Vec::new(),
            defaults: None,
            clock: None,
            policy: Policy::default(),
            tick_us: None,
            record: None,
            event_capacity: 1024,
            on_event: None,
            threads: false,
            state_cache: DEFAULT_STATE_CACHE,
            codel_time: CodelTime::Zero,
        }
    }
}

/// A module object whose codels listed in `apart` are those closures: one object again,
/// for a module run outside the engine ([`crate::HostedModule`]), which calls one codel
/// at a time.
fn with_apart(mut object: ModuleFn, mut apart: Vec<(usize, CodelFn)>) -> ModuleFn {
    if apart.is_empty() {
        return object;
    }
    Box::new(
        move |k, ctx| match apart.iter_mut().find(|(j, _)| *j == k) {
            Some((_, f)) => f(ctx),
            None => object(k, ctx),
        },
    )
}
