//! `bip-zenoh`: one functional layer across processes and computers. One engine process
//! holds the model and its [`bip_engine::Engine`] (the gate); a module's codels run in a
//! module process, on this computer or another, and talk to the engine over zenoh. The
//! engine grants each codel run, sends it to the module's process with what the codel
//! sees (ids, arguments, port data, time), and commits what comes back through its gate,
//! exactly as it commits a codel it ran itself: nothing runs that the model does not
//! allow.
//!
//! - Engine side: [`RemoteModules`] binds modules to their processes
//!   ([`RemoteModules::bind`] in place of the module's generated `bind`).
//! - Module side: [`ModuleHost`] serves the runs of the modules a process holds, bound as
//!   in one process ([`bip_engine::HostedModule`]).
//! - Requests from other processes: [`RequestServer`] in the engine's process, [`request`]
//!   in a client's, [`ClientRequest`] from the command line (checked against the model).
//! - [`Types`]: how the model's data cross the network (JSON, one codec per Rust type).
//! - [`Deployment`]: which module runs in which process, from a RON file.
//! - [`Network`]: the zenoh session (peer mode, TCP on loopback by default).
//!
//! docs/distributed.md is the guide: the key expressions, the messages, faults, the
//! rover split over three module processes.

mod client;
mod codec;
mod deploy;
mod host;
mod launch;
mod layer;
mod link;
mod network;
mod presence;
mod remote;
mod requests;
mod runtime;
mod wire;

pub use client::ClientRequest;
pub use codec::{Codec, Types};
pub use deploy::{DeployError, Deployment, Process};
pub use host::ModuleHost;
pub use launch::Launched;
pub use layer::{run_layer, LayerError, LayerOptions};
pub use network::{
    Mode, Network, NetworkError, ENV_CONNECT, ENV_LOW_LATENCY, ENV_MODE, ENV_PREFIX, ENV_PROCESS,
    ENV_ZENOH_CONFIG,
};
pub use presence::{Presence, PROBE_EVERY};
pub use remote::{RemoteError, RemoteModules, RemoteOptions};
pub use requests::{request, request_bytes, RequestServer, ServiceReply, ServiceRequest};
pub use runtime::{tune_zenoh_runtime, LAYER_RUNTIME, ZENOH_RUNTIME_ENV};
pub use wire::{keys, Answer, Message, PortData, RunEnd, RunGrant, RunResult};
