//! The inspection view: what an engine's user, a supervisor, a test or the command line
//! may look at without changing anything ([`Engine::inspect`]).

use crate::budgets::CodelTimes;
use core::any::Any;

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::{CacheStats, EnabledSet, State, System};

use super::{Engine, Stats};
use crate::error::EngineError;
use crate::event::{CodelId, Reasons, ServiceId};
use crate::record::Recording;

/// A read-only view of an [`Engine`]: its model and state, names, counters and the state
/// cache's figures. Cheap to make and to copy.
#[derive(Clone, Copy)]
pub struct Inspect<'a> {
    engine: &'a Engine,
}

impl Engine {
    /// A read-only view of the engine (see [`Inspect`]).
    pub fn inspect(&self) -> Inspect<'_> {
        Inspect { engine: self }
    }
}

impl<'a> Inspect<'a> {
    pub fn system(self) -> &'a System {
        self.engine.gate.system()
    }

    /// The current state of the model.
    pub fn state(self) -> &'a State {
        self.engine.gate.state()
    }

    /// The enabled steps of the current state.
    pub fn enabled(self) -> &'a EnabledSet {
        self.engine.gate.enabled()
    }

    /// The range error that stopped the engine, if one did: in a step, or in the initial
    /// state (then the engine is stopped before its first step).
    pub fn stopped(self) -> Option<&'a bip_model::RangeError> {
        self.engine.stopped.as_ref()
    }

    /// Counters since the engine started.
    pub fn stats(self) -> Stats {
        self.engine.stats
    }

    /// How long codel `c`'s runs took, by the engine's clock, and how many exceeded its
    /// WCET.
    pub fn codel_times(self, c: CodelId) -> CodelTimes {
        self.engine.budgets.times[c.0 as usize]
    }

    /// What the state cache holds and how often it knew the step
    /// ([`super::EngineBuilder::state_cache`]).
    pub fn cache_stats(self) -> CacheStats {
        self.engine.gate.cache_stats()
    }

    /// The bytes the state cache and what the engine keeps per cached state hold.
    pub fn cache_bytes(self) -> usize {
        let e = self.engine;
        e.gate.cache_bytes() + e.sched.known_candidates.bytes() + e.held.known.bytes()
    }

    /// The clock's time (microseconds since the engine started).
    pub fn now_us(self) -> u64 {
        self.engine.time.clock.now_us()
    }

    /// The length of a tick.
    pub fn tick_us(self) -> u64 {
        self.engine.time.tick_us
    }

    /// Requests waiting to be served.
    pub fn waiting_requests(self) -> usize {
        self.engine.requests.inbox.len()
    }

    /// Steps recorded so far ([`super::EngineBuilder::record`]).
    pub fn recorded_steps(self) -> usize {
        self.engine.recording.as_ref().map_or(0, Recording::len)
    }

    /// The value of an ids field (`None` if there is no such module or field).
    pub fn ids(self, module: &str, field: &str) -> Option<i64> {
        let m = self.system().genom.as_ref()?.module(module)?;
        let f = m.ids.iter().find(|f| f.name == field)?;
        self.state().slots().get(f.slot as usize).copied()
    }

    /// The data last written on a port, if any and of type `T`.
    pub fn port<T: Any>(self, module: &str, port: &str) -> Option<&'a T> {
        self.engine.runner.ports.get(module, port)
    }

    /// `(module, service, state)` of a codel.
    pub fn codel_name(self, c: CodelId) -> (&'a str, &'a str, &'a str) {
        let i = &self.engine.t.codels[c.0 as usize].info;
        (&i.module, &i.service, &i.state)
    }

    /// `(module, service)` of a service.
    pub fn service_name(self, s: ServiceId) -> (&'a str, &'a str) {
        let s = &self.engine.t.services[s.0 as usize];
        (&s.module, &s.name)
    }

    pub fn codel_id(self, module: &str, service: &str, state: &str) -> Option<CodelId> {
        let t = &self.engine.t;
        t.codel_index(module, service, state)
            .map(|k| CodelId(k as u32))
    }

    pub fn service_id(self, module: &str, service: &str) -> Option<ServiceId> {
        let t = &self.engine.t;
        t.service_index(module, service)
            .map(|k| ServiceId(k as u32))
    }

    pub fn service_count(self) -> usize {
        self.engine.t.services.len()
    }

    pub fn codel_count(self) -> usize {
        self.engine.t.codels.len()
    }

    /// The conditions of a service's refusals that `r` names, as the model writes them.
    pub fn refusal_texts(self, s: ServiceId, r: Reasons) -> impl Iterator<Item = String> + 'a {
        let list = &self.engine.t.services[s.0 as usize].refusals;
        r.iter()
            .filter_map(move |k| list.get(k))
            .map(|c| c.to_string())
    }

    /// The conditions of a codel's holds that `r` names.
    pub fn hold_texts(self, c: CodelId, r: Reasons) -> impl Iterator<Item = String> + 'a {
        let list = &self.engine.t.codels[c.0 as usize].map.holds;
        r.iter()
            .filter_map(move |k| list.get(k))
            .map(|c| c.to_string())
    }

    /// The codels held now: activities with work to do (requested, or running and not
    /// waiting for their period) whose codel has no step, with the conditions that fail.
    pub fn held(self) -> Result<Vec<(CodelId, Reasons)>, EngineError> {
        self.engine.held()
    }

    /// Every activity with work outstanding (requested, or running): the codel it runs
    /// next, whether it waits for its task's period, and the conditions of that codel
    /// that fail now (what holds it once its period comes).
    pub fn outstanding(self) -> Result<Vec<(CodelId, bool, Reasons)>, EngineError> {
        self.engine.outstanding()
    }
}
