//! A deployment file: which module runs in which process, and the network
//! (docs/distributed.md, "Deployment").

use std::path::Path;

use bip_engine::System;
use serde::Deserialize;

use crate::network::Network;

/// A layer's deployment, as a RON file writes it.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Deployment {
    /// The first chunk of the layer's keys.
    #[serde(default = "default_prefix")]
    pub prefix: String,
    /// The zenoh endpoints the engine listens on (default: `tcp/127.0.0.1:7447`).
    #[serde(default = "default_listen")]
    pub listen: Vec<String>,
    /// The endpoints the module processes connect to (default: the engine's).
    #[serde(default)]
    pub connect: Vec<String>,
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

fn default_listen() -> Vec<String> {
    vec!["tcp/127.0.0.1:7447".into()]
}

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
        let d =
            Deployment::parse(&text).map_err(|(line, column, message)| DeployError::Syntax {
                file: file.clone(),
                line,
                column,
                message,
            })?;
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

    /// The engine's network: it listens.
    pub fn engine_network(&self) -> Network {
        Network {
            listen: self.listen.clone(),
            connect: Vec::new(),
            prefix: self.prefix.clone(),
        }
    }

    /// A module process's network: it connects to the engine (or to `connect`).
    pub fn module_network(&self) -> Network {
        let connect = if self.connect.is_empty() {
            self.listen.clone()
        } else {
            self.connect.clone()
        };
        Network {
            listen: Vec::new(),
            connect,
            prefix: self.prefix.clone(),
        }
    }
}
