//! Starting a deployment's module processes on this machine (`bip run --deploy`, the
//! example's `--deploy`): each by the command the file gives it, or the caller's default,
//! told its network by its environment; killed when the launch is dropped, and able to
//! end by itself when its standard input closes (should the launcher die first).

use std::path::Path;
use std::process::{Child, Command, Stdio};

use crate::deploy::{DeployError, Deployment, Process};
use crate::network::ENV_PROCESS;

/// The module processes started, killed (and reaped) when dropped.
pub struct Launched(Vec<Child>);

impl Drop for Launched {
    fn drop(&mut self) {
        for c in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

impl Deployment {
    /// Starts every process of the deployment read from `file`: by its `command` (a
    /// program relative to the file's directory, or found on `PATH`), else by
    /// `default(process)`; with [`ENV_PROCESS`] and the network's environment set ([`crate::Network::env`])
    /// and its standard input a pipe from this process.
    pub fn launch(
        &self,
        file: &Path,
        default: impl Fn(&Process) -> Option<Command>,
    ) -> Result<Launched, DeployError> {
        let dir = file.parent().unwrap_or(Path::new("."));
        let mut launched = Launched(Vec::new());
        let network = self.module_network();
        for p in &self.processes {
            let mut command = match p.command.split_first() {
                Some((program, args)) => {
                    let local = dir.join(program);
                    let mut c = if program.contains('/') && local.exists() {
                        Command::new(local)
                    } else {
                        Command::new(program)
                    };
                    c.args(args);
                    c
                }
                None => default(p).ok_or_else(|| DeployError::Model {
                    file: file.display().to_string(),
                    message: format!("process `{}` has no command; give it one", p.name),
                })?,
            };
            command
                .env(ENV_PROCESS, &p.name)
                .envs(network.env())
                .stdin(Stdio::piped());
            let child = command.spawn().map_err(|e| DeployError::Read {
                file: format!("{:?}", command.get_program()),
                message: format!("cannot start process `{}`: {e}", p.name),
            })?;
            launched.0.push(child);
        }
        Ok(launched)
    }
}
