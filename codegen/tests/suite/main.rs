//! bip-codegen from the outside: what the bindings hold, names that would clash, and a
//! build script's rewrite only on change. That the rover's bindings compile and run is
//! `testing/rover-bindings`.

use bip_codegen::{rust_bindings, write_rust_bindings, CodegenError};

fn load(text: &str) -> bip_model::System {
    bip_lang::load_str("m.ron", text).unwrap_or_else(|e| panic!("{e:?}"))
}

const ONE: &str = r#"System(
    name: "one",
    modules: [(
        name: "type",
        tasks: [(name: "t", period: 1)],
        services: [
            (name: "Run", kind: Activity, task: "t", codels: [
                (state: "start", yields: ["main"]),
                (state: "main", yields: ["pause::main", "ether"], throws: ["e_lost"]),
            ]),
            (name: "Init", kind: Function),
        ],
    )],
)"#;

#[test]
fn the_bindings_hold_an_enum_per_codel_a_trait_and_binds() {
    let text = rust_bindings(&load(ONE)).expect("generates");
    for want in [
        "pub mod r#type {",
        "pub enum RunMain {",
        "        PauseMain,\n",
        "        Ether,\n",
        "        ELost,\n",
        "RunMain::ELost => bip_engine::Next::Throw(\"e_lost\"),",
        "RunMain::PauseMain => bip_engine::Next::Yield(\"pause::main\"),",
        "fn run_start(&mut self, ctx: &mut bip_engine::Ctx<'_>) -> RunStart;",
        ".codel((\"type\", \"Run\", \"main\"), {",
        "pub fn bind(\n    builder: bip_engine::EngineBuilder,\n    r#type: impl r#type::Codels,\n",
    ] {
        assert!(text.contains(want), "no `{want}` in\n{text}");
    }
    // the same model, the same text
    assert_eq!(rust_bindings(&load(ONE)).expect("generates"), text);
}

#[test]
fn names_that_become_the_same_rust_name_are_an_error() {
    let text = ONE.replace(r#"throws: ["e_lost"]"#, r#"throws: ["pause_main"]"#);
    let err = rust_bindings(&load(&text)).expect_err("a clash");
    assert!(
        matches!(&err, CodegenError::Clash { rust, .. } if rust == "PauseMain"),
        "{err}"
    );
    assert_eq!(
        err.to_string(),
        "yield `pause::main` and exception `pause_main` both become `PauseMain` in the bindings; rename one"
    );
}

#[test]
fn a_model_without_codels_has_no_bindings_to_make() {
    let core = r#"System(name: "core", atoms: {"A": (locations: ["s"], initial: "s", transitions: [])},
        components: [(name: "a", atom: "A")])"#;
    let err = rust_bindings(&load(core)).expect_err("no layer");
    assert!(matches!(err, CodegenError::NoGenomLayer), "{err}");
}

#[test]
fn a_build_script_rewrites_the_bindings_only_when_they_change() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let model = dir.path().join("one.ron");
    let out = dir.path().join("one.rs");
    std::fs::write(&model, ONE).expect("writes");
    write_rust_bindings(&model, &out).expect("generates");
    let first = std::fs::metadata(&out)
        .and_then(|m| m.modified())
        .expect("written");
    std::thread::sleep(std::time::Duration::from_millis(20));
    write_rust_bindings(&model, &out).expect("generates");
    let second = std::fs::metadata(&out)
        .and_then(|m| m.modified())
        .expect("written");
    assert_eq!(first, second, "an unchanged model leaves the file alone");
    std::fs::write(&model, ONE.replace("e_lost", "e_gone")).expect("writes");
    write_rust_bindings(&model, &out).expect("generates");
    let text = std::fs::read_to_string(&out).expect("reads");
    assert!(text.contains("EGone") && !text.contains("ELost"));
    // a model with an error: its summary, with its position
    std::fs::write(&model, "System(name: 1)").expect("writes");
    let err = write_rust_bindings(&model, &out).expect_err("a bad model");
    assert!(err.to_string().contains("one.ron:1:"), "{err}");
}
