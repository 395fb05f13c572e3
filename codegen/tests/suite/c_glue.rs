//! The Rust glue of a GenoM3 component's C codels (`bip_codegen::c::rust_glue`): what it
//! declares for a small component, and what it refuses, by name. That the glue compiles
//! and runs is `testing/c-codels` and `examples/c-rover-controller`.

use bip_codegen::CodegenError;

fn glue(text: &str) -> Result<String, CodegenError> {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let gen = dir.path().join("g.gen");
    std::fs::write(&gen, text).expect("writes");
    let spec = bip_lang::read_gen_file(&gen, &[]).unwrap_or_else(|e| panic!("{e:?}"));
    bip_codegen::c::rust_glue(&spec)
}

const SMALL: &str = "component g {\n  exception e_far;\n  ids { long n; sequence<double, 4> xs; sequence<double> all; };\n  port out double level;\n  task t { period 10 ms; codel<start> g_boot(out ::ids) yield ether; };\n  activity Run(in long k, in double gain) {\n    task t;\n    throw e_far;\n    local long left;\n    codel<start> g_run(in k, in gain, out left, port out level) yield pause::go, ether;\n    codel<go> g_go(inout left, ids in xs) yield pause::go, ether;\n  };\n};\n";

#[test]
fn the_glue_declares_each_codel_and_numbers_them_as_the_engine_does() {
    let text = glue(SMALL).expect("generates");
    for want in [
        // the machine's codel first, then the service's, with their outcomes
        "service: \"t\", codel: \"start\", yields: &[\"ether\"], throws: &[]",
        "service: \"Run\", codel: \"go\", yields: &[\"pause::go\", \"ether\"], throws: &[\"e_far\"]",
        // prototypes' mirrors: by value, by pointer, a port's handle
        "fn g_run(a0: i32, a1: f64, a2: *mut i32, a3: *const PortHandle_level, this: *const bip_genom_c::ContextIface)",
        "fn g_go(a0: *mut i32, a1: *const super::sequence4_double",
        // the events' and the exception's symbols, of their names' sizes
        "static g_pause_go: [core::ffi::c_char; 15];",
        "static g_e_far_id: [core::ffi::c_char; 11];",
        // two parameters: the glue's struct, taken by name; copied at the start codel
        "pub struct Run_input {",
        "ctx.args::<Run_input>()",
        // the bounded sequences get their bound
        "v.ids.xs._maximum = 4;",
        // the out port: its data handed to the engine as the model's Float
        "write_port::<f64>(\"level\", v as f64)",
        // the codels' own buffers in the ids: the module object still goes to a task thread
        "unsafe impl Send for State {}",
        "pub fn bind(",
        "pub fn bind_shared(",
    ] {
        assert!(text.contains(want), "no `{want}` in\n{text}");
    }
}

fn refused(text: &str) -> String {
    match glue(text) {
        Err(CodegenError::CMapping(m)) => m,
        other => panic!("expected a refusal, got {:?}", other.map(|_| ())),
    }
}

#[test]
fn a_multiple_port_a_codel_takes_is_refused_by_name() {
    let m = refused("component h {\n  port multiple out double ps;\n  task t { period 10 ms; codel<start> h_s(port out ps) yield ether; };\n};\n");
    assert!(
        m.contains("component `h`") && m.contains("port `ps`") && m.contains("multiple"),
        "{m}"
    );
}

#[test]
fn a_port_or_a_request_of_pointers_is_refused_by_name() {
    let m = refused("component h {\n  port out sequence<double> ps;\n  task t { period 10 ms; codel<start> h_s(port out ps) yield ether; };\n};\n");
    assert!(m.contains("port `ps`") && m.contains("pointer"), "{m}");
    let m = refused("component h {\n  task t { period 10 ms; };\n  activity A(in string name, in long k) { task t; codel<start> h_a(in name, in k) yield ether; };\n};\n");
    assert!(m.contains("service `A`") && m.contains("`name`"), "{m}");
}
