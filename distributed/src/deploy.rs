//! A deployment file: which module runs in which process, and the network
//! (docs/distributed.md, "Deployment").

use std::path::{Path, PathBuf};

use bip_engine::System;
use serde::Deserialize;

use crate::network::{Mode, Network};

/// A layer's deployment, as a RON file writes it.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Deployment {
    /// The first chunk of the layer's keys.
    #[serde(default = "default_prefix")]
    pub prefix: String,
    /// The zenoh endpoints the engine listens on, in peer mode (default:
    /// `tcp/127.0.0.1:7447`).
    #[serde(default, deserialize_with = "given")]
    pub listen: Option<Vec<String>>,
    /// The endpoints the module processes connect to (default: the engine's); in client
    /// mode, the zenoh router(s) every process connects to.
    #[serde(default)]
    pub connect: Vec<String>,
    /// Peer (the default: the engine listens, the module processes connect to it) or
    /// client (every process, the engine's too, a client of the router at `connect`).
    #[serde(default)]
    pub mode: Mode,
    /// zenoh's low-latency transport (default: on); see [`Network::low_latency`].
    #[serde(default = "default_low_latency")]
    pub low_latency: bool,
    /// A zenoh configuration file (JSON5, relative to the deployment file) for what the
    /// deployment does not say (TLS, authentication, leases, ...).
    #[serde(default, deserialize_with = "given")]
    pub zenoh_config: Option<PathBuf>,
    pub processes: Vec<Process>,
}

/// A module process and the modules it runs.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Process {
    pub name: String,
    pub modules: Vec<String>,
    /// The program and its arguments that run it (`["target/release/drive"]`), started by
    /// [`Deployment::launch`]; empty: the launcher's default.
    #[serde(default)]
    pub command: Vec<String>,
}

fn default_prefix() -> String {
    "bip/layer".into()
}

/// A field the file gives, written as its value (`listen: [..]`, not `Some([..])`).
fn given<'de, D: serde::Deserializer<'de>, T: Deserialize<'de>>(
    d: D,
) -> Result<Option<T>, D::Error> {
    T::deserialize(d).map(Some)
}

fn default_low_latency() -> bool {
    true
}

/// Where the engine listens when the deployment does not say.
pub const DEFAULT_LISTEN: &str = "tcp/127.0.0.1:7447";

/// A deployment that cannot be read or does not fit its model.
#[derive(Debug, thiserror::Error)]
pub enum DeployError {
    #[error("{file}: {message}")]
    Read { file: String, message: String },
    #[error("{file}:{line}:{column}: {message}")]
    Syntax {
        file: String,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{file}: {message}")]
    Model { file: String, message: String },
}

impl Deployment {
    /// Reads a deployment file and checks it against `system`: every module with codels
    /// in exactly one process, no other.
    pub fn load(path: &Path, system: &System) -> Result<Deployment, DeployError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| DeployError::Read {
            file: file.clone(),
            message: e.to_string(),
        })?;
        let mut d =
            Deployment::parse(&text).map_err(|(line, column, message)| DeployError::Syntax {
                file: file.clone(),
                line,
                column,
                message,
            })?;
        if let Some(z) = &mut d.zenoh_config {
            *z = path.parent().unwrap_or(Path::new(".")).join(&*z);
        }
        d.check(system)
            .map_err(|message| DeployError::Model { file, message })?;
        Ok(d)
    }

    /// Parses the text of a deployment; an error's line, column and message.
    pub fn parse(text: &str) -> Result<Deployment, (usize, usize, String)> {
        ron::from_str(text).map_err(|e| (e.span.start.line, e.span.start.col, e.code.to_string()))
    }

    /// Every module of `system` that has codels runs in exactly one process; every
    /// module named is one of them.
    pub fn check(&self, system: &System) -> Result<(), String> {
        if self.mode == Mode::Client {
            if self.connect.is_empty() {
                return Err(
                    "in client mode every process connects to a zenoh router: give its endpoint in `connect`"
                        .into(),
                );
            }
            if self.listen.is_some() {
                return Err(
                    "in client mode no process listens (the router does): leave `listen` out"
                        .into(),
                );
            }
        }
        let with_codels: Vec<&str> = system
            .genom
            .iter()
            .flat_map(|g| &g.modules)
            .filter(|m| m.services.iter().any(|s| s.every_codel().next().is_some()))
            .map(|m| m.name.as_str())
            .collect();
        let mut seen: Vec<(&str, &str)> = Vec::new();
        for p in &self.processes {
            if self.processes.iter().filter(|q| q.name == p.name).count() > 1 {
                return Err(format!("two processes are named `{}`", p.name));
            }
            for m in &p.modules {
                if !with_codels.contains(&m.as_str()) {
                    return Err(format!(
                        "process `{}` runs module `{m}`, which the model does not have with codels (its modules with codels: {})",
                        p.name,
                        with_codels.join(", ")
                    ));
                }
                if let Some((_, other)) = seen.iter().find(|(x, _)| x == m) {
                    return Err(format!(
                        "module `{m}` runs in two processes, `{other}` and `{}`",
                        p.name
                    ));
                }
                seen.push((m, &p.name));
            }
        }
        if let Some(m) = with_codels
            .iter()
            .find(|m| !seen.iter().any(|(x, _)| x == *m))
        {
            return Err(format!("module `{m}` runs in no process; give it one"));
        }
        Ok(())
    }

    /// The modules of process `name`.
    pub fn modules_of(&self, name: &str) -> Option<Vec<&str>> {
        self.processes
            .iter()
            .find(|p| p.name == name)
            .map(|p| p.modules.iter().map(String::as_str).collect())
    }

    /// Where the engine listens: none in client mode.
    pub fn engine_listen(&self) -> Vec<String> {
        match (self.mode, &self.listen) {
            (Mode::Client, _) => Vec::new(),
            (Mode::Peer, Some(l)) => l.clone(),
            (Mode::Peer, None) => vec![DEFAULT_LISTEN.into()],
        }
    }

    /// The engine's network: it listens (peer mode), or connects to the router (client
    /// mode).
    pub fn engine_network(&self) -> Network {
        Network {
            listen: self.engine_listen(),
            connect: match self.mode {
                Mode::Peer => Vec::new(),
                Mode::Client => self.connect.clone(),
            },
            ..self.network()
        }
    }

    /// A module process's network: it connects to the engine (or to `connect`).
    pub fn module_network(&self) -> Network {
        let connect = if self.connect.is_empty() {
            self.engine_listen()
        } else {
            self.connect.clone()
        };
        Network {
            connect,
            ..self.network()
        }
    }

    /// What every process's network has in common.
    fn network(&self) -> Network {
        Network {
            listen: Vec::new(),
            connect: Vec::new(),
            prefix: self.prefix.clone(),
            mode: self.mode,
            low_latency: self.low_latency,
            zenoh_config: self.zenoh_config.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn counter() -> System {
        let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/counter.ron");
        bip_engine::load_file(&model).expect("the counter layer")
    }

    fn deployment(network: &str) -> Result<Deployment, String> {
        let text = format!(r#"({network} processes: [(name: "p", modules: ["counter"])])"#);
        let d = Deployment::parse(&text).map_err(|(l, c, m)| format!("{l}:{c}: {m}"))?;
        d.check(&counter())?;
        Ok(d)
    }

    #[test]
    fn a_peer_engine_listens_and_its_module_processes_connect_to_it() {
        let d = deployment("").expect("the defaults");
        assert_eq!(d.engine_network().listen, [DEFAULT_LISTEN]);
        assert!(d.engine_network().connect.is_empty());
        assert_eq!(d.module_network().connect, [DEFAULT_LISTEN]);
        assert!(d.module_network().low_latency);
        let d = deployment(
            r#"listen: ["tcp/0.0.0.0:7447"], connect: ["tcp/192.168.1.10:7447"], low_latency: false,"#,
        )
        .expect("another host");
        assert_eq!(d.engine_network().listen, ["tcp/0.0.0.0:7447"]);
        assert_eq!(d.module_network().connect, ["tcp/192.168.1.10:7447"]);
        assert!(!d.module_network().low_latency && !d.engine_network().low_latency);
    }

    #[test]
    fn in_client_mode_every_process_connects_to_the_router() {
        let d = deployment(r#"mode: client, connect: ["tcp/10.0.0.1:7447"],"#).expect("a router");
        for n in [d.engine_network(), d.module_network()] {
            assert_eq!(n.mode, Mode::Client);
            assert!(n.listen.is_empty());
            assert_eq!(n.connect, ["tcp/10.0.0.1:7447"]);
        }
        let e = deployment("mode: client,").expect_err("no router");
        assert!(e.contains("give its endpoint in `connect`"), "{e}");
        let e = deployment(
            r#"mode: client, connect: ["tcp/10.0.0.1:7447"], listen: ["tcp/127.0.0.1:7447"],"#,
        )
        .expect_err("a client that listens");
        assert!(e.contains("leave `listen` out"), "{e}");
        let e = deployment("mode: router,").expect_err("not a mode of a layer's process");
        assert!(e.contains("router"), "{e}");
    }
}
