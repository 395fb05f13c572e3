//! bip-codegen from the outside: what the bindings hold, names that would clash, and a
//! build script's rewrite only on change. That the rover's bindings compile and run is
//! `testing/rover-bindings`.

mod c_glue;
mod c_headers;

use bip_codegen::{rust_bindings, rust_bindings_no_std, write_rust_bindings, CodegenError};

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
        // numbered as the model declares them, as `Next::Declared` takes them
        "#[repr(u16)]\n    pub enum RunMain {",
        "bip_engine::Next::Declared(outcome as u16)",
        "fn run_start(&mut self, ctx: RunStartCtx<'_, '_>) -> RunStart;",
        // the numbering the engine checks against its model
        "bip_engine::CodelSignature {\n            service: \"Run\",\n            codel: \"main\",\n            yields: &[\"pause::main\", \"ether\"],\n            throws: &[\"e_lost\"],\n        },",
        // and the data types the typed code assumes, declared where the module is bound
        "pub const TYPES: bip_engine::ModuleTypes = bip_engine::ModuleTypes {\n        ids: &[],\n        ports: &[],\n        services: &[\n            bip_engine::ServiceTypes {\n                name: \"Run\",\n                args: \"\",\n                output: \"\",\n            },",
        "builder\n            .typed_as(\"type\", &TYPES)\n            .module(\"type\", CODELS, move |codel, ctx| match codel {",
        "1 => codels.run_main(RunMainCtx { ctx }).into(),",
        "pub fn bind(\n    builder: bip_engine::EngineBuilder,\n    r#type: impl r#type::Codels,\n",
    ] {
        assert!(text.contains(want), "no `{want}` in\n{text}");
    }
    // the same model, the same text
    assert_eq!(rust_bindings(&load(ONE)).expect("generates"), text);
}

const TYPED: &str = r#"System(
    name: "typed",
    modules: [(
        name: "nav",
        tasks: [(name: "t", period: 1)],
        ids: [(name: "gear", ty: Int(-1, 3), init: 0), (name: "armed", ty: Bool, init: false)],
        ports: [(name: "pose", ty: Record(name: "Pose", fields: [(name: "x", ty: Float), (name: "ok", ty: Bool)])),
                (name: "map", ty: Rust("crate::world::Map")), (name: "raw"),
                (name: "level", ty: Int(0, 100)),
                (name: "cell", ty: Record(name: "Cell", fields: [(name: "row", ty: Int(-8, 8))]))],
        services: [
            (name: "GoTo", kind: Activity, task: "t", args: Int(0, 9), output: Record(name: "Pose", fields: [(name: "x", ty: Float), (name: "ok", ty: Bool)]),
             codels: [
                (state: "start", yields: ["main"], writes: ["gear", "armed"]),
                (state: "main", yields: ["pause::main", "ether"], throws: ["e_lost"], writes: ["pose", "level"]),
            ]),
            (name: "Count", kind: Activity, task: "t", output: Int(0, 9),
             codels: [(state: "start", yields: ["ether"], throws: ["e_lost"])]),
        ],
    )],
)"#;

#[test]
fn the_bindings_type_what_each_codel_may_touch() {
    let text = rust_bindings(&load(TYPED)).expect("generates");
    for want in [
        // a record is a struct, once, though two places declare it
        "pub struct Pose {\n    /// Field `x`: Float.\n    pub x: f64,\n    /// Field `ok`: Bool.\n    pub ok: bool,\n}",
        // every codel reads every typed port; a Rust path is used as written
        "pub fn read_nav_pose(&self) -> Option<&super::Pose> {",
        "pub fn read_nav_map(&self) -> Option<&crate::world::Map> {",
        // only the codel that writes a port or an ids field has its writer
        "pub fn write_pose(&mut self, value: super::Pose) {",
        "pub fn port_pose_mut(&mut self) -> Option<&mut super::Pose> {",
        // an ids field of a range is a Bounded, a Bool one a bool
        "pub fn set_ids_gear(&mut self, value: bip_engine::Bounded<-1, 3>) {\n            self.ctx.set(\"gear\", value.get());",
        "pub fn ids_gear(&self) -> bip_engine::Bounded<-1, 3> {",
        "pub fn ids_armed(&self) -> bool {\n            self.ctx.get_bool(\"armed\").unwrap_or_default()",
        "pub fn set_ids_armed(&mut self, value: bool) {\n            self.ctx.set_bool(\"armed\", value);",
        // an Int port: the engine holds an i64, the context gives and takes a Bounded by
        // value, and gives no `&mut i64`
        "pub fn read_nav_level(&self) -> Option<bip_engine::Bounded<0, 100>> {\n            self.ctx.port::<i64>(\"nav\", \"level\").and_then(|v| bip_engine::Bounded::new(*v))",
        "pub fn write_level(&mut self, value: bip_engine::Bounded<0, 100>) {\n            self.ctx.write_port(\"level\", value.get());",
        // the data types the code assumes, a record's in full, for the engine to check
        "bip_engine::Typed {\n                name: \"gear\",\n                ty: \"Int(-1, 3)\",\n            },",
        "bip_engine::Typed {\n                name: \"pose\",\n                ty: \"Record(name: \\\"Pose\\\", fields: [(name: \\\"x\\\", ty: Float), (name: \\\"ok\\\", ty: Bool)])\",\n            },",
        "bip_engine::Typed {\n                name: \"raw\",\n                ty: \"\",\n            },",
        // a record's Int field is a Bounded
        "pub struct Cell {\n    /// Field `row`: Int(-8, 8).\n    pub row: bip_engine::Bounded<-8, 8>,\n}",
        // the service's arguments and output, of their types; an Int's by value
        "pub fn args(&self) -> Option<bip_engine::Bounded<0, 9>> {\n            self.ctx.args::<i64>().and_then(|v| bip_engine::Bounded::new(*v))",
        "pub fn set_output(&mut self, value: super::Pose) {",
        "pub fn set_output(&mut self, value: bip_engine::Bounded<0, 9>) {\n            self.ctx.set_output(value.get());",
        // a typed request, and its typed end; an Int is sent as its i64
        "pub fn request_go_to(\n        engine: &mut bip_engine::Engine,\n        args: bip_engine::Bounded<0, 9>,\n    ) -> Result<GoToTicket, bip_engine::RequestError> {\n        engine.request(\"nav\", \"GoTo\", args.get()).map(GoToTicket)",
        "Done(Option<bip_engine::Bounded<0, 9>>),",
        "\"e_lost\" => CountEnd::Exception(CountException::ELost, output.as_ref().and_then(|o| o.get::<i64>()).and_then(|v| bip_engine::Bounded::new(*v))),",
        "Done(Option<super::Pose>),",
        "Exception(GoToException, Option<super::Pose>),",
        "\"e_lost\" => GoToEnd::Exception(GoToException::ELost, output.as_ref().and_then(|o| o.get::<super::Pose>()).cloned()),",
    ] {
        assert!(text.contains(want), "no `{want}` in\n{text}");
    }
    let contexts: Vec<&str> = text.split("pub struct GoTo").collect();
    let start = contexts
        .iter()
        .find(|c| c.starts_with("StartCtx"))
        .expect("start's context");
    let main = contexts
        .iter()
        .find(|c| c.starts_with("MainCtx"))
        .expect("main's context");
    assert!(
        !start.contains("fn write_pose"),
        "start does not write pose"
    );
    assert!(
        !main.contains("fn set_ids_gear"),
        "main does not write gear"
    );
    assert!(
        !text.contains("port_level_mut"),
        "no `&mut i64` to an Int port"
    );
    // an untyped port has no typed accessor
    assert!(!text.contains("read_nav_raw"), "{text}");
}

#[test]
fn requests_from_other_threads_are_left_out_without_std() {
    let with_std = rust_bindings(&load(TYPED)).expect("generates");
    let handle_request = "pub fn request_go_to_from(\n        handle: &bip_engine::Handle,\n        args: bip_engine::Bounded<0, 9>,\n    ) -> Result<GoToPending, bip_engine::RequestError> {\n        handle.request(\"nav\", \"GoTo\", args.get()).map(GoToPending)";
    assert!(with_std.contains(handle_request), "{with_std}");
    assert!(with_std.contains("pub struct GoToPending(pub bip_engine::PendingReply);"));
    let without = rust_bindings_no_std(&load(TYPED)).expect("generates");
    assert!(
        !without.contains("Handle") && !without.contains("std::"),
        "{without}"
    );
    // the rest is there: the requests, their tickets and ends
    for want in [
        "pub fn request_go_to(",
        "pub struct GoToTicket(pub bip_engine::Ticket);",
        "pub enum GoToEnd {",
    ] {
        assert!(without.contains(want), "no `{want}` in\n{without}");
    }
    assert!(!without.contains("Pending"), "{without}");
}

#[test]
fn two_records_of_one_name_with_other_fields_are_an_error() {
    let text = TYPED.replacen("(name: \"ok\", ty: Bool)", "(name: \"ok\", ty: Float)", 1);
    let err = rust_bindings(&load(&text)).expect_err("a clash");
    assert!(
        matches!(&err, CodegenError::Clash { rust, .. } if rust == "Pose"),
        "{err}"
    );
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

/// A task's machine gets its codels in the module's trait, like an activity's, and no
/// request: nothing requests it.
#[test]
fn a_task_machine_has_codel_methods_and_no_request() {
    let text = rust_bindings(&load(include_str!(
        "../../../robots/tests/task-machine.ron"
    )))
    .expect("generates");
    for want in [
        "fn main_start(&mut self, ctx: MainStartCtx<'_, '_>) -> MainStart;",
        "fn main_control(&mut self, ctx: MainControlCtx<'_, '_>) -> MainControl;",
        "pub fn request_calibrate(",
    ] {
        assert!(text.contains(want), "missing `{want}` in\n{text}");
    }
    assert!(!text.contains("request_main"), "{text}");
}
