//! Data types of ports, service arguments and outputs (docs/model.md, "Data types"): they
//! reach the engine's map as declared, and a wrong one is an error at its place.

use crate::support;
use support::errors::{assert_error, first_error};

use bip_lang::load_str;
use bip_model::genom::map::DataType;

const TYPED: &str = r#"System(
    name: "typed",
    constants: {"TOP": 9},
    modules: [(
        name: "nav",
        tasks: [(name: "t", period: 1)],
        ports: [
            (name: "pose", ty: Record(name: "Pose", fields: [(name: "x", ty: Float), (name: "ok", ty: Bool)])),
            (name: "map", ty: Rust("terrain::Dtm")),
            (name: "raw"),
        ],
        services: [
            (name: "GoTo", kind: Activity, task: "t", args: Float, output: Int(0, "TOP"),
             codels: [(state: "start", yields: ["ether"], writes: ["pose"])]),
            (name: "Stop", kind: Function, interrupts: ["GoTo"]),
        ],
    )],
)"#;

#[test]
fn declared_types_reach_the_engines_map() {
    let sys = load_str("typed.ron", TYPED).unwrap_or_else(|e| panic!("{}", e.summary()));
    let m = sys
        .genom
        .as_ref()
        .expect("layer")
        .module("nav")
        .expect("nav");
    let ty = |p: &str| {
        m.ports
            .iter()
            .find(|x| x.name == p)
            .and_then(|x| x.ty.clone())
    };
    assert_eq!(
        ty("pose"),
        Some(DataType::Record {
            name: "Pose".into(),
            fields: vec![("x".into(), DataType::Float), ("ok".into(), DataType::Bool)],
        })
    );
    assert_eq!(ty("map"), Some(DataType::Rust("terrain::Dtm".into())));
    assert_eq!(ty("raw"), None);
    let goto = sys
        .genom
        .as_ref()
        .and_then(|g| g.service("nav", "GoTo"))
        .expect("GoTo");
    assert_eq!(goto.args, Some(DataType::Float));
    assert_eq!(goto.output, Some(DataType::Int { lo: 0, hi: 9 }));
}

#[test]
fn a_type_matches_rust_values_by_their_type_names() {
    assert!(DataType::Float.accepts("f64"));
    assert!(!DataType::Float.accepts("f32"));
    assert!(DataType::Int { lo: 0, hi: 3 }.accepts("i64"));
    assert!(!DataType::Int { lo: 0, hi: 3 }.accepts("u32"));
    let dtm = DataType::Rust("terrain::Dtm".into());
    assert!(dtm.accepts("terrain::Dtm"));
    assert!(dtm.accepts("rover::terrain::Dtm"));
    assert!(!dtm.accepts("rover::terrain_x::Dtm"));
    assert!(!dtm.accepts("rover::Dtm"));
    let pose = DataType::Record {
        name: "Pose".into(),
        fields: Vec::new(),
    };
    assert!(pose.accepts("nav_bindings::Pose"));
    assert!(!pose.accepts("nav_bindings::OldPose"));
    assert_eq!(DataType::Rust("a::B".into()).to_string(), "Rust(\"a::B\")");
    assert_eq!(DataType::Int { lo: 0, hi: 3 }.to_string(), "Int(0, 3)");
}

#[test]
fn an_unknown_type_is_an_error_at_its_name() {
    let text = TYPED.replace("args: Float", "args: Double");
    let (msg, _, (line, _)) = first_error(&text);
    assert!(
        msg.contains("Double") && msg.contains("`DataType`"),
        "{msg}"
    );
    assert!(msg.contains("`Float`") && msg.contains("`Rust`"), "{msg}");
    assert_eq!(line, 13, "{msg}");
}

#[test]
fn a_missing_field_type_is_an_error_at_the_field() {
    let text = TYPED.replace("(name: \"ok\", ty: Bool)", "(name: \"ok\")");
    let (msg, _, (line, _)) = first_error(&text);
    assert!(msg.contains("ty"), "{msg}");
    assert_eq!(line, 8, "{msg}");
}

#[test]
fn bad_types_are_errors_with_their_place() {
    assert_error(
        &TYPED.replace("Int(0, \"TOP\")", "Int(5, 2)"),
        "type `Int(5, 2)` is empty",
        "2",
    );
    assert_error(
        &TYPED.replace("Int(0, \"TOP\")", "Int(0, \"TOPP\")"),
        "TOPP",
        "TOPP",
    );
    assert_error(
        &TYPED.replace("terrain::Dtm", "terrain Dtm!"),
        "`terrain Dtm!` is not a Rust type path",
        "terrain Dtm!",
    );
    assert_error(
        &TYPED.replace(
            "(name: \"x\", ty: Float)",
            "(name: \"x\", ty: Rust(\"f32\"))",
        ),
        "field `x` of record `Pose` has a Rust type",
        "f32",
    );
    assert_error(
        &TYPED.replace("(name: \"ok\", ty: Bool)", "(name: \"x\", ty: Bool)"),
        "x",
        "x",
    );
    assert_error(
        &TYPED.replace(
            "(name: \"Stop\", kind: Function,",
            "(name: \"Stop\", kind: Function, args: Bool,",
        ),
        "`Stop` is not an activity and has no codel for arguments",
        "Stop",
    );
}
