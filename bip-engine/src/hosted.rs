//! A module's codels run outside the engine that gates them: in a module process of a
//! distributed layer (docs/distributed.md). The engine grants a codel run and binds the
//! module to a closure that sends the run away; the module's process calls the same
//! codels on a [`Ctx`] built here, with what the engine sent (ids, arguments, port data,
//! time), and sends back what they did. Nothing here is on the one-process engine's path.

use core::any::Any;
use core::cell::Cell;

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::System;

use crate::bind::Tables;
use crate::codel::{call_guarded, CodelInfo, Ctx, CtxFault, ModuleFn, Next};
use crate::engine::EngineBuilder;
use crate::error::BuildError;
use crate::event::{FaultKind, Output};
use crate::ports::PortStore;
use crate::signature::CodelSignature;

/// The codels of one module, run on request outside the engine, with a copy of the
/// layer's port data that the runs' messages keep up to date.
pub struct HostedModule {
    name: String,
    signature: &'static [CodelSignature],
    /// The module's codels, in the order its object numbers them.
    codels: Vec<CodelInfo>,
    ports: PortStore,
    body: ModuleFn,
}

/// One run of a hosted codel: what the engine sent, and what the codel leaves there.
pub struct HostedRun<'a> {
    /// The module's ids fields ([`HostedModule::fields`]), as the engine staged them; the
    /// codel's writes are left there.
    pub ids: &'a mut [i64],
    pub args: Option<&'a (dyn Any + Send)>,
    /// The output the codel gives its service, if it gives one.
    pub output: &'a mut Option<Output>,
    pub now_us: u64,
    pub tick: u64,
}

/// How a hosted run ended.
#[derive(Debug)]
pub struct HostedEnd {
    /// The codel's outcome, or why it is faulty: a panic, or a rule of its model it broke
    /// (in the engine's words, [`FaultKind`]'s).
    pub next: Result<Next, String>,
    /// The ids fields it wrote (bit `k` for field `k`).
    pub written: u64,
}

impl HostedModule {
    /// The codels of `module` of `system`, bound to `f` as [`crate::EngineBuilder::module`]
    /// binds them (and checked against `codels` alike).
    pub fn new(
        system: &System,
        module: &str,
        codels: &'static [CodelSignature],
        f: impl FnMut(usize, &mut Ctx<'_>) -> Next + Send + 'static,
    ) -> Result<HostedModule, BuildError> {
        HostedModule::of(system, module, codels, Box::new(f))
    }

    fn of(
        system: &System,
        module: &str,
        signature: &'static [CodelSignature],
        body: ModuleFn,
    ) -> Result<HostedModule, BuildError> {
        let mut t = Tables::new(system)?;
        let map = system.genom.as_ref().and_then(|g| g.module(module));
        let infos: Vec<CodelInfo> = t
            .codels
            .iter()
            .filter(|c| c.info.module == module)
            .map(|c| c.info.clone())
            .collect();
        let (false, Some(map)) = (infos.is_empty(), map) else {
            return Err(BuildError::UnknownModule(module.into()));
        };
        if let Some(difference) = crate::signature::difference(signature, map) {
            return Err(BuildError::OtherModel {
                module: module.into(),
                difference,
            });
        }
        let ports = PortStore::new(
            core::mem::take(&mut t.ports),
            core::mem::take(&mut t.port_types),
            core::mem::take(&mut t.port_links),
        );
        Ok(HostedModule {
            name: module.into(),
            signature,
            codels: infos,
            ports,
            body,
        })
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// The module's codels as its object numbers them.
    pub fn signature(&self) -> &'static [CodelSignature] {
        self.signature
    }

    pub fn codel_count(&self) -> usize {
        self.codels.len()
    }

    /// The module's ids fields, in the order a run's `ids` holds them.
    pub fn fields(&self) -> impl Iterator<Item = &str> {
        self.codels
            .first()
            .into_iter()
            .flat_map(|c| c.fields.iter().map(|f| f.name.as_str()))
    }

    /// The ports codel `local` may write (its module's, by name).
    pub fn writes(&self, local: usize) -> impl Iterator<Item = &str> {
        self.codels
            .get(local)
            .into_iter()
            .flat_map(|c| c.ports.iter().map(|p| p.1.as_str()))
    }

    /// Sets the data of out port `module.port`, as the engine holds it; an error (in the
    /// engine's words) if the model has no such port or it takes another type.
    pub fn set_port<T: Any + Send + Clone + Default>(
        &mut self,
        module: &str,
        port: &str,
        value: T,
    ) -> Result<(), String> {
        let k = self
            .ports
            .index(module, port)
            .ok_or_else(|| format!("the model has no port `{module}.{port}`"))?;
        match self.ports.get_mut_or_default::<T>(k) {
            Ok(v) => {
                *v = value;
                Ok(())
            }
            Err(w) => Err(format!(
                "port `{}` takes {}, not a `{}`",
                w.port, w.expected, w.given
            )),
        }
    }

    /// The data of port `module.port`, if it holds a `T`.
    pub fn port<T: Any>(&self, module: &str, port: &str) -> Option<&T> {
        self.ports.get(module, port)
    }

    /// Runs codel `local` of the module (caught panics and broken rules are its fault).
    pub fn run(&mut self, local: usize, run: HostedRun<'_>) -> HostedEnd {
        let Some(info) = self.codels.get(local) else {
            return HostedEnd {
                next: Err(format!("the module has no codel {local}")),
                written: 0,
            };
        };
        let mut written = 0;
        let mut fault: Option<CtxFault> = None;
        let mut ctx = Ctx {
            info,
            ids: run.ids,
            written: &mut written,
            fault: Cell::from_mut(&mut fault),
            ports: &mut self.ports,
            args: run.args,
            output: Some(run.output),
            now_us: run.now_us,
            tick: run.tick,
        };
        let body = &mut self.body;
        let next = call_guarded(&mut ctx, |ctx: &mut Ctx<'_>| body(local, ctx));
        let next = match (next, fault) {
            (Ok(_), Some(f)) => Err(FaultKind::from(f).to_string()),
            (next, _) => next.map_err(|m| FaultKind::Panic(m).to_string()),
        };
        HostedEnd { next, written }
    }
}

impl EngineBuilder {
    /// The objects bound to `modules` on this builder (with [`EngineBuilder::module`], as
    /// generated bindings bind them: the same code as for one process), to run in this
    /// process for an engine in another. A module not bound to an object is
    /// [`BuildError::UnknownModule`].
    pub fn hosted(mut self, modules: &[&str]) -> Result<Vec<HostedModule>, BuildError> {
        let mut out = Vec::with_capacity(modules.len());
        for &m in modules {
            let (system, taken) = self.take_module(m);
            let Some((signature, f)) = taken else {
                return Err(BuildError::UnknownModule(m.into()));
            };
            out.push(HostedModule::of(system, m, signature, f)?);
        }
        Ok(out)
    }
}
