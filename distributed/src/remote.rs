//! The engine's side: a module whose codels run in another process is bound to a closure
//! that sends each granted run there and brings its outcome back, for the engine to
//! commit through its gate as it commits a codel it ran itself.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use bip_engine::bip_model::genom::ModuleMap;
use bip_engine::{CodelSignature, Ctx, EngineBuilder, ModuleTypes, Next, System, VirtualClock};
use serde_json::Value;

use crate::codec::Types;
use crate::link::RunLink;
use crate::network::{query, Network, NetworkError};
use crate::presence::{Presence, Watch};
use crate::wire::{keys, Answer, Message, PortData, RunEnd, RunGrant, RunResult};

/// How long the engine waits for a module process.
#[derive(Clone, Debug)]
pub struct RemoteOptions {
    /// The deadline of a codel run, beyond the codel's WCET when the model gives one: past
    /// it, the run is the codel's fault and its activity takes its error path.
    pub deadline: Duration,
    /// The engine's virtual clock, if it runs on one: a remote codel's time on its
    /// process's virtual clock ([`RunResult::virtual_us`]) is added to it, as a codel in
    /// the engine's process advances the engine's clock itself.
    pub virtual_clock: Option<VirtualClock>,
    /// How long the engine's thread polls for a run's answer before it sleeps until it
    /// comes (zero: it sleeps at once). Polling saves the wake-up of a sleeping thread,
    /// the most of a round trip on a loaded machine (docs/performance.md), for a CPU kept
    /// busy meanwhile.
    pub spin: Duration,
}

impl Default for RemoteOptions {
    fn default() -> RemoteOptions {
        RemoteOptions {
            deadline: Duration::from_millis(500),
            virtual_clock: None,
            spin: Duration::ZERO,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum RemoteError {
    #[error(transparent)]
    Network(#[from] NetworkError),
    #[error("{0}")]
    Types(String),
    #[error("the model has no module `{0}` with codels")]
    NoSuchModule(String),
    #[error("no process answered for module `{module}` within {waited_ms} ms (key `{key}`)")]
    NoAnswer {
        module: String,
        key: String,
        waited_ms: u128,
    },
    #[error("the process of module `{module}` runs other codels: {difference}")]
    OtherCodels { module: String, difference: String },
}

/// The engine's connection to its module processes.
pub struct RemoteModules {
    session: zenoh::Session,
    prefix: String,
    low_latency: bool,
    types: Arc<Types>,
    system: System,
    options: RemoteOptions,
    presence: Presence,
    /// Held by every proxy too, so that the watch lasts as long as the engine's modules.
    watch: Arc<Watch>,
}

/// What the closure of a remote module knows of its codels.
struct RemoteCodel {
    /// `Service.codel`.
    name: String,
    service: String,
    deadline: Duration,
}

impl RemoteModules {
    /// Opens the engine's zenoh session; every typed datum of `system` must have its codec
    /// in `types`.
    pub fn new(
        network: &Network,
        system: &System,
        types: Types,
        options: RemoteOptions,
    ) -> Result<RemoteModules, RemoteError> {
        types.check(system).map_err(RemoteError::Types)?;
        let session = network.open()?;
        let presence = Presence::default();
        let watch = Arc::new(Watch::start(&session, &network.prefix, &presence)?);
        Ok(RemoteModules {
            session,
            prefix: network.prefix.clone(),
            low_latency: network.low_latency,
            types: Arc::new(types),
            system: system.clone(),
            options,
            presence,
            watch,
        })
    }

    /// The engine's zenoh session (for a [`crate::RequestServer`] beside the modules).
    pub fn session(&self) -> &zenoh::Session {
        &self.session
    }

    /// Which module processes are there: a [`crate::RequestServer`] given it refuses
    /// requests to a module whose process is not.
    pub fn presence(&self) -> &Presence {
        &self.presence
    }

    /// Waits until the process of `module` answers, and checks that it numbers the
    /// module's codels as `codels` does.
    pub fn wait_for(
        &self,
        module: &str,
        codels: &[CodelSignature],
        timeout: Duration,
    ) -> Result<(), RemoteError> {
        let want = codels
            .iter()
            .map(|c| format!("{}.{}", c.service, c.codel))
            .collect();
        self.wait_for_codels(module, want, timeout)
    }

    /// [`RemoteModules::wait_for`], the codels numbered as the model declares them.
    pub fn wait_for_model(&self, module: &str, timeout: Duration) -> Result<(), RemoteError> {
        let want = self
            .model_codels(module)?
            .iter()
            .map(|c| c.name.clone())
            .collect();
        self.wait_for_codels(module, want, timeout)
    }

    fn wait_for_codels(
        &self,
        module: &str,
        want: Vec<String>,
        timeout: Duration,
    ) -> Result<(), RemoteError> {
        let key = keys::hello(&self.prefix, module);
        let start = Instant::now();
        while start.elapsed() < timeout {
            let left = timeout.saturating_sub(start.elapsed());
            let answer = query(
                &self.session,
                &key,
                &Message::Hello,
                left.min(Duration::from_millis(250)),
            );
            if let Ok(Answer::Hello { codels, .. }) = answer {
                if codels != want {
                    return Err(RemoteError::OtherCodels {
                        module: module.into(),
                        difference: format!("it runs {codels:?}, the engine expects {want:?}"),
                    });
                }
                self.presence.mark_present(module);
                return Ok(());
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        Err(RemoteError::NoAnswer {
            module: module.into(),
            key,
            waited_ms: timeout.as_millis(),
        })
    }

    /// Binds module `module` of `builder` to its process: in place of its generated
    /// `bind`, with the same signature and types, which the engine checks against its
    /// model as it does in one process.
    pub fn bind(
        &self,
        builder: EngineBuilder,
        module: &str,
        codels: &'static [CodelSignature],
        types: &'static ModuleTypes,
    ) -> Result<EngineBuilder, RemoteError> {
        let mut proxy = self.proxy(module)?;
        Ok(builder
            .typed_as(module, types)
            .module(module, codels, move |k, ctx| proxy.run(k, ctx)))
    }

    /// Binds module `module` of `builder` to its process without generated bindings:
    /// each of its codels, as the model declares them (`bip run`, a layer whose module
    /// processes are programs of their own).
    pub fn bind_model(
        &self,
        builder: EngineBuilder,
        module: &str,
    ) -> Result<EngineBuilder, RemoteError> {
        let proxy = Arc::new(std::sync::Mutex::new(self.proxy(module)?));
        let codels = self.model_codels(module)?;
        let mut builder = builder;
        for (k, c) in codels.into_iter().enumerate() {
            let proxy = Arc::clone(&proxy);
            let state = c.name.rsplit_once('.').map_or("", |x| x.1).to_string();
            // the engine calls one codel of a module at a time: the lock is never
            // contended
            builder = builder.codel((module, &c.service, &state), move |ctx| {
                proxy.lock().unwrap_or_else(|p| p.into_inner()).run(k, ctx)
            });
        }
        Ok(builder)
    }

    /// The model's map of `module`.
    fn module_map(&self, module: &str) -> Result<&ModuleMap, RemoteError> {
        self.system
            .genom
            .as_ref()
            .and_then(|g| g.module(module))
            .ok_or_else(|| RemoteError::NoSuchModule(module.into()))
    }

    /// The codels of `module` as the model declares them (services, then their codels,
    /// those at a request last), as the engine numbers them.
    fn model_codels(&self, module: &str) -> Result<Vec<RemoteCodel>, RemoteError> {
        Ok(self
            .module_map(module)?
            .services
            .iter()
            .flat_map(|s| {
                s.every_codel().map(|c| RemoteCodel {
                    name: format!("{}.{}", s.name, c.state),
                    service: s.name.clone(),
                    deadline: self.options.deadline + Duration::from_micros(c.wcet_us.unwrap_or(0)),
                })
            })
            .collect())
    }

    /// The proxy of module `module`'s process.
    fn proxy(&self, module: &str) -> Result<Proxy, RemoteError> {
        let map = self.module_map(module)?;
        let fields: Vec<String> = map.ids.iter().map(|f| f.name.clone()).collect();
        let codels = self.model_codels(module)?;
        self.presence
            .expect(module, codels.iter().map(|c| c.name.clone()).collect());
        Ok(Proxy {
            link: RunLink::new(
                &self.session,
                &self.prefix,
                module,
                self.low_latency,
                self.options.spin,
            )?,
            module: module.to_string(),
            types: Arc::clone(&self.types),
            fields,
            codels,
            seen: HashMap::new(),
            clock: self.options.virtual_clock.clone(),
            presence: self.presence.clone(),
            epoch: None,
            _watch: Arc::clone(&self.watch),
        })
    }
}

/// The closure of one remote module.
struct Proxy {
    link: RunLink,
    module: String,
    types: Arc<Types>,
    fields: Vec<String>,
    codels: Vec<RemoteCodel>,
    /// The port data the module's process holds, as last sent or received: only changes
    /// are sent.
    seen: HashMap<(String, String), Value>,
    clock: Option<VirtualClock>,
    presence: Presence,
    /// The presence's epoch of the module when `seen` was last right.
    epoch: Option<u64>,
    _watch: Arc<Watch>,
}

/// Why a remote run did not give an outcome.
enum NotRun {
    /// The process did not run the codel (gone, hung, cut off, refused the run, answered
    /// something unreadable): [`bip_engine::FaultKind::Remote`].
    Remote(String),
    /// The codel ran and was faulty in its process (its words).
    Codel(String),
}

impl Proxy {
    fn run(&mut self, k: usize, ctx: &mut Ctx<'_>) -> Next {
        match self.try_run(k, ctx) {
            Ok(next) => next,
            Err(NotRun::Remote(why)) => {
                ctx.remote_fault(why);
                // not looked at: the run is the fault just noted
                Next::Declared(0)
            }
            // the engine makes it the codel's fault, with this message, without the
            // panic hook's noise
            Err(NotRun::Codel(why)) => std::panic::resume_unwind(Box::new(why)),
        }
    }

    fn try_run(&mut self, k: usize, ctx: &mut Ctx<'_>) -> Result<Next, NotRun> {
        let codel = self
            .codels
            .get(k)
            .ok_or_else(|| NotRun::Remote(format!("module `{}` has no codel {k}", self.module)))?;
        if let Some(why) = self.presence.absent(&self.module) {
            self.seen.clear();
            return Err(NotRun::Remote(format!(
                "the process of module `{}` is absent: {why}",
                self.module
            )));
        }
        // a process that may have changed since (restarted, back from a cut) may have
        // lost the port data it had
        let epoch = self.presence.epoch(&self.module);
        if self.epoch != Some(epoch) {
            self.seen.clear();
            self.epoch = Some(epoch);
        }
        let ids = self
            .fields
            .iter()
            .map(|f| ctx.get(f).unwrap_or(0))
            .collect();
        let args = self
            .types
            .args_codec(&self.module, &codel.service)
            .and_then(|c| c.read_args(ctx));
        let mut ports = Vec::new();
        for (m, p, c) in self.types.ports() {
            let Some(data) = c.read_port(ctx, m, p) else {
                continue;
            };
            let key = (m.to_string(), p.to_string());
            if self.seen.get(&key) != Some(&data) {
                self.seen.insert(key, data.clone());
                ports.push(PortData {
                    module: m.into(),
                    port: p.into(),
                    data,
                });
            }
        }
        let grant = RunGrant {
            seq: self.link.next_seq(),
            codel: k as u32,
            name: codel.name.clone(),
            ids,
            args,
            ports,
            now_us: ctx.now_us(),
            tick: ctx.tick(),
        };
        let deadline = codel.deadline;
        let answer = self.link.exchange(&Message::Run(grant), deadline);
        let result = match answer {
            Ok(Answer::Ran(r)) => r,
            Ok(Answer::Refused { reason, .. }) => {
                // what it holds is unknown now: send every port again next time
                self.seen.clear();
                return Err(NotRun::Remote(format!(
                    "the process of module `{}` refused the run: {reason}",
                    self.module
                )));
            }
            Ok(Answer::Hello { .. }) => {
                self.seen.clear();
                return Err(NotRun::Remote(
                    "a module process answered a run with its codels".into(),
                ));
            }
            Err(e) => {
                self.seen.clear();
                let why = format!(
                    "the process of module `{}` did not run the codel (deadline {} ms): {e}",
                    self.module,
                    deadline.as_millis()
                );
                // its next runs fail at once, until it answers again
                self.presence.mark_absent(&self.module, e);
                return Err(NotRun::Remote(why));
            }
        };
        let service = codel.service.clone();
        match self.apply(ctx, &service, result) {
            Ok(Ok(next)) => Ok(next),
            Ok(Err(codel_fault)) => Err(NotRun::Codel(codel_fault)),
            Err(unreadable) => {
                self.seen.clear();
                Err(NotRun::Remote(format!(
                    "the process of module `{}` answered what the engine cannot take: {unreadable}",
                    self.module
                )))
            }
        }
    }

    /// Does in the engine's context what the codel did in its process: the codel's end
    /// (its outcome or its fault in its process), or why the answer cannot be taken.
    fn apply(
        &mut self,
        ctx: &mut Ctx<'_>,
        service: &str,
        r: RunResult,
    ) -> Result<Result<Next, String>, String> {
        if let Some(clock) = &self.clock {
            clock.advance(r.virtual_us);
        }
        for (j, f) in self.fields.iter().enumerate() {
            if r.written >> j & 1 == 1 {
                let v = r
                    .ids
                    .get(j)
                    .copied()
                    .ok_or("fewer ids fields than written")?;
                ctx.set(f, v);
            }
        }
        for p in r.ports {
            let codec = self
                .types
                .port_codec(&p.module, &p.port)
                .ok_or_else(|| format!("no codec for port `{}.{}`", p.module, p.port))?;
            codec
                .write_port(ctx, &p.port, &p.data)
                .map_err(|e| format!("port `{}.{}`: {e}", p.module, p.port))?;
            self.seen.insert((p.module, p.port), p.data);
        }
        if let Some(v) = r.output {
            let codec = self
                .types
                .output_codec(&self.module, service)
                .ok_or_else(|| format!("no codec for the output of `{}.{service}`", self.module))?;
            codec.set_output(ctx, &v)?;
        }
        Ok(match r.end {
            RunEnd::Outcome(k) => Ok(Next::Declared(k)),
            RunEnd::Fault(why) => Err(why),
        })
    }
}
