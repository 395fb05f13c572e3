//! The example controller's command: `cargo run --release -p bip-rover-controller [--
//! --real-time]` plays the script on the virtual clock (or the real one) and prints the
//! log; `RUST_LOG=bip_engine=debug` shows every step on stderr.

fn main() {
    let real_time = std::env::args().any(|a| a == "--real-time");
    let model = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../robots/rover.ron");
    let _ = tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("off")),
        )
        .with_writer(std::io::stderr)
        .try_init();
    if let Err(e) = bip_rover_controller::run(&model, real_time, &mut |line| println!("{line}")) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
