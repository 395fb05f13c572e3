//! `bip run` and `bip request` (docs/distributed.md): their refusals, in the user's terms,
//! before anything starts or is sent. A layer run end to end by the same library code is
//! bip-zenoh's test (`distributed/tests/layer.rs`, with a module program of its own).

use crate::common::bip;

fn text(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr)
}

#[test]
fn a_malformed_request_is_refused_against_the_model_before_it_is_sent() {
    let cases = [
        (
            vec!["rflex.TrackSpeed", "fast"],
            "the arguments of rflex.TrackSpeed (`fast`) are not of its type Float",
        ),
        (
            vec!["rflex.TrackSpeed"],
            "takes arguments of type Float; give them",
        ),
        (vec!["rflex.Init", "3"], "rflex.Init takes no arguments"),
        (vec!["rflex.Fly"], "module `rflex` has no service `Fly`"),
        (vec!["wheels.Init"], "the model has no module `wheels`"),
        (vec!["rflex"], "`rflex` is not `module.Service`"),
    ];
    for (args, why) in cases {
        let mut all = vec!["request", "robots/rover.ron"];
        all.extend(args);
        let out = bip(&all);
        assert_eq!(out.status.code(), Some(2), "{}", text(&out));
        assert!(text(&out).contains(why), "{}", text(&out));
    }
}

#[test]
fn a_request_that_no_engine_answers_is_an_error() {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port();
    let endpoint = format!("tcp/127.0.0.1:{port}");
    let out = bip(&[
        "request",
        "robots/rover.ron",
        "rflex.Init",
        "--connect",
        &endpoint,
        "--prefix",
        &format!("bip/test/{}/none", std::process::id()),
        "--timeout-ms",
        "300",
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(text(&out).contains("no engine answered"), "{}", text(&out));
}

#[test]
fn bip_run_refuses_what_it_cannot_start() {
    let dir = tempfile::tempdir().expect("a directory");
    let write = |name: &str, text: &str| {
        let f = dir.path().join(name);
        std::fs::write(&f, text).expect("written");
        f.display().to_string()
    };
    // a process without a command: the launcher does not know what to start
    let no_command = write(
        "deploy.ron",
        r#"(processes: [(name: "all", modules: ["rflex"])])"#,
    );
    let out = bip(&["run", "robots/tests/mini.ron", "--deploy", &no_command]);
    // mini.ron's antenna has codels too: the file is checked against the model first
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(
        text(&out).contains("module `antenna` runs in no process"),
        "{}",
        text(&out)
    );
    let no_command = write(
        "deploy.ron",
        r#"(processes: [(name: "all", modules: ["rflex", "antenna"])])"#,
    );
    let out = bip(&["run", "robots/tests/mini.ron", "--deploy", &no_command]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(
        text(&out).contains("process `all` has no command; give it one"),
        "{}",
        text(&out)
    );
    // records cross the network only with the codecs of the layer's own engine program
    let rover = write(
        "rover.ron",
        &std::fs::read_to_string("examples/rover-controller/deploy.ron")
            .expect("the rover's deployment"),
    );
    let out = bip(&["run", "robots/rover.ron", "--deploy", &rover]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(
        text(&out).contains("has no codec to cross the network"),
        "{}",
        text(&out)
    );
}
