//! The example controller of C codels: its script meets what the model answers, with the
//! codels' own outcomes; and, with outcomes a test hook picks at random, every recording
//! is a path of the model and only undeclared outcomes are faults.

mod property;

#[test]
fn the_supervisors_script_runs_the_c_codels_within_the_model() {
    let mut log = Vec::new();
    let r = bip_c_rover_controller::run(&mut |line| log.push(line))
        .unwrap_or_else(|e| panic!("the controller fails: {e}"));
    let log = log.join("\n");
    // Move before Init is refused by its `after`
    assert!(
        r.of("loco.Move")
            .first()
            .is_some_and(|t| t.contains("refused: after loco.Init")),
        "{log}"
    );
    // the first goal is reached (nav's codel returns nav_ether), the second is blocked
    // (nav_e_blocked), and Stop interrupts Move
    let goto = r.of("nav.GoTo");
    assert!(goto.contains(&"done: ether"), "{log}");
    assert!(goto.contains(&"done: exception e_blocked"), "{log}");
    assert!(
        r.of("loco.Move")
            .contains(&"done: interrupted by a request of loco.Stop"),
        "{log}"
    );
    assert!(r.of("loco.Stop").contains(&"done: ether"), "{log}");
    assert_eq!(r.faults, 0, "{log}");
    // the wheels moved the rover, and loc's C filter followed it
    assert!(r.world.x > 1.2, "{log}");
    assert!((r.world.x - r.estimate.0).abs() < 1e-9, "{log}");
    assert!(r.steps > 100, "{log}");
}
