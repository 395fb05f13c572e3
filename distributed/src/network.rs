//! The zenoh session of an engine or module process: peer mode (or a client of a zenoh
//! router), TCP, multicast scouting off (the peers are named), the low-latency transport,
//! and the key prefix of the layer, so that two layers on one network (two tests at once)
//! never see each other.

use std::path::PathBuf;
use std::time::Duration;

use zenoh::Wait;

use crate::wire::{Answer, Message};

/// The environment variable that names a launched module process's process (its name in
/// the deployment file).
pub const ENV_PROCESS: &str = "BIP_LAYER_PROCESS";
/// The endpoints it connects to, separated by commas.
pub const ENV_CONNECT: &str = "BIP_LAYER_CONNECT";
/// The layer's key prefix.
pub const ENV_PREFIX: &str = "BIP_LAYER_PREFIX";
/// `peer` or `client` ([`Mode`]).
pub const ENV_MODE: &str = "BIP_LAYER_MODE";
/// `0` when the low-latency transport is off ([`Network::low_latency`]).
pub const ENV_LOW_LATENCY: &str = "BIP_LAYER_LOW_LATENCY";
/// The zenoh configuration file ([`Network::zenoh_config`]).
pub const ENV_ZENOH_CONFIG: &str = "BIP_LAYER_ZENOH_CONFIG";

/// A zenoh session's role: a peer (it listens and connects directly to other peers), or
/// a client of a zenoh router (it connects to the router, which routes between clients).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    #[default]
    Peer,
    Client,
}

impl Mode {
    fn as_str(self) -> &'static str {
        match self {
            Mode::Peer => "peer",
            Mode::Client => "client",
        }
    }
}

/// Where a process listens and whom it connects to, and the layer's key prefix.
#[derive(Clone, Debug)]
pub struct Network {
    /// zenoh endpoints to listen on (`tcp/127.0.0.1:7447`).
    pub listen: Vec<String>,
    /// zenoh endpoints to connect to (another peer, or a zenoh router).
    pub connect: Vec<String>,
    /// The first chunk of every key of the layer (`bip/rover`): docs/distributed.md,
    /// "Key expressions".
    pub prefix: String,
    /// Peer (the default) or client of a router.
    pub mode: Mode,
    /// zenoh's low-latency transport (docs/distributed.md, "The network"): each message
    /// written at once by the thread that sends it, none larger than 65,535 bytes. Used on
    /// a link only when both of its ends ask for it; otherwise (a client with zenoh's
    /// default configuration) the link is zenoh's usual one.
    pub low_latency: bool,
    /// A zenoh configuration file (JSON5) read first, for what a layer does not set
    /// itself (TLS, authentication, leases, ...); the settings above override it.
    pub zenoh_config: Option<PathBuf>,
}

impl Default for Network {
    /// A peer on no endpoint yet, under the prefix `bip/layer`, with the low-latency
    /// transport.
    fn default() -> Network {
        Network {
            listen: Vec::new(),
            connect: Vec::new(),
            prefix: "bip/layer".into(),
            mode: Mode::Peer,
            low_latency: true,
            zenoh_config: None,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum NetworkError {
    #[error("zenoh configuration `{key}`: {message}")]
    Config { key: &'static str, message: String },
    #[error("the zenoh configuration file {file}: {message}")]
    ConfigFile { file: String, message: String },
    #[error("cannot open the zenoh session: {0}")]
    Open(String),
    #[error("the key prefix `{0}` is not a zenoh key expression (chunks of letters, digits, `_`, `-`, separated by `/`)")]
    Prefix(String),
    #[error("{0} is not `peer` or `client`")]
    Mode(String),
}

impl Network {
    /// A layer on this machine: listening on `127.0.0.1:port` (the engine's side), or
    /// connecting to it (a module process's).
    pub fn loopback(prefix: &str, port: u16, listen: bool) -> Network {
        let endpoint = format!("tcp/127.0.0.1:{port}");
        let (listen, connect) = if listen {
            (vec![endpoint], Vec::new())
        } else {
            (Vec::new(), vec![endpoint])
        };
        Network {
            listen,
            connect,
            prefix: prefix.to_string(),
            ..Network::default()
        }
    }

    /// A launched module process's network, from the environment its launcher set
    /// ([`ENV_CONNECT`], [`ENV_PREFIX`], and [`ENV_MODE`], [`ENV_LOW_LATENCY`],
    /// [`ENV_ZENOH_CONFIG`] when it gives them); `None` when not launched so.
    pub fn from_env() -> Option<Result<Network, NetworkError>> {
        let connect = std::env::var(ENV_CONNECT).ok()?;
        let prefix = std::env::var(ENV_PREFIX).ok()?;
        let mode = match std::env::var(ENV_MODE).ok().as_deref() {
            None | Some("peer") => Mode::Peer,
            Some("client") => Mode::Client,
            Some(other) => {
                return Some(Err(NetworkError::Mode(format!("{ENV_MODE} `{other}`"))));
            }
        };
        Some(Ok(Network {
            listen: Vec::new(),
            connect: connect
                .split(',')
                .filter(|e| !e.is_empty())
                .map(String::from)
                .collect(),
            prefix,
            mode,
            low_latency: std::env::var(ENV_LOW_LATENCY).map_or(true, |v| v != "0"),
            zenoh_config: std::env::var_os(ENV_ZENOH_CONFIG).map(PathBuf::from),
        }))
    }

    /// The environment that tells a launched process this network ([`Network::from_env`]).
    pub fn env(&self) -> Vec<(&'static str, String)> {
        let mut env = vec![
            (ENV_CONNECT, self.connect.join(",")),
            (ENV_PREFIX, self.prefix.clone()),
            (ENV_MODE, self.mode.as_str().to_string()),
            (
                ENV_LOW_LATENCY,
                if self.low_latency { "1" } else { "0" }.into(),
            ),
        ];
        if let Some(file) = &self.zenoh_config {
            env.push((ENV_ZENOH_CONFIG, file.display().to_string()));
        }
        env
    }

    /// The zenoh configuration of the session.
    pub fn config(&self) -> Result<zenoh::Config, NetworkError> {
        let mut c = match &self.zenoh_config {
            Some(file) => zenoh::Config::from_file(file).map_err(|e| NetworkError::ConfigFile {
                file: file.display().to_string(),
                message: e.to_string(),
            })?,
            None => zenoh::Config::default(),
        };
        let list = |v: &[String]| serde_json::to_string(v).unwrap_or_else(|_| "[]".into());
        let flag = |b: bool| if b { "true" } else { "false" }.to_string();
        let mut settings: Vec<(&'static str, String)> = vec![
            ("mode", format!("\"{}\"", self.mode.as_str())),
            ("scouting/multicast/enabled", "false".into()),
            ("listen/endpoints", list(&self.listen)),
            ("connect/endpoints", list(&self.connect)),
        ];
        if self.low_latency {
            // zenoh refuses its QoS (priorities) with the low-latency transport
            settings.push(("transport/unicast/lowlatency", flag(true)));
            settings.push(("transport/unicast/qos/enabled", flag(false)));
        }
        for (key, value) in settings {
            c.insert_json5(key, &value)
                .map_err(|e| NetworkError::Config {
                    key,
                    message: e.to_string(),
                })?;
        }
        Ok(c)
    }

    /// Opens the zenoh session.
    pub fn open(&self) -> Result<zenoh::Session, NetworkError> {
        if zenoh::key_expr::KeyExpr::try_from(self.prefix.as_str()).is_err()
            || self.prefix.contains(['*', '$', '?', '#'])
        {
            return Err(NetworkError::Prefix(self.prefix.clone()));
        }
        zenoh::open(self.config()?)
            .wait()
            .map_err(|e| NetworkError::Open(e.to_string()))
    }
}

/// Sends a query and reads its one answer.
pub(crate) fn query(
    session: &zenoh::Session,
    key: &str,
    message: &Message,
    timeout: Duration,
) -> Result<Answer, String> {
    let replies = session
        .get(key)
        .payload(message.to_bytes())
        .timeout(timeout)
        .wait()
        .map_err(|e| format!("cannot query `{key}`: {e}"))?;
    let reply = match replies.recv_timeout(timeout) {
        Ok(Some(r)) => r,
        _ => {
            return Err(format!(
                "no answer on `{key}` within {} ms",
                timeout.as_millis()
            ))
        }
    };
    let sample = reply.result().map_err(|e| {
        format!(
            "an error on `{key}`: {}",
            e.payload().try_to_string().unwrap_or_default()
        )
    })?;
    serde_json::from_slice(&sample.payload().to_bytes())
        .map_err(|e| format!("an unreadable answer on `{key}`: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_zenoh_configuration_file_gives_what_the_layer_does_not_set() {
        let dir = std::env::temp_dir().join(format!("bip-zenoh-config-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a directory");
        let file = dir.join("zenoh.json5");
        std::fs::write(
            &file,
            r#"{ mode: "router", transport: { link: { tx: { lease: 3000 } } } }"#,
        )
        .expect("written");
        let network = Network {
            connect: vec!["tcp/127.0.0.1:7447".into()],
            mode: Mode::Client,
            zenoh_config: Some(file.clone()),
            ..Network::default()
        };
        let c = network.config().expect("read");
        assert_eq!(c.get_json("transport/link/tx/lease").expect("set"), "3000");
        assert_eq!(c.get_json("mode").expect("set"), "\"client\"");
        assert_eq!(
            c.get_json("connect/endpoints").expect("set"),
            r#"["tcp/127.0.0.1:7447"]"#
        );
        assert_eq!(
            c.get_json("transport/unicast/lowlatency").expect("set"),
            "true"
        );
        std::fs::write(&file, "{ mode: ").expect("written");
        let e = network.config().expect_err("unreadable");
        assert!(e.to_string().contains("zenoh.json5"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
