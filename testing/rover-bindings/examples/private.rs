//! The bindings of `models/typed.ron` included in a private module of a binary that uses
//! almost none of them, as a controller that needs part of a layer does. Every warning is
//! denied here, so a warning of the generated code (unused items above all) fails the
//! build: `cargo test` and `cargo clippy --all-targets` build this example.
//!
//!     cargo run -p bip-rover-bindings --example private
#![deny(warnings)]

mod typed {
    include!(concat!(env!("OUT_DIR"), "/typed.rs"));
}

fn main() {
    println!("module arm binds {} codels", typed::arm::CODELS.len());
}
