//! The example controller on robots/rover.ron: its supervisor script meets each answer
//! the model gives, and its recording is a path of the model along which every invariant
//! holds (the controller checks that itself and fails otherwise).

mod distributed;
mod faults;
mod relay;

use bip_rover_controller::rover::ndd;

fn reply_texts<'a>(r: &'a bip_rover_controller::Report, service: &str) -> Vec<&'a str> {
    r.replies
        .iter()
        .filter(|(s, _, _)| s == service)
        .map(|(_, _, text)| text.as_str())
        .collect()
}

#[test]
fn the_rover_controller_plays_its_script_within_the_model() {
    let model = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../robots/rover.ron");
    let mut log = Vec::new();
    let r = bip_rover_controller::run(&model, false, &mut |line| log.push(line))
        .unwrap_or_else(|e| panic!("the controller fails: {e}"));
    let log = log.join("\n");
    // refused: TrackSpeed before Init, with the reason
    assert!(
        reply_texts(&r, "rflex.TrackSpeed")
            .first()
            .is_some_and(|t| t.contains("rflex.TrackSpeed: refused: after rflex.Init")),
        "{log}"
    );
    // held by the rover's constraints, each named, with its line in the file
    let text = std::fs::read_to_string(&model).expect("the rover");
    let held_by = |codel: &str, name: &str, kind: &str| {
        let line = text
            .lines()
            .position(|l| l.contains(&format!("name: \"{name}\"")) && l.contains(kind))
            .expect("the constraint")
            + 1;
        let shown = format!("{name} (line {line}): {kind}(");
        r.held
            .iter()
            .any(|(c, why)| c == codel && why.iter().any(|w| w.starts_with(&shown)))
    };
    assert!(
        held_by("antenna.Communicate.start", "mast_still", "Exclusive"),
        "{log}"
    );
    assert!(
        held_by("camera.Shoot.start", "power_budget", "AtMost"),
        "{log}"
    );
    assert!(
        held_by("rflex.TrackSpeed.track", "battery_reserve", "Guard"),
        "{log}"
    );
    // navigation: aborted by the rover's rule without the laser (not a client's
    // interrupt), arrives, then blocked by the rock
    assert_eq!(
        reply_texts(&r, "ndd.GoTo")
            .into_iter()
            .filter(|t| t.starts_with("done"))
            .collect::<Vec<_>>(),
        [
            "done: aborted by a rule of the model",
            "done: ether, with an output",
            "done: exception e_blocked, with an output"
        ],
        "{log}"
    );
    // GoTo's output (a `Float` in rover.ron): where the rover stopped, at the goal (1 m)
    // then before the rock (2 m)
    assert!(
        matches!(r.stopped_at.as_slice(), [a, b] if (a - 1.0).abs() < 0.05 && *b < 2.0),
        "{:?}",
        r.stopped_at
    );
    // the same ends, read through GoTo's typed tickets
    assert!(
        matches!(
            r.goto_ends.as_slice(),
            [
                ndd::GoToEnd::Other(bip_engine::Outcome::Aborted),
                ndd::GoToEnd::Done(Some(_)),
                ndd::GoToEnd::Exception(ndd::GoToException::EBlocked, Some(at))
            ] if *at < 2.0
        ),
        "{:?}",
        r.goto_ends
    );
    assert!(reply_texts(&r, "antenna.Communicate").contains(&"done: ether"));
    assert_eq!((r.overruns, r.faults), (1, 0), "{log}");
    // the recording replays with the step relation
    let path = r.trace.replay(&r.system).expect("a path of the model");
    assert!(path.len() > 300, "{}", path.len());
    assert!(
        log.contains("every invariant holds in every state"),
        "{log}"
    );
}
