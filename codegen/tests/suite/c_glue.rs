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
        "let v = (*(*call).state).port_level;",
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
fn a_multiple_ports_handle_takes_the_instance_name_first() {
    let text = glue("component h {\n  port multiple out double ps;\n  port multiple in double qs;\n  task t { period 10 ms; codel<start> h_s(port out ps, port in qs) yield ether; };\n};\n").expect("generates");
    for want in [
        "pub port_ps: bip_genom_c::Instances<f64>,",
        "pub port_qs: bip_genom_c::Instances<f64>,",
        // GenoM3's members, in its order: data, write, open, close; data, read
        "data: unsafe extern \"C\" fn(*const core::ffi::c_char, *const bip_genom_c::ContextIface) -> *mut f64,\n    write: unsafe extern \"C\" fn(*const core::ffi::c_char, *const bip_genom_c::ContextIface) -> bip_genom_c::GenomEvent,\n    open: unsafe extern \"C\" fn(*const core::ffi::c_char, *const bip_genom_c::ContextIface) -> bip_genom_c::GenomEvent,\n    close:",
        "    read: unsafe extern \"C\" fn(*const core::ffi::c_char,",
        // the multiple in port's instance is opened by its first read
        "*(*(*call).state).port_qs.open(id) = v",
    ] {
        assert!(text.contains(want), "no `{want}` in\n{text}");
    }
}

const OWNED: &str = "component h {\n  ids { string label; };\n  port out sequence<octet> raw;\n  task t { period 10 ms; codel<start> h_s(port out raw) yield ether; };\n  activity A(in string name, in long k, out string said) { task t; codel<start> h_a(in name, in k, out said, inout label) yield ether; };\n};\n";

#[test]
fn strings_and_unbounded_sequences_are_owned_and_converted_as_the_model_types_them() {
    let text = glue(OWNED).expect("generates");
    for want in [
        // bip-genom-c's owning types, in the C layout
        "pub type sequence_octet = bip_genom_c::Sequence<u8>;",
        "pub label: bip_genom_c::GenomString,",
        // memory that owns buffers is cloned, never copied
        "#[derive(Clone)]\npub struct State {",
        "#[derive(Clone)]\npub struct A_input {",
        "d.name = v.name.clone();",
        // the model's `Vec<u8>` port and `String` output, converted from the mirrors
        "let v = (*(*call).state).port_raw.to_vec();",
        "ctx.set_output(d.said.to_string_lossy());",
        // `in string` as `const char *` into the owned string, `out string` as `char **`
        "fn h_a(a0: *const core::ffi::c_char, a1: i32, a2: *mut bip_genom_c::GenomString, a3: *mut bip_genom_c::GenomString,",
        "(*s).svc_A.name.0.cast_const()",
    ] {
        assert!(text.contains(want), "no `{want}` in\n{text}");
    }
}

#[test]
fn a_port_or_a_request_of_natives_is_refused_by_name() {
    let m = refused("native handle;\ncomponent h {\n  port out handle ps;\n  task t { period 10 ms; codel<start> h_s(port out ps) yield ether; };\n};\n");
    assert!(m.contains("port `ps`") && m.contains("native"), "{m}");
    let m = refused("native handle;\ncomponent h {\n  task t { period 10 ms; };\n  activity A(in handle dev, in long k) { task t; codel<start> h_a(in dev, in k) yield ether; };\n};\n");
    assert!(m.contains("service `A`") && m.contains("`dev`"), "{m}");
}

#[test]
fn a_union_owning_a_buffer_is_refused_by_name() {
    let m = refused("enum kind { a, b };\nunion u switch (kind) { case a: string s; case b: long n; };\ncomponent h {\n  ids { u x; };\n  task t { period 10 ms; };\n};\n");
    assert!(m.contains("`u`") && m.contains("union"), "{m}");
}

#[test]
fn a_sequence_the_model_names_otherwise_than_its_mirror_is_refused_by_name() {
    let m = refused("struct p { double x; };\ncomponent h {\n  port out sequence<p> ps;\n  task t { period 10 ms; codel<start> h_s(port out ps) yield ether; };\n};\n");
    assert!(m.contains("port `ps`") && m.contains("Vec<p>"), "{m}");
}

#[test]
fn a_long_double_is_its_bytes_but_not_by_value() {
    let text = glue("component h {\n  ids { long double x; };\n  port out long double level;\n  task t { period 10 ms; codel<start> h_s(inout x, port out level) yield ether; };\n};\n").expect("generates");
    assert!(text.contains("pub x: bip_genom_c::LongDouble,"), "{text}");
    assert!(
        text.contains("let v = (*(*call).state).port_level.to_f64();"),
        "{text}"
    );
    let m = refused("component h {\n  ids { long double x; };\n  task t { period 10 ms; codel<start> h_s(in x) yield ether; };\n};\n");
    assert!(
        m.contains("codel `h_s`") && m.contains("`x`") && m.contains("in long double"),
        "{m}"
    );
}

#[test]
fn a_component_the_glue_refuses_leaves_no_file_behind() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let gen = dir.path().join("g.gen");
    std::fs::write(
        &gen,
        "component h {\n  ids { long double x; };\n  task t { period 10 ms; codel<start> h_s(in x) yield ether; };\n};\n",
    )
    .expect("writes");
    let spec = bip_lang::read_gen_file(&gen, &[]).unwrap_or_else(|e| panic!("{e:?}"));
    let out = dir.path().join("out");
    let to = bip_codegen::c::CBindings {
        include: out.join("include"),
        rust: out.join("g_c.rs"),
    };
    assert!(bip_codegen::c::write_c_bindings_of(&[&spec], &to).is_err());
    assert!(!out.exists(), "files were written before the refusal");
}
