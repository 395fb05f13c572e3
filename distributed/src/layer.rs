//! A layer run from its model and its deployment file alone (`bip run layer.ron --deploy
//! deploy.ron`): the module processes started on this machine (each the user's program,
//! named by its command in the file), the engine with every module bound to its process
//! from the model (no generated bindings), requests served on the network, on the real
//! clock, until stopped.

use std::path::Path;
use std::time::{Duration, Instant};

use bip_engine::{Engine, Event, RealClock, Stats, System, Until};

use crate::codec::Types;
use crate::deploy::{DeployError, Deployment};
use crate::remote::{RemoteError, RemoteModules, RemoteOptions};
use crate::requests::RequestServer;

/// How a layer runs.
#[derive(Clone, Debug)]
pub struct LayerOptions {
    /// How long (`None`: until `stop`).
    pub run_for: Option<Duration>,
    /// The deadline of a codel run beyond its WCET ([`RemoteOptions::deadline`]).
    pub deadline: Duration,
    /// How long to wait for each module process to answer at the start.
    pub wait: Duration,
    /// How long a client's request's replies are followed.
    pub follow: Duration,
}

impl Default for LayerOptions {
    fn default() -> LayerOptions {
        LayerOptions {
            run_for: None,
            deadline: RemoteOptions::default().deadline,
            wait: Duration::from_secs(20),
            follow: Duration::from_secs(60),
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum LayerError {
    #[error(transparent)]
    Deploy(#[from] DeployError),
    #[error(transparent)]
    Remote(#[from] RemoteError),
    #[error("{0}")]
    Engine(String),
}

/// Runs the layer of `system` as `deployment` (read from `file`) says, calling `each` with
/// every event of the engine, until `stop()` or `options.run_for`; the engine's figures
/// at the end. The processes started are killed when it returns, however it returns.
pub fn run_layer(
    system: &System,
    deployment: &Deployment,
    file: &Path,
    options: &LayerOptions,
    stop: &dyn Fn() -> bool,
    each: &mut dyn FnMut(&Event),
) -> Result<Stats, LayerError> {
    // the model's own types only: a record or a Rust type needs the layer's own engine
    // program, which knows its Rust type (docs/distributed.md, "bip run")
    let types = || Types::of(system);
    let remote_options = RemoteOptions {
        deadline: options.deadline,
        ..RemoteOptions::default()
    };
    types().check(system).map_err(RemoteError::Types)?;
    // started first, so that they are killed last, after the engine stopped listening
    let _launched = deployment.launch(file, |_| None)?;
    let remote = RemoteModules::new(
        &deployment.engine_network(),
        system,
        types(),
        remote_options,
    )?;
    let mut builder = Engine::builder(system.clone());
    for m in deployment.processes.iter().flat_map(|p| &p.modules) {
        remote.wait_for_model(m, options.wait)?;
        builder = remote.bind_model(builder, m)?;
    }
    let mut engine = builder
        .clock(RealClock::new())
        .build()
        .map_err(|e| LayerError::Engine(e.to_string()))?;
    let _server = RequestServer::start(
        remote.session(),
        &deployment.prefix,
        system,
        types(),
        engine.handle(),
        options.follow,
        Some(remote.presence()),
    )
    .map_err(RemoteError::from)?;
    let start = Instant::now();
    while !stop() && options.run_for.is_none_or(|d| start.elapsed() < d) {
        engine
            .run_until(Until::Ticks(1))
            .map_err(|e| LayerError::Engine(e.to_string()))?;
        for e in engine.events() {
            each(&e);
        }
    }
    Ok(engine.inspect().stats())
}
