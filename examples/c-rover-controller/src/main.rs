//! `cargo run --release -p bip-c-rover-controller`: plays the supervisor's script with the
//! components' C codels on the simulated world and prints the log.

fn main() {
    if let Err(e) = bip_c_rover_controller::run(&mut |line| println!("{line}")) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
