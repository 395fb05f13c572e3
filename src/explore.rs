//! `bip explore FILE [--trace TRACE] [--port N]`: a local web explorer of a model's states.
//! The page (embedded in the binary, no network needed) shows the current state in the
//! user's terms, fires the enabled steps, goes back and forward through the history, and
//! steps through a counterexample. `session` keeps the exploration, `api` answers the
//! page's requests, `http` serves them; it listens on the loopback interface unless told
//! otherwise.

mod api;
mod http;
mod session;
mod timing;
#[cfg(test)]
mod timing_tests;

use std::io::Write;
use std::net::{IpAddr, Ipv4Addr, TcpListener};
use std::path::PathBuf;

use crate::{exit, load, trace};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The model file (RON).
    pub file: PathBuf,
    /// A trace of the model (a counterexample, a witness, a recording) to step through.
    #[arg(long, value_name = "TRACE")]
    pub trace: Option<PathBuf>,
    /// The port to listen on (0: any free port; the first line printed says which).
    #[arg(long, default_value_t = 7390)]
    pub port: u16,
    /// The address to listen on. Anything but loopback lets other machines drive the
    /// explorer and read the model.
    #[arg(long, value_name = "ADDRESS", default_value_t = IpAddr::V4(Ipv4Addr::LOCALHOST))]
    pub listen: IpAddr,
}

pub fn run(args: &Args) -> u8 {
    let loaded = match &args.trace {
        None => load::system(&args.file).map(|system| (system, None)),
        Some(path) => trace::model_and_trace(&args.file, path)
            .map(|(system, trace)| (system, Some((path, trace)))),
    };
    let Some((system, trace)) = loaded else {
        return exit::ERROR;
    };
    let mut session = session::Session::new(system);
    if let Some((path, trace)) = trace {
        if let Err(e) = session.load(&trace) {
            eprintln!("error: {}: {e}", path.display());
            return exit::ERROR;
        }
    }
    if !args.listen.is_loopback() {
        eprintln!(
            "warning: listening on {}, not loopback: anyone who can reach this machine can \
             drive the explorer and read the model",
            args.listen
        );
    }
    let listener = match TcpListener::bind((args.listen, args.port)) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("error: cannot listen on {}:{}: {e}", args.listen, args.port);
            return exit::ERROR;
        }
    };
    let address = match listener.local_addr() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}");
            return exit::ERROR;
        }
    };
    // the first line says where, for a reader that asked for port 0
    println!("bip explore: http://{address}/ (Ctrl-C to stop)");
    let _ = std::io::stdout().flush();
    match http::serve(listener, session, args.listen.is_loopback()) {
        Ok(()) => exit::OK,
        Err(e) => {
            eprintln!("error: cannot serve on {address}: {e}");
            exit::ERROR
        }
    }
}
