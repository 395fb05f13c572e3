//! The smallest controller worth copying: load a model, bind its codels, send requests,
//! run, print what happened, and check the run against the model.
//!
//!     cargo run -p bip-engine --example minimal

use bip_engine::{DefaultCodels, Engine, Next, Until};

pub fn main() -> Result<(), Box<dyn std::error::Error>> {
    // one dependency: bip-engine loads the model (an error prints as file:line:col)
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/rover.ron");
    let system = bip_engine::load_file(model)?;

    let mut engine = Engine::builder(system.clone())
        // a codel is a closure over its context, bound by (module, service, codel)
        .codel(("rflex", "TrackSpeed", "track"), |ctx| {
            // rover.ron declares the arguments a `Float`: an f64
            let speed = ctx.args::<f64>().copied().unwrap_or(0.0);
            let x = ctx.now_us() as f64 / 1e6 * speed;
            // `travelled` stands for what the wheels' encoders would give
            let travelled = x.abs();
            ctx.write_port("odo", Odometry { x, travelled });
            Next::Yield("pause::track")
        })
        // the codels not bound here yield their first declared yield
        .default_codels(DefaultCodels::FirstYield)
        .record(10_000)
        .build()?;

    engine.request("rflex", "Init", ())?;
    engine.request("rflex", "TrackSpeed", 0.5)?;
    // the default clock is virtual: ten ticks of the model pass at once
    engine.run_until(Until::Ticks(10))?;
    engine.request("rflex", "Stop", ())?;
    engine.run_until(Until::Ticks(2))?;

    // events name their service or codel and print in the model's terms
    for event in engine.events() {
        println!("{event}");
    }
    if let Some(odo) = engine.inspect().port::<Odometry>("rflex", "odo") {
        println!(
            "odometry: x {:.2} m, travelled {:.2} m",
            odo.x, odo.travelled
        );
    }

    // the run is a path of the model: its step relation accepts every step
    let steps = engine.record().replay(&system)?;
    println!("{} steps, each one the model allows", steps.len());
    Ok(())
}

/// The data of port `rflex.odo`: rover.ron declares it a record `Odometry`.
#[derive(Clone, Default)]
struct Odometry {
    x: f64,
    travelled: f64,
}
