//! The zenoh session of an engine or module process: peer mode, TCP, multicast scouting
//! off (the peers are named), and the key prefix of the layer, so that two layers on one
//! network (two tests at once) never see each other.

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
}

#[derive(Debug, thiserror::Error)]
pub enum NetworkError {
    #[error("zenoh configuration `{key}`: {message}")]
    Config { key: &'static str, message: String },
    #[error("cannot open the zenoh session: {0}")]
    Open(String),
    #[error("the key prefix `{0}` is not a zenoh key expression (chunks of letters, digits, `_`, `-`, separated by `/`)")]
    Prefix(String),
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
        }
    }

    /// A launched module process's network, from the environment its launcher set
    /// ([`ENV_CONNECT`], [`ENV_PREFIX`]); `None` when not launched so.
    pub fn from_env() -> Option<Network> {
        let connect = std::env::var(ENV_CONNECT).ok()?;
        let prefix = std::env::var(ENV_PREFIX).ok()?;
        Some(Network {
            listen: Vec::new(),
            connect: connect
                .split(',')
                .filter(|e| !e.is_empty())
                .map(String::from)
                .collect(),
            prefix,
        })
    }

    /// Opens the zenoh session.
    pub fn open(&self) -> Result<zenoh::Session, NetworkError> {
        if zenoh::key_expr::KeyExpr::try_from(self.prefix.as_str()).is_err()
            || self.prefix.contains(['*', '$', '?', '#'])
        {
            return Err(NetworkError::Prefix(self.prefix.clone()));
        }
        let mut c = zenoh::Config::default();
        let list = |v: &[String]| serde_json::to_string(v).unwrap_or_else(|_| "[]".into());
        let settings: [(&'static str, String); 4] = [
            ("mode", "\"peer\"".into()),
            ("scouting/multicast/enabled", "false".into()),
            ("listen/endpoints", list(&self.listen)),
            ("connect/endpoints", list(&self.connect)),
        ];
        for (key, value) in settings {
            c.insert_json5(key, &value)
                .map_err(|e| NetworkError::Config {
                    key,
                    message: e.to_string(),
                })?;
        }
        zenoh::open(c)
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
