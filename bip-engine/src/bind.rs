//! The engine's tables, read once from the compiled system and its GenoM map: what each
//! interaction is to the engine (a codel, a request, a tick, another step), and per codel
//! and service what the engine needs to run it, reply and explain.

#[allow(unused_imports)]
use crate::prelude::*;

use alloc::sync::Arc;

use bip_model::genom::map::{DataType, GenomMap};
use bip_model::genom::{CodelMap, Condition, TimedTaskMap};
use bip_model::{Pick, Role, System};

use crate::codel::{CodelInfo, Field};
use crate::error::BuildError;
use crate::event::{Codel, CodelId, Output, Reasons, Service, ServiceId, Ticket};
use crate::types::Args;

/// What an interaction is to the engine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum InterKind {
    /// A codel's normal outcomes (`fail: false`) or error path (`fail: true`).
    Codel { codel: u32, fail: bool },
    /// An async codel's start: it then runs apart (docs/genom.md, "Async codels").
    Start { codel: u32 },
    /// An async codel's return: committed when its run apart has ended.
    Return { codel: u32 },
    /// A timed model's codel start: the codel takes its task's core, and its body runs;
    /// its finish ([`InterKind::Codel`]) comes once its time has passed
    /// (docs/engine.md, "Codel times").
    TimedStart { codel: u32 },
    /// A timed codel's finish that drops its outcome: its activity left it while it ran.
    Dropped { codel: u32 },
    /// A service's request, sent by the engine on behalf of a client.
    Request { service: u32 },
    /// The error path of a codel that runs at a request (docs/genom.md, "Codels at the
    /// request"): a function's failed reply, or a validation's refusal; taken only by the
    /// engine serving the request.
    AtRequestFail { codel: u32 },
    /// A `Time` step: fired once per tick.
    Time,
    /// Progress the model takes by itself (connectors of yours, model-owned requests).
    Progress,
    /// A stimulus from outside that is not a GenoM request: fired only when asked
    /// (`Engine::step_as`).
    Environment,
}

/// What a port of an activity's atom does in its life cycle (docs/genom.md, section 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PortKind {
    Request,
    Interrupt,
    Abort,
    Tick,
    Run(u32),
    Fail(u32),
}

pub(crate) struct CodelTable {
    /// What events say of it.
    pub name: Arc<Codel>,
    pub map: CodelMap,
    pub service: u32,
    /// The module's component (where the ids are).
    pub module_component: u32,
    /// Its exceptions, shared with the outcomes that name them.
    pub throws: Vec<Arc<str>>,
    pub info: CodelInfo,
    /// For each of `map.ids`, its index among the module's fields.
    pub ids_field: Vec<usize>,
    /// Its task's period in ticks ([`period_ticks`]).
    pub period_ticks: u64,
    /// Its task, an index into [`Tables::tasks`].
    pub task: Option<u32>,
    /// The last yield it returned, and its index in `map.yields`. A codel returns the
    /// same literals again and again, and the text at a `&'static str`'s address never
    /// changes (it is never freed), so the same address and length are the same yield
    /// without comparing the text.
    pub last_yield: Option<(&'static str, usize)>,
    /// The run step last taken from a step table entry of its run interaction (see
    /// [`RunStep`]).
    pub run_step: Option<RunStep>,
    /// It runs at a request (a function's codel, a `validate` codel): it reads the
    /// request's arguments before the request is accepted.
    pub at_request: bool,
}

/// A codel's run step found among the steps of a step table entry: when its run
/// interaction's steps are that entry again ([`bip_model::EnabledSet::pooled_steps`]) and
/// the codel yields the same, the step is the same (the pool never changes), and it was
/// the only one that matched, so the policy had no choice to make.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RunStep {
    /// Where the entry's steps start in the pool.
    pub entry: u32,
    pub yield_k: u32,
    /// Where the step's picks start in the pool.
    pub step: u32,
}

impl CodelTable {
    /// The index of yield `y` (as a codel returns it) among the codel's yields.
    pub fn yield_index(&mut self, y: &'static str) -> Option<usize> {
        if let Some((last, k)) = self.last_yield {
            // the address and the length
            if core::ptr::eq(last, y) {
                return Some(k);
            }
        }
        let k = self.map.yields.iter().position(|x| x.target == y)?;
        self.last_yield = Some((y, k));
        Some(k)
    }
}

pub(crate) struct ServiceTable {
    /// What events say of it.
    pub name_ref: Arc<Service>,
    pub module: String,
    pub name: String,
    /// The activity's task.
    #[cfg_attr(not(feature = "std"), allow(dead_code))]
    pub task: Option<String>,
    /// `None` for a task's machine, which nothing requests.
    pub request: Option<u32>,
    pub owned: bool,
    pub refusals: Vec<Condition>,
    /// What its requests' arguments may be.
    pub args: Args,
    pub activity: Option<ActivityTable>,
    /// Its `validate` codel and a function's codel, which run when it is requested.
    pub validate: Option<u32>,
    pub function: Option<u32>,
}

pub(crate) struct ActivityTable {
    pub component: u32,
    pub loc_slot: u32,
    pub ether: u32,
    pub req_slot: u32,
    pub paused_slot: u32,
    pub stopping_slot: Option<u32>,
    /// Per port of the atom.
    pub port_kind: Vec<Option<PortKind>>,
    /// Per location, the codel that runs from there (`start` from `ether`).
    pub codel_at: Vec<Option<u32>>,
    // the requests it serves
    pub current: Option<Ticket>,
    pub pending: Option<Ticket>,
    pub current_args: Option<Box<dyn core::any::Any + Send>>,
    pub pending_args: Option<Box<dyn core::any::Any + Send>>,
    /// What the current request's codels gave as its output so far.
    pub output: Option<Output>,
}

/// An activity as a quiescent point looks at it ([`Rest`]), and the held codel last
/// reported for it, with why.
pub(crate) struct Watched {
    pub service: u32,
    pub rest: Rest,
    pub held: Option<(u32, Reasons)>,
}

/// The slots that tell whether an activity is at rest (its [`ActivityTable`]'s, kept
/// together: a quiescent point asks every activity).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rest {
    paused_slot: u32,
    loc_slot: u32,
    req_slot: u32,
    ether: u32,
}

pub(crate) struct Tables {
    pub kind: Vec<InterKind>,
    /// Per interaction, whether a step of it can move a request along an activity's life
    /// cycle (a port of an activity's atom other than its tick): the others, ticks first,
    /// need no tracking.
    pub moves_requests: Vec<bool>,
    /// Per transition of an activity's atom (`moving[moving_start[c] + t]` for transition
    /// `t` of component `c`), whether taking it moves a request along the life cycle: a
    /// request, interrupt, abort or error path, or a codel that starts or ends its
    /// activity. A codel step that moves none (the codel runs again, or pauses) needs no
    /// tracking.
    pub moving_start: Vec<u32>,
    pub moving: Vec<bool>,
    pub codels: Vec<CodelTable>,
    pub services: Vec<ServiceTable>,
    /// Per component, the service whose activity it is.
    pub activity_of: Vec<Option<u32>>,
    /// The activities (of the services that have one), in service order: the only ones
    /// that can hold a codel.
    pub activities: Vec<Watched>,
    /// (module, port) per port store entry.
    pub ports: Vec<(String, String)>,
    /// The declared type of each port's data.
    pub port_types: Vec<Option<DataType>>,
    /// (module, in port, the port store entry of the out port it reads) per connected in
    /// port: its codels read the writer's data under the in port's name.
    pub port_links: Vec<(String, String, usize)>,
    /// The system has internal transitions: without any, the engine need not look for
    /// their steps (a GenoM layer has none).
    pub has_internal: bool,
    /// The `Time` interactions, in index order.
    pub time: Vec<u32>,
    /// One bit per interaction that can be a progress candidate (a codel's run or error
    /// path, a progress connector): requests and ticks are looked at elsewhere.
    pub progress_mask: Vec<u64>,
    /// The modules' tasks, in order: each one's period in ticks and declared deadline.
    pub tasks: Vec<(u64, Option<u64>)>,
    /// In a timed model, per task of `tasks`: its name (`m.t`) and its atom, if it runs
    /// codels.
    pub timed_tasks: Vec<(Arc<str>, Option<TimedTaskMap>)>,
    /// Per interaction, the service whose pending request sends its interrupts again
    /// through it ([`bip_model::genom::map::ServiceMap::interrupt`]): what it ends was
    /// interrupted by that service.
    pub interrupts_of: Vec<Option<u32>>,
}

impl Tables {
    pub fn new(system: &System) -> Result<Tables, BuildError> {
        let mut kind: Vec<InterKind> = system
            .interactions
            .iter()
            .map(|i| match system.connectors[i.connector as usize].role {
                Role::Time => InterKind::Time,
                Role::Environment => InterKind::Environment,
                Role::Progress => InterKind::Progress,
            })
            .collect();
        let mut t = Tables {
            kind: Vec::new(),
            moves_requests: Vec::new(),
            moving_start: Vec::new(),
            moving: Vec::new(),
            codels: Vec::new(),
            services: Vec::new(),
            activity_of: vec![None; system.components.len()],
            activities: Vec::new(),
            ports: Vec::new(),
            port_types: Vec::new(),
            port_links: Vec::new(),
            has_internal: system.summary().internal_transitions > 0,
            time: Vec::new(),
            progress_mask: Vec::new(),
            interrupts_of: vec![None; system.interactions.len()],
            tasks: Vec::new(),
            timed_tasks: Vec::new(),
        };
        let Some(map) = &system.genom else {
            return Ok(t.finish(system, kind));
        };
        for m in &map.modules {
            let fields: Vec<Field> = m
                .ids
                .iter()
                .map(|f| Field {
                    name: f.name.clone(),
                    slot: f.slot,
                    lo: f.lo,
                    hi: f.hi,
                })
                .collect();
            if fields.len() > 64 {
                return Err(BuildError::TooMany(
                    format!("module {}", m.name),
                    "ids fields",
                ));
            }
            let port_base = t.ports.len();
            let task_base = t.tasks.len() as u32;
            t.tasks
                .extend(m.tasks.iter().map(|k| (period_ticks(k), k.deadline_us)));
            if map.time_unit_us.is_some() {
                t.timed_tasks.extend(
                    m.tasks
                        .iter()
                        .map(|k| (Arc::from(format!("{}.{}", m.name, k.name)), k.timed)),
                );
            }
            for p in &m.ports {
                t.ports.push((m.name.clone(), p.name.clone()));
                t.port_types.push(p.ty.clone());
            }
            for s in &m.services {
                let sid = t.services.len() as u32;
                if s.refusals.len() > 64 {
                    return Err(BuildError::TooMany(
                        format!("service {}.{}", m.name, s.name),
                        "refusal conditions",
                    ));
                }
                if let Some(r) = s.request.filter(|_| !s.owned_by_model) {
                    kind[r as usize] = InterKind::Request { service: sid };
                }
                if let Some(i) = s.interrupt {
                    t.interrupts_of[i as usize] = Some(sid);
                }
                let period_ticks = s.task.and_then(|k| m.tasks.get(k)).map_or(1, period_ticks);
                let mut activity = None;
                if let Some(comp) = s.component {
                    t.activity_of[comp as usize] = Some(sid);
                    let a = activity_table(system, comp, t.codels.len() as u32, s)?;
                    t.activities.push(Watched {
                        service: sid,
                        rest: a.rest(),
                        held: None,
                    });
                    activity = Some(a);
                }
                for c in &s.codels {
                    let cid = t.codels.len() as u32;
                    kind[c.run as usize] = InterKind::Codel {
                        codel: cid,
                        fail: false,
                    };
                    kind[c.fail as usize] = InterKind::Codel {
                        codel: cid,
                        fail: true,
                    };
                    if let Some(a) = c.apart {
                        kind[a.start as usize] = InterKind::Start { codel: cid };
                        kind[a.returned as usize] = InterKind::Return { codel: cid };
                    }
                    if let Some(tc) = c.timed {
                        kind[tc.start as usize] = InterKind::TimedStart { codel: cid };
                        if let Some(d) = tc.dropped {
                            kind[d as usize] = InterKind::Dropped { codel: cid };
                        }
                    }
                    let k = codel_table(m, s, c, sid, &fields, port_base, period_ticks, cid)?;
                    t.codels.push(CodelTable {
                        task: s.task.map(|k| task_base + k as u32),
                        ..k
                    });
                }
                // the codels at a request: their success is the request's step
                let mut at_request = [None, None];
                for (slot, c) in at_request.iter_mut().zip([&s.validate, &s.function]) {
                    let Some(c) = c else { continue };
                    let cid = t.codels.len() as u32;
                    kind[c.fail as usize] = InterKind::AtRequestFail { codel: cid };
                    let k = codel_table(m, s, c, sid, &fields, port_base, period_ticks, cid)?;
                    t.codels.push(CodelTable {
                        at_request: true,
                        ..k
                    });
                    *slot = Some(cid);
                }
                t.services.push(ServiceTable {
                    name_ref: Arc::new(Service {
                        id: ServiceId(sid),
                        module: m.name.clone(),
                        name: s.name.clone(),
                        refusals: s.refusals.iter().map(ToString::to_string).collect(),
                    }),
                    module: m.name.clone(),
                    name: s.name.clone(),
                    task: s.task.and_then(|k| m.tasks.get(k)).map(|t| t.name.clone()),
                    request: s.request,
                    owned: s.owned_by_model,
                    refusals: s.refusals.clone(),
                    args: Args {
                        service: format!("{}.{}", m.name, s.name),
                        ty: s.args.clone(),
                        has_codels: !s.codels.is_empty() || at_request.iter().any(Option::is_some),
                    },
                    activity,
                    validate: at_request[0],
                    function: at_request[1],
                });
            }
        }
        t.port_links = port_links(map);
        Ok(t.finish(system, kind))
    }

    fn finish(mut self, system: &System, kind: Vec<InterKind>) -> Tables {
        self.progress_mask = vec![0; kind.len().div_ceil(64)];
        for (i, k) in kind.iter().enumerate() {
            // a timed codel's finish is the engine's choice of its time, not a candidate
            let progress = match *k {
                InterKind::Codel { codel, .. } => self.codels[codel as usize].map.timed.is_none(),
                InterKind::Start { .. } | InterKind::TimedStart { .. } | InterKind::Progress => {
                    true
                }
                _ => false,
            };
            if progress {
                self.progress_mask[i / 64] |= 1 << (i % 64);
            }
            if *k == InterKind::Time {
                self.time.push(i as u32);
            }
        }
        self.moves_requests = system
            .interactions
            .iter()
            .map(|i| {
                i.ports.iter().any(|p| {
                    let activity = self.activity_of[p.component as usize]
                        .and_then(|s| self.services[s as usize].activity.as_ref());
                    activity.is_some_and(|a| {
                        let port = a.port_kind.get(p.port as usize).copied().flatten();
                        port.is_some_and(|k| k != PortKind::Tick)
                    })
                })
            })
            .collect();
        for c in 0..system.components.len() {
            self.moving_start.push(self.moving.len() as u32);
            let activity =
                self.activity_of[c].and_then(|s| self.services[s as usize].activity.as_ref());
            let Some(a) = activity else { continue };
            for tr in &system.atom_of(c as u32).transitions {
                let port = tr
                    .port
                    .and_then(|p| a.port_kind.get(p as usize).copied().flatten());
                self.moving.push(match port {
                    None | Some(PortKind::Tick) => false,
                    Some(PortKind::Run(_)) => tr.from == a.ether || tr.to == a.ether,
                    Some(_) => true,
                });
            }
        }
        self.moving_start.push(self.moving.len() as u32);
        self.kind = kind;
        self
    }

    /// Whether a step of interaction `i` with `picks` moves a request along an activity's
    /// life cycle (and must be tracked for replies).
    #[inline]
    pub fn step_moves_request(&self, i: u32, picks: &[Pick]) -> bool {
        self.moves_requests[i as usize] && picks.iter().any(|&p| self.moves_request(p))
    }

    /// Whether the pick moves a request along its activity's life cycle (see `moving`).
    pub fn moves_request(&self, p: Pick) -> bool {
        let (start, end) = (
            self.moving_start[p.component as usize],
            self.moving_start[p.component as usize + 1],
        );
        start + p.transition < end && self.moving[(start + p.transition) as usize]
    }

    pub fn codel_index(&self, module: &str, service: &str, state: &str) -> Option<usize> {
        self.codels.iter().position(|c| {
            c.info.module == module && c.info.service == service && c.info.state == state
        })
    }

    pub fn service_index(&self, module: &str, service: &str) -> Option<usize> {
        self.services
            .iter()
            .position(|s| s.module == module && s.name == service)
    }
}

impl ActivityTable {
    pub fn rest(&self) -> Rest {
        Rest {
            paused_slot: self.paused_slot,
            loc_slot: self.loc_slot,
            req_slot: self.req_slot,
            ether: self.ether,
        }
    }
}

impl Rest {
    /// True if the activity has no work now (not requested and in `ether`), or waits for
    /// its task's period: then none of its codels is held, whatever the conditions.
    #[inline]
    pub fn at_rest(&self, slots: &[i64]) -> bool {
        slots[self.paused_slot as usize] != 0
            || (slots[self.loc_slot as usize] == i64::from(self.ether)
                && slots[self.req_slot as usize] == 0)
    }
}

fn activity_table(
    system: &System,
    comp: u32,
    first_codel: u32,
    s: &bip_model::genom::ServiceMap,
) -> Result<ActivityTable, BuildError> {
    let atom = system.atom_of(comp);
    let c = &system.components[comp as usize];
    let var = |name: &str| atom.var_index(name).map(|v| c.var_slot(v));
    let codel_by_state = |state: &str| {
        s.codels
            .iter()
            .position(|k| k.state == state)
            .map(|k| first_codel + k as u32)
    };
    let port_kind = atom
        .ports
        .iter()
        .map(|p| match p.as_str() {
            "request" => Some(PortKind::Request),
            "interrupt" => Some(PortKind::Interrupt),
            "abort" => Some(PortKind::Abort),
            "tick" => Some(PortKind::Tick),
            other => match other.strip_suffix("_fail").and_then(codel_by_state) {
                Some(k) => Some(PortKind::Fail(k)),
                // an async codel's start takes up the request as its run would
                None => codel_by_state(other)
                    .or_else(|| other.strip_suffix("_start").and_then(codel_by_state))
                    .map(PortKind::Run),
            },
        })
        .collect();
    let codel_at = atom
        .locations
        .iter()
        .map(|l| {
            if l == "ether" {
                codel_by_state("start")
            } else {
                codel_by_state(l)
            }
        })
        .collect();
    let missing =
        || BuildError::UnknownCodel(s.name.clone(), "<activity atom>".into(), "req".into());
    Ok(ActivityTable {
        component: comp,
        loc_slot: c.slot,
        ether: atom.location_index("ether").ok_or_else(missing)?,
        req_slot: var("req").ok_or_else(missing)?,
        paused_slot: var("paused").ok_or_else(missing)?,
        stopping_slot: var("stopping"),
        port_kind,
        codel_at,
        current: None,
        pending: None,
        current_args: None,
        pending_args: None,
        output: None,
    })
}

/// What the engine keeps of codel `c` of service `s` of module `m` (numbered `cid`):
/// its names, exceptions, ids fields and written ports; no task, and not at a request
/// (the caller says).
#[allow(clippy::too_many_arguments)]
fn codel_table(
    m: &bip_model::genom::ModuleMap,
    s: &bip_model::genom::ServiceMap,
    c: &CodelMap,
    sid: u32,
    fields: &[Field],
    port_base: usize,
    period_ticks: u64,
    cid: u32,
) -> Result<CodelTable, BuildError> {
    if c.holds.len() > 64 {
        return Err(BuildError::TooMany(
            format!("codel ({}, {}, {})", m.name, s.name, c.state),
            "hold conditions",
        ));
    }
    let ids_field: Vec<usize> = c
        .ids
        .iter()
        .map(|f| fields.iter().position(|x| x.slot == f.slot).unwrap_or(0))
        .collect();
    let writable = ids_field.iter().fold(0u64, |acc, &k| acc | 1 << k);
    let ports = c
        .writes
        .iter()
        .filter_map(|w| {
            m.ports
                .iter()
                .position(|p| &p.name == w)
                .map(|k| (port_base + k, w.clone()))
        })
        .collect();
    Ok(CodelTable {
        name: Arc::new(Codel {
            id: CodelId(cid),
            module: m.name.clone(),
            service: s.name.clone(),
            state: c.state.clone(),
            holds: c.holds.iter().map(ToString::to_string).collect(),
        }),
        map: c.clone(),
        service: sid,
        module_component: m.component,
        throws: c.throws.iter().map(|x| Arc::from(x.as_str())).collect(),
        info: CodelInfo {
            module: m.name.clone(),
            service: s.name.clone(),
            state: c.state.clone(),
            fields: fields.to_vec(),
            writable,
            ports,
            output: s.output.clone(),
        },
        ids_field,
        period_ticks,
        task: None,
        last_yield: None,
        run_step: None,
        at_request: false,
    })
}

/// A task's period in ticks; for an aperiodic task, which the clock never releases and
/// which has no deadline, more ticks than a run ever has: its clock never releases it,
/// its deadline (the period, lacking one) never passes, and rate-monotonic priorities
/// place it below every periodic task.
pub(crate) fn period_ticks(task: &bip_model::genom::TaskMap) -> u64 {
    task.period.map_or(u64::MAX, u64::from)
}

/// Each connected in port and the port store entry of the out port it reads (the store
/// holds every module's out ports, module after module, in the map's order).
fn port_links(map: &GenomMap) -> Vec<(String, String, usize)> {
    let mut base = Vec::with_capacity(map.modules.len());
    let mut next = 0;
    for m in &map.modules {
        base.push(next);
        next += m.ports.len();
    }
    map.modules
        .iter()
        .flat_map(|m| m.in_ports.iter().map(move |p| (m, p)))
        .filter_map(|(m, p)| {
            let (wm, wp) = p.reads?;
            let k = base.get(wm as usize)? + wp as usize;
            Some((m.name.clone(), p.name.clone(), k))
        })
        .collect()
}
