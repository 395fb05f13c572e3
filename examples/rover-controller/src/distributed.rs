//! The rover as a distributed layer (docs/distributed.md): the engine in one process, the
//! modules' codels in three module processes, over zenoh. The codels are the same
//! objects, bound by the same generated `bind`; only where each module runs changes.

use std::error::Error;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use bip_engine::{Engine, EngineBuilder, System, VirtualClock};
use bip_zenoh::{Codec, ModuleHost, Network, RemoteModules, Types};
use serde_json::json;

use crate::codels::{Antenna, Camera, Heater, Laser, Localisation, Mapping, Navigation, Wheels};
use crate::hardware::{Dtm, Hardware, Image, Scan};
use crate::rover::{self, Odometry, Pose};

/// The rover's deployment file: three module processes (`deploy.ron`).
pub fn default_deployment_file() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("deploy.ron")
}

fn number(v: &serde_json::Value, field: &str) -> Result<f64, String> {
    v.get(field)
        .and_then(serde_json::Value::as_f64)
        .ok_or_else(|| format!("no number `{field}` in {v}"))
}

fn count(v: &serde_json::Value, field: &str) -> Result<u64, String> {
    v.get(field)
        .and_then(serde_json::Value::as_u64)
        .ok_or_else(|| format!("no count `{field}` in {v}"))
}

/// How the rover's data cross the network: its records and the hardware's types as JSON
/// objects of their fields (the model's `Float` and `Int` have their codecs already).
pub fn types(system: &System) -> Types {
    Types::of(system)
        .port(
            "rflex",
            "odo",
            Codec::with::<Odometry>(
                |o| json!({ "x": o.x, "travelled": o.travelled }),
                |v| {
                    Ok(Odometry {
                        x: number(v, "x")?,
                        travelled: number(v, "travelled")?,
                    })
                },
            ),
        )
        .port(
            "pom",
            "pose",
            Codec::with::<Pose>(|p| json!({ "x": p.x }), |v| Ok(Pose { x: number(v, "x")? })),
        )
        .port(
            "sick",
            "scan",
            Codec::with::<Scan>(
                |s| json!({ "ahead": s.ahead, "tick": s.tick }),
                |v| {
                    Ok(Scan {
                        ahead: number(v, "ahead")?,
                        tick: count(v, "tick")?,
                    })
                },
            ),
        )
        .port(
            "aspect",
            "dtm",
            Codec::with::<Dtm>(
                |d| json!({ "cells": d.cells }),
                |v| {
                    Ok(Dtm {
                        cells: count(v, "cells")? as u32,
                    })
                },
            ),
        )
        .port(
            "camera",
            "image",
            Codec::with::<Image>(
                |i| json!({ "frames": i.frames }),
                |v| {
                    Ok(Image {
                        frames: count(v, "frames")? as u32,
                    })
                },
            ),
        )
}

/// Every module of the rover bound to its codels on the simulated hardware, as in one
/// process; `exposure` is the virtual clock the camera advances (none on a real clock).
pub fn bind_codels(
    builder: EngineBuilder,
    hw: &Hardware,
    tick_s: f64,
    exposure: Option<VirtualClock>,
) -> EngineBuilder {
    rover::bind(
        builder,
        Wheels {
            hw: hw.clone(),
            tick_s,
        },
        Laser { hw: hw.clone() },
        Localisation,
        Navigation { hw: hw.clone() },
        Mapping,
        Antenna { hw: hw.clone() },
        Heater::default(),
        Camera { exposure },
    )
}

/// Binds every module of the rover to its module process.
pub fn bind_remote(
    builder: EngineBuilder,
    remote: &RemoteModules,
) -> Result<EngineBuilder, Box<dyn Error>> {
    use crate::rover::{antenna, aspect, camera, heating, ndd, pom, rflex, sick};
    let modules = [
        ("rflex", rflex::CODELS, &rflex::TYPES),
        ("sick", sick::CODELS, &sick::TYPES),
        ("pom", pom::CODELS, &pom::TYPES),
        ("ndd", ndd::CODELS, &ndd::TYPES),
        ("aspect", aspect::CODELS, &aspect::TYPES),
        ("antenna", antenna::CODELS, &antenna::TYPES),
        ("heating", heating::CODELS, &heating::TYPES),
        ("camera", camera::CODELS, &camera::TYPES),
    ];
    let mut builder = builder;
    for (m, codels, types) in modules {
        remote.wait_for(m, codels, std::time::Duration::from_secs(20))?;
        builder = remote.bind(builder, m, codels, types)?;
    }
    Ok(builder)
}

/// A module process: serves the codels of `modules` until `stop` is set.
pub fn serve_process(
    model: &std::path::Path,
    modules: &[&str],
    network: &Network,
    stop: Arc<AtomicBool>,
) -> Result<(), Box<dyn Error>> {
    let system = bip_engine::load_file(model)?;
    let tick_s = system.tick_ms.unwrap_or(100) as f64 / 1000.0;
    let clock = VirtualClock::new();
    let hw = Hardware::new();
    let builder = bind_codels(
        Engine::builder(system.clone()),
        &hw,
        tick_s,
        Some(clock.clone()),
    );
    let mut host = ModuleHost::new(network, &system, types(&system))?.virtual_clock(clock);
    for hosted in builder.hosted(modules)? {
        host = host.module(hosted);
    }
    host.serve(stop)?;
    Ok(())
}
