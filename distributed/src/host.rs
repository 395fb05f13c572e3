//! The module process's side: it answers the engine's runs of its modules' codels,
//! bound as in one process ([`HostedModule`]), one thread per module.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;

use bip_engine::Clock;
use bip_engine::{CodelSignature, HostedModule, HostedRun, Next, System, VirtualClock};
use zenoh::Wait;

use crate::codec::Types;
use crate::link;
use crate::network::Network;
use crate::remote::RemoteError;
use crate::wire::{keys, Answer, Message, PortData, RunEnd, RunGrant, RunResult};

/// The modules a process runs for an engine.
pub struct ModuleHost {
    session: zenoh::Session,
    prefix: String,
    low_latency: bool,
    types: Arc<Types>,
    modules: Vec<Served>,
    clock: Option<VirtualClock>,
}

struct Served {
    name: String,
    hosted: HostedModule,
    codels: &'static [CodelSignature],
}

impl ModuleHost {
    /// Opens the process's zenoh session; every typed datum of `system` must have its
    /// codec in `types`.
    pub fn new(
        network: &Network,
        system: &System,
        types: Types,
    ) -> Result<ModuleHost, RemoteError> {
        types.check(system).map_err(RemoteError::Types)?;
        Ok(ModuleHost {
            session: network.open()?,
            prefix: network.prefix.clone(),
            low_latency: network.low_latency,
            types: Arc::new(types),
            modules: Vec::new(),
            clock: None,
        })
    }

    /// Serves the runs of a module's codels ([`bip_engine::EngineBuilder::hosted`]).
    pub fn module(mut self, hosted: HostedModule) -> Self {
        self.modules.push(Served {
            name: hosted.name().to_string(),
            codels: hosted.signature(),
            hosted,
        });
        self
    }

    /// The virtual clock the codels of this process advance to act out slow work: each
    /// run reports how far (see [`RunResult::virtual_us`]).
    pub fn virtual_clock(mut self, clock: VirtualClock) -> Self {
        self.clock = Some(clock);
        self
    }

    /// Answers runs until `stop` is set (checked every 50 ms).
    pub fn serve(self, stop: Arc<AtomicBool>) -> Result<(), RemoteError> {
        let mut threads = Vec::new();
        // the engine hears that the process is there, and when it is gone
        let mut tokens = Vec::new();
        let mut declared = Vec::new();
        for served in self.modules {
            let (sink, inbox) = mpsc::channel();
            // the run key first: a process that answers `hello` takes runs
            let runs = sink.clone();
            let subscriber = link::subscriber(
                &self.session,
                &keys::run(&self.prefix, &served.name),
                move |payload| {
                    let _ = runs.send(Inbound::Run(payload));
                },
            )?;
            let answers = keys::ran(&self.prefix, &served.name);
            let publisher = link::publisher(&self.session, &answers)?;
            let hello = keys::hello(&self.prefix, &served.name);
            let queryable = self
                .session
                .declare_queryable(hello.as_str())
                .callback(move |q| {
                    let _ = sink.send(Inbound::Hello(q));
                })
                .wait()
                .map_err(|e| crate::NetworkError::Open(format!("cannot serve `{hello}`: {e}")))?;
            declared.push((subscriber, queryable));
            let alive = keys::alive(&self.prefix, &served.name);
            let token = self
                .session
                .liveliness()
                .declare_token(alive.as_str())
                .wait()
                .map_err(|e| crate::NetworkError::Open(format!("cannot declare `{alive}`: {e}")))?;
            tokens.push(token);
            let types = Arc::clone(&self.types);
            let clock = self.clock.clone();
            let stop = Arc::clone(&stop);
            let low_latency = self.low_latency;
            let mut served = served;
            // the module's own thread answers both its runs and `hello`: a process
            // that answers `hello` is one whose module takes runs
            threads.push(std::thread::spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    match inbox.recv_timeout(Duration::from_millis(50)) {
                        Ok(Inbound::Run(payload)) => {
                            let answer = served.answer(&payload, &types, clock.as_ref());
                            let bytes = served.fitting(answer, low_latency, &answers);
                            if let Err(e) = publisher.put(bytes).wait() {
                                tracing::warn!(target: "bip_zenoh", "cannot answer on `{answers}`: {e}");
                            }
                        }
                        Ok(Inbound::Hello(q)) => {
                            let hello = served.hello().to_bytes();
                            if let Err(e) = q.reply(q.key_expr().clone(), hello).wait() {
                                tracing::warn!(target: "bip_zenoh", "cannot answer `hello`: {e}");
                            }
                        }
                        Err(mpsc::RecvTimeoutError::Timeout) => {}
                        Err(mpsc::RecvTimeoutError::Disconnected) => break,
                    }
                }
            }));
        }
        for t in threads {
            let _ = t.join();
        }
        drop(tokens);
        drop(declared);
        Ok(())
    }
}

/// What a module's thread is given: a run's message, or a `hello` query to answer.
enum Inbound {
    Run(Vec<u8>),
    Hello(zenoh::query::Query),
}

impl Served {
    fn hello(&self) -> Answer {
        Answer::Hello {
            module: self.name.clone(),
            codels: self
                .codels
                .iter()
                .map(|c| format!("{}.{}", c.service, c.codel))
                .collect(),
        }
    }

    fn answer(&mut self, payload: &[u8], types: &Types, clock: Option<&VirtualClock>) -> Answer {
        match serde_json::from_slice::<Message>(payload) {
            Ok(Message::Hello) => self.hello(),
            Ok(Message::Run(g)) => {
                let seq = Some(g.seq);
                match self.run(g, types, clock) {
                    Ok(r) => Answer::Ran(r),
                    Err(reason) => Answer::Refused { seq, reason },
                }
            }
            Err(e) => Answer::Refused {
                seq: None,
                reason: format!("not a message of the engine: {e}"),
            },
        }
    }

    /// `answer`'s bytes, or a refusal when they are more than the link carries.
    fn fitting(&self, answer: Answer, low_latency: bool, key: &str) -> Vec<u8> {
        let bytes = answer.to_bytes();
        match link::too_large(low_latency, key, bytes.len()) {
            None => bytes,
            Some(reason) => Answer::Refused {
                seq: match answer {
                    Answer::Ran(r) => Some(r.seq),
                    _ => None,
                },
                reason: format!("module `{}` cannot send its answer: {reason}", self.name),
            }
            .to_bytes(),
        }
    }

    fn run(
        &mut self,
        mut g: RunGrant,
        types: &Types,
        clock: Option<&VirtualClock>,
    ) -> Result<RunResult, String> {
        let k = g.codel as usize;
        let sig = self
            .codels
            .get(k)
            .ok_or_else(|| format!("module `{}` has no codel {k}", self.name))?;
        let name = format!("{}.{}", sig.service, sig.codel);
        if name != g.name {
            return Err(format!(
                "codel {k} of module `{}` is `{name}` here, `{}` in the engine",
                self.name, g.name
            ));
        }
        let fields = self.hosted.fields().count();
        if g.ids.len() != fields {
            return Err(format!(
                "module `{}` has {fields} ids fields, the run {}",
                self.name,
                g.ids.len()
            ));
        }
        for p in &g.ports {
            let codec = types
                .port_codec(&p.module, &p.port)
                .ok_or_else(|| format!("no codec for port `{}.{}`", p.module, p.port))?;
            codec.host_set_port(&mut self.hosted, &p.module, &p.port, &p.data)?;
        }
        let args = match (&g.args, types.args_codec(&self.name, sig.service)) {
            (Some(v), Some(c)) => Some(c.decode(v)?),
            (Some(_), None) => {
                return Err(format!(
                    "`{}.{}` takes no arguments",
                    self.name, sig.service
                ))
            }
            (None, _) => None,
        };
        let mut output = None;
        let before = clock.map(|c| c.now_us());
        let end = self.hosted.run(
            k,
            HostedRun {
                ids: &mut g.ids,
                args: args.as_deref(),
                output: &mut output,
                now_us: g.now_us,
                tick: g.tick,
            },
        );
        let virtual_us = match (clock, before) {
            (Some(c), Some(t0)) => c.now_us().saturating_sub(t0),
            _ => 0,
        };
        let end_of = |next: Next| -> RunEnd {
            let yields = sig.yields.len();
            match next {
                Next::Declared(k) => RunEnd::Outcome(k),
                Next::Yield(y) => match sig.yields.iter().position(|x| *x == y) {
                    Some(k) => RunEnd::Outcome(k as u16),
                    None => RunEnd::Fault(format!("returned `{y}`, which it does not yield")),
                },
                Next::Throw(e) => match sig.throws.iter().position(|x| *x == e) {
                    Some(k) => RunEnd::Outcome((yields + k) as u16),
                    None => RunEnd::Fault(format!("threw `{e}`, which it does not declare")),
                },
            }
        };
        let end = match end.next {
            Ok(next) => (end_of(next), end.written),
            Err(why) => (RunEnd::Fault(why), 0),
        };
        let mut ports = Vec::new();
        for p in self.hosted.writes(k) {
            let data = types
                .port_codec(&self.name, p)
                .and_then(|c| c.host_port(&self.hosted, &self.name, p));
            if let Some(data) = data {
                ports.push(PortData {
                    module: self.name.clone(),
                    port: p.to_string(),
                    data,
                });
            }
        }
        let output = match (&output, types.output_codec(&self.name, sig.service)) {
            (Some(o), Some(c)) => c.output(o),
            _ => None,
        };
        Ok(RunResult {
            seq: g.seq,
            end: end.0,
            ids: g.ids,
            written: end.1,
            ports,
            output,
            virtual_us,
        })
    }
}
