//! Data that holds pointers (camera.gen): an image's unbounded sequence of bytes and
//! strings, grown and written by C codels and read back on the Rust side, and given by
//! the Rust side to C codels; the memory of both sides owns its buffers (the
//! AddressSanitizer run of these tests, in .ci/run, finds no leak and no double free).

use bip_c_codels::camera_glue::{cam, camera};
use bip_engine::{Engine, Event, Outcome, Output, Policy, Reply, System, Ticket, Until};
use bip_genom_c::{GenomString, Sequence};

pub(crate) fn system() -> System {
    bip_engine::load_file(concat!(env!("CARGO_MANIFEST_DIR"), "/camera.ron")).expect("loads")
}

pub(crate) type Camera = std::sync::Arc<std::sync::Mutex<camera::Component>>;

pub(crate) fn engine(system: &System) -> (Engine, Camera) {
    let builder = Engine::builder(system.clone())
        .policy(Policy::Seeded(1))
        .record(4096);
    let (builder, shared) = camera::bind_shared(builder);
    (builder.build().expect("builds"), shared)
}

/// Runs until `ticket`'s reply: its outcome and output.
pub(crate) fn reply(engine: &mut Engine, ticket: Ticket) -> (Outcome, Option<Output>) {
    engine.run_until(Until::Ticks(10)).expect("runs");
    engine
        .events()
        .find_map(|ev| match ev {
            Event::Reply {
                ticket: t,
                reply: Reply::Done { outcome, output },
                ..
            } if t == ticket => Some((outcome, output)),
            _ => None,
        })
        .expect("a reply")
}

fn shoot(engine: &mut Engine, width: u32, height: u32, label: &str) {
    let args = camera::Shoot_input {
        width,
        height,
        label: GenomString::new(label),
    };
    let ticket = engine.request("camera", "Shoot", args).expect("a request");
    assert_eq!(reply(engine, ticket).0, Outcome::Ether);
}

#[test]
fn a_codel_grows_a_sequence_and_writes_a_string_that_the_rust_side_reads_back() {
    let system = system();
    let (mut engine, shared) = engine(&system);
    shoot(&mut engine, 4, 3, "first");
    // the engine's copy of port frame, written by the codel's `write`
    let frame: &cam::image = engine.inspect().port("camera", "frame").expect("written");
    assert_eq!((frame.width, frame.height), (4, 3));
    let want: Vec<u8> = (0..12).collect();
    assert_eq!(frame.pixels.as_slice(), &want[..]);
    assert_eq!(frame.label.to_string_lossy(), "first");
    // an anonymous sequence<octet> is the model's Vec<u8>
    let raw: &Vec<u8> = engine.inspect().port("camera", "raw").expect("written");
    assert_eq!(raw, &vec![0, 1, 2, 3]);

    // a larger image: the codel's reserve releases the old buffer and takes a new one
    shoot(&mut engine, 40, 30, "second");
    let frame: &cam::image = engine.inspect().port("camera", "frame").expect("written");
    assert_eq!(frame.pixels.len(), 1200);
    assert_eq!(frame.pixels.as_slice()[1199], ((1199 + 1) % 256) as u8);
    assert_eq!(frame.label.to_string_lossy(), "second");
    let raw: &Vec<u8> = engine.inspect().port("camera", "raw").expect("written");
    assert_eq!(raw.len(), 40);
    // a bounded sequence<long, 4> is the model's Vec<i32> too, of its length
    let hist: &Vec<i32> = engine.inspect().port("camera", "hist").expect("written");
    assert_eq!(hist.iter().sum::<i32>(), 1200);
    assert_eq!(hist.len(), 4);
    // the ids' sequence of strings, grown by one at each shot
    let module = shared.lock().expect("unpoisoned");
    let labels: Vec<String> = module
        .state
        .ids
        .labels
        .as_slice()
        .iter()
        .map(GenomString::to_string_lossy)
        .collect();
    assert_eq!(labels, ["first", "second"]);
    assert_eq!(module.state.ids.shots, 2);
    drop(module);
    engine
        .record()
        .replay(&system)
        .expect("a path of the model");
}

#[test]
fn the_rust_side_gives_an_image_and_a_string_and_reads_the_outputs() {
    let system = system();
    let (mut engine, shared) = engine(&system);
    let img = cam::image {
        width: 2,
        height: 2,
        pixels: Sequence::from_slice(&[10, 20, 30, 40]),
        label: GenomString::new("given"),
    };
    let ticket = engine
        .request("camera", "Describe", img)
        .expect("a request");
    let (outcome, output) = reply(&mut engine, ticket);
    assert_eq!(outcome, Outcome::Ether);
    let summary = output.expect("an output");
    assert_eq!(
        summary.get::<String>().map(String::as_str),
        Some("given 2x2 sum 100")
    );

    // the output of an out sequence<octet> is the model's Vec<u8>; an in string a String
    let ticket = engine.request("camera", "Rename", "left".to_string());
    let (_, output) = reply(&mut engine, ticket.expect("a request"));
    assert_eq!(output.expect("an output").get::<Vec<u8>>(), Some(&vec![]));
    let ticket = engine.request("camera", "Rename", "right".to_string());
    let (_, output) = reply(&mut engine, ticket.expect("a request"));
    assert_eq!(
        output.expect("an output").get::<Vec<u8>>(),
        Some(&b"left".to_vec())
    );
    let title = shared
        .lock()
        .expect("unpoisoned")
        .state
        .ids
        .title
        .to_string_lossy();
    assert_eq!(title, "right");
    engine
        .record()
        .replay(&system)
        .expect("a path of the model");
}

#[test]
fn outputs_of_several_parameters_and_of_a_number_are_given_back() {
    let system = system();
    let (mut engine, _) = engine(&system);
    let img = cam::image {
        width: 2,
        height: 1,
        pixels: Sequence::from_slice(&[10, 20]),
        ..Default::default()
    };
    let ticket = engine.request("camera", "Stats", img).expect("a request");
    let (outcome, output) = reply(&mut engine, ticket);
    assert_eq!(outcome, Outcome::Ether);
    // an out double and an out string: the glue's struct, accepted by its name
    let output = output.expect("an output");
    let stats = output.get::<camera::Stats_output>().expect("Stats_output");
    assert_eq!(stats.mean, 15.0);
    assert_eq!(stats.verdict.to_string_lossy(), "dark");

    // a bounded sequence given as the model's Vec<i32>, cut at its bound
    let ticket = engine.request("camera", "Total", vec![1i32, 2, 3, 4, 5]);
    let (_, output) = reply(&mut engine, ticket.expect("a request"));
    assert_eq!(output.expect("an output").get::<i64>(), Some(&10));

    shoot(&mut engine, 2, 2, "one");
    shoot(&mut engine, 2, 2, "two");
    let ticket = engine.request("camera", "Shots", ()).expect("a request");
    let (_, output) = reply(&mut engine, ticket);
    // an out unsigned long: the model's Int, an i64
    assert_eq!(output.expect("an output").get::<i64>(), Some(&2));
    engine
        .record()
        .replay(&system)
        .expect("a path of the model");
}

#[test]
fn the_model_refuses_what_the_glue_cannot_carry() {
    let system = system();
    let (mut engine, _) = engine(&system);
    // the model's type of Rename's argument is String: its C string is no request
    assert!(engine
        .request("camera", "Rename", GenomString::new("left"))
        .is_err());
}
