//! `bip request MODEL module.Service [ARGS]`: sends a request to a layer run by `bip run`
//! (or any engine with a request server) and prints its replies as they come; the
//! arguments (JSON, or a bare word) are read against the service's type in the model
//! first, and a malformed request is refused before anything is sent
//! ([`bip_zenoh::ClientRequest`]). Exit codes: 0 the request was made (whatever the
//! model answered), 2 it was not (malformed, refused by the layer, no engine answered).

use std::path::PathBuf;
use std::time::Duration;

use bip_zenoh::{ClientRequest, Deployment, Network};

use crate::{exit, load};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The model file (RON).
    pub file: PathBuf,
    /// The service, `module.Service`.
    pub service: String,
    /// Its arguments: JSON (`0.5`, `{"x": 1.0}`), or a bare word (a JSON string).
    pub args: Option<String>,
    /// The layer's deployment file: where to connect, and the key prefix.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["connect", "prefix"])]
    pub deploy: Option<PathBuf>,
    /// A zenoh endpoint of the layer to connect to.
    #[arg(long, value_name = "ENDPOINT", default_value = "tcp/127.0.0.1:7447")]
    pub connect: Vec<String>,
    /// The layer's key prefix.
    #[arg(long, default_value = "bip/layer")]
    pub prefix: String,
    /// How long to wait for the replies, in milliseconds.
    #[arg(long, value_name = "MS", default_value_t = 5000)]
    pub timeout_ms: u64,
}

pub fn run(args: &Args) -> u8 {
    bip_zenoh::tune_zenoh_runtime();
    let Some(system) = load::system(&args.file) else {
        return exit::ERROR;
    };
    let request = match ClientRequest::parse(&system, &args.service, args.args.as_deref()) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return exit::ERROR;
        }
    };
    let network = match &args.deploy {
        Some(file) => match Deployment::load(file, &system) {
            Ok(d) => d.module_network(),
            Err(e) => {
                eprintln!("error: {e}");
                return exit::ERROR;
            }
        },
        None => Network {
            connect: args.connect.clone(),
            prefix: args.prefix.clone(),
            ..Network::default()
        },
    };
    let timeout = Duration::from_millis(args.timeout_ms);
    match request.send(&network, timeout, |r| println!("{r}")) {
        Ok(_) => exit::OK,
        Err(e) => {
            eprintln!("error: {e}");
            exit::ERROR
        }
    }
}
