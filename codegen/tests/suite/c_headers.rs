//! The C headers of a GenoM3 component (`bip_codegen::c`), checked with gcc: every IDL
//! type the importer reads (fixtures/every_type.gen) has the size, the alignment and the
//! member offsets that bip-codegen computes for the memory the engine owns; the
//! prototypes follow GenoM3's passing convention, so that codels written to it compile
//! with every warning an error, and a codel of another prototype fails at the codel.

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use bip_codegen::c::ctype::{Body, CType, CTypes};
use bip_codegen::CodegenError;

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/every_type.gen")
}

/// The fixture's headers written in a temporary folder, and the declarations its
/// component sees.
fn headers() -> (tempfile::TempDir, CTypes) {
    let spec = bip_lang::read_gen_file(&fixture(), &[]).unwrap_or_else(|e| panic!("{e:?}"));
    let dir = tempfile::tempdir().expect("a temporary folder");
    bip_codegen::write_c_headers_of(&spec, dir.path()).expect("writes the headers");
    let types = bip_codegen::c::c_types(&spec, &spec.components[0]).expect("maps every type");
    (dir, types)
}

/// Runs gcc in `dir` with `args`; its status and what it said, in the C locale.
fn gcc(dir: &Path, args: &[&str]) -> (bool, String) {
    compiler(dir, "gcc", "-std=c11", args)
}

/// Runs `program` (gcc or g++) in `dir` with `std`, every warning an error (but unused
/// parameters, which codels often have) and `args`.
fn compiler(dir: &Path, program: &str, std: &str, args: &[&str]) -> (bool, String) {
    let out = Command::new(program)
        .current_dir(dir)
        .env("LC_ALL", "C")
        .args([
            std,
            "-Wall",
            "-Wextra",
            "-Wno-unused-parameter",
            "-Werror",
            "-I.",
        ])
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("{program} runs (the C headers' tests need it): {e}"));
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The anonymous sequences and optionals within `t`, by C name.
fn templates(t: &CType, out: &mut Vec<CType>) {
    match t {
        CType::Sequence(e, _) | CType::Optional(e) => {
            templates(e, out);
            out.push(t.clone());
        }
        CType::Array(e, _) => templates(e, out),
        _ => {}
    }
}

/// Every type of the headers with a layout: the declared ones (but natives, which are
/// opaque, and exceptions without members, whose detail is `void`), the ids struct and
/// every anonymous sequence and optional.
fn laid_out(types: &CTypes) -> Vec<CType> {
    let mut all = Vec::new();
    for key in &types.order {
        let Some(d) = types.decl(key) else { continue };
        let members: Vec<&CType> = match &d.body {
            Body::Native | Body::Const { .. } => continue,
            Body::Exception(ms) if ms.is_empty() => continue,
            Body::Struct(ms) | Body::Exception(ms) => ms.iter().map(|(_, t)| t).collect(),
            Body::Union { switch, members } => std::iter::once(switch)
                .chain(members.iter().map(|(_, t)| t))
                .collect(),
            Body::Typedef(t) => vec![t],
            Body::Enum(_) => Vec::new(),
        };
        for t in members {
            templates(t, &mut all);
        }
        all.push(CType::Named(key.clone()));
    }
    let mut seen = BTreeSet::new();
    all.retain(|t| seen.insert(types.name(t)));
    all
}

#[test]
fn every_type_the_importer_reads_has_gccs_layout() {
    let (dir, types) = headers();
    let all = laid_out(&types);
    let mut probe = String::from(
        "#include <stdio.h>\n#include <stddef.h>\n#include \"probe_c_types.h\"\nint main(void)\n{\n",
    );
    let mut want = String::new();
    for t in &all {
        let name = types.name(t);
        let l = types.layout(t).expect("a layout");
        let _ = writeln!(
            probe,
            "  printf(\"%s %zu %zu\\n\", \"{name}\", sizeof({name}), _Alignof({name}));"
        );
        let _ = writeln!(want, "{name} {} {}", l.size, l.align);
        for (field, at) in types.offsets(t).expect("offsets") {
            let _ = writeln!(
                probe,
                "  printf(\"%s.%s %zu\\n\", \"{name}\", \"{field}\", offsetof({name}, {field}));"
            );
            let _ = writeln!(want, "{name}.{field} {at}");
        }
    }
    probe.push_str("  return 0;\n}\n");
    std::fs::write(dir.path().join("probe.c"), &probe).expect("writes");
    let (ok, said) = gcc(dir.path(), &["probe.c", "-o", "probe"]);
    assert!(ok, "the headers do not compile:\n{said}");
    let run = Command::new(dir.path().join("probe"))
        .output()
        .expect("runs");
    let got = String::from_utf8_lossy(&run.stdout);
    // every kind of type is in the comparison
    for name in [
        "geo_basics",
        "geo_everything",
        "geo_reading",
        "geo_mode",
        "geo_mat",
        "geo_samples",
        "sequence_double",
        "sequence8_geo_vec",
        "sequence_sequence4_long",
        "sequence4_long",
        "sequence2_string8",
        "optional_geo_vec",
        "optional_sequence_float",
        "geo_everything_inner",
        "probe_ids_limits_s",
        "probe_e_bad_detail",
        "probe_ids",
        "geo_tree",
        "sequence_geo_tree",
    ] {
        assert!(
            all.iter().any(|t| types.name(t) == name),
            "{name} is not compared"
        );
    }
    let diff: Vec<String> = want
        .lines()
        .zip(got.lines())
        .filter(|(w, g)| w != g)
        .map(|(w, g)| format!("bip-codegen: {w}   gcc: {g}"))
        .collect();
    assert!(diff.is_empty(), "layouts differ:\n{}", diff.join("\n"));
    assert_eq!(want.lines().count(), got.lines().count());
}

#[test]
fn the_mapping_follows_genom3s_table() {
    let (dir, _) = headers();
    let text = std::fs::read_to_string(dir.path().join("probe_c_types.h")).expect("reads");
    for want in [
        // basic types
        "  bool b;\n  int8_t c;\n  uint8_t o;\n  int8_t i8;\n  uint8_t u8;\n  int16_t s;\n  int16_t i16;\n  uint16_t us;\n  uint16_t u16;\n  int32_t l;\n  int32_t i32;\n  uint32_t ul;\n  uint32_t u32;\n  int64_t ll;\n  int64_t i64;\n  uint64_t ull;\n  uint64_t u64;\n  float f;\n  double d;\n  long double ld;\n",
        // strings, arrays, scoped names, natives
        "  geo_label name;\n  geo_text note;\n  char odd[7];\n  geo_mat rotation;\n  uint8_t bytes[3][5];\n",
        "typedef char geo_label[16];",
        // numeric constants (a string constant is not mapped)
        "static const int32_t geo_dim = 3;",
        "static const double geo_half = 0.5;",
        "static const uint64_t geo_big = 18446744073709551615ULL;",
        "typedef char *geo_text;",
        "typedef double geo_mat[3][3];",
        "  geo_handle *h;\n",
        "typedef struct geo_handle geo_handle;",
        // enums
        "typedef uint32_t geo_mode;\nenum {\n  geo_idle = 0,\n  geo_busy = 1,\n  geo_broken = 2,\n};",
        // sequences and optionals
        "typedef struct sequence_double {\n  uint32_t _maximum, _length;\n  double *_buffer;\n  void (*_release)(void *_buffer);\n} sequence_double;",
        "typedef struct sequence8_geo_vec {\n  const uint32_t _maximum;\n  uint32_t _length;\n  geo_vec _buffer[8];\n#ifdef __cplusplus\n",
        "#endif\n} sequence8_geo_vec;",
        "typedef struct optional_geo_vec {\n  bool _present;\n  geo_vec _value;\n} optional_geo_vec;",
        // unions
        "struct geo_reading {\n  int16_t _d;\n  union {\n    double range;\n    geo_vec direction;\n    int8_t code;\n  } _u;\n};",
        // exceptions
        "const char genom_extern_weak probe_e_bad_id[] = \"::probe::e_bad\";",
        "probe_e_bad(probe_e_bad_detail *d, genom_context self)",
        "typedef void probe_e_plain_detail;",
        "probe_e_plain(genom_context self)",
        // events
        "const char genom_extern_weak probe_pause_run[] = \"::probe::pause::run\";",
        "const char genom_extern_weak probe_ether[] = \"::probe::ether\";",
        // ports
        "typedef struct probe_position {\n  geo_vec *(*data)(genom_context self);\n  genom_event (*write)(genom_context self);\n} probe_position;",
        "  double (*(*data)(const char *id, genom_context self))[3];\n  genom_event (*read)(const char *id, genom_context self);\n",
        "  genom_event (*open)(const char *id, genom_context self);",
        // the passing conventions: in by value, a struct by const pointer, out and inout
        // by pointer, an array as an array, ports as const handles, the context last
        "probe_check(const geo_vec *t, double gain, const genom_context self);",
        // an attribute's ids member, named by its last member
        "probe_check_limits(double lo, double hi, probe_ids_limits_s *limits, const genom_context self);",
        "probe_set_target(const geo_vec *t, geo_vec *target, double gains[4], const genom_context self);",
        "probe_track_start(const geo_label who, int32_t steps, double *best, const geo_label name, const geo_vec *target, const probe_world *world, const genom_context self);",
        "probe_track_run(probe_ids_limits_s *limits, geo_basics *all, const geo_mat rotation, double gains, const probe_frames *frames, const probe_sensors *sensors, int32_t *count, bool *armed, const genom_context self);",
        "probe_main_start(probe_ids *ids, const probe_position *position, const genom_context self);",
    ] {
        assert!(text.contains(want), "the header lacks\n{want}\n---\n{text}");
    }
    assert!(!text.contains("greeting"), "a string constant is mapped");
}

/// Codels of the fixture as GenoM3's convention declares them, one of them (`probe_check`)
/// as `check` says.
fn codels(check: &str) -> String {
    format!(
        r#"#include "acprobe.h"
#include "probe_c_types.h"

genom_event
{check}
{{
  return t->v[0] > gain ? probe_ether : genom_ok;
}}

genom_event
probe_set_target(const geo_vec *t, geo_vec *target, double gains[4],
                 const genom_context self)
{{
  (void)self;
  *target = *t;
  gains[0] = 1.;
  return genom_ok;
}}

genom_event
probe_main_start(probe_ids *ids, const probe_position *position,
                 const genom_context self)
{{
  ids->state.values._length = 0;
  if (genom_sequence_reserve(&ids->state.values, 4)) return genom_fatal;
  *position->data(self) = ids->target;
  position->write(self);
  return probe_ether;
}}

genom_event
probe_track_run(probe_ids_limits_s *limits, geo_basics *all,
                const geo_mat rotation, double gains, const probe_frames *frames,
                const probe_sensors *sensors, int32_t *count, bool *armed,
                const genom_context self)
{{
  probe_e_bad_detail d = {{ .code = 3, .why = "out of range" }};
  (void)rotation; (void)frames; (void)sensors; (void)armed;
  limits->hi = gains;
  all->b = true;
  if (++*count > 3) return probe_e_bad(&d, self);
  if (*count > 2) return probe_e_plain(self);
  return *count ? probe_pause_run : probe_ether;
}}
"#
    )
}

const CHECK: &str = "probe_check(const geo_vec *t, double gain, const genom_context self)";

#[test]
fn codels_of_genom3s_prototypes_compile_and_another_fails_at_the_codel() {
    let (dir, _) = headers();
    std::fs::write(dir.path().join("codels.c"), codels(CHECK)).expect("writes");
    let (ok, said) = gcc(dir.path(), &["-c", "codels.c", "-o", "codels.o"]);
    assert!(ok, "codels of GenoM3's prototypes do not compile:\n{said}");

    // an `in` struct taken by a pointer that is not const: not GenoM3's prototype
    let wrong = "probe_check(geo_vec *t, double gain, const genom_context self)";
    std::fs::write(dir.path().join("codels.c"), codels(wrong)).expect("writes");
    let (ok, said) = gcc(dir.path(), &["-c", "codels.c", "-o", "codels.o"]);
    assert!(!ok, "a wrong prototype compiled");
    assert!(
        said.contains("codels.c:5:1: error: conflicting types for 'probe_check'"),
        "gcc's error is not at the codel:\n{said}"
    );
    assert!(said.contains("probe_c_types.h"), "{said}");
}

#[test]
fn a_type_genom3_does_not_map_is_an_error_naming_its_place() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let gen = dir.path().join("w.gen");
    std::fs::write(
        &gen,
        "component w {\n  port out any p;\n  task t { period 10 ms; codel<start> w_start() yield ether; };\n};\n",
    )
    .expect("writes");
    let spec = bip_lang::read_gen_file(&gen, &[]).unwrap_or_else(|e| panic!("{e:?}"));
    match bip_codegen::c_headers(&spec) {
        Err(CodegenError::CMapping(m)) => {
            assert!(m.contains("port `p`") && m.contains("`any`"), "{m}")
        }
        other => panic!("expected no C mapping, got {:?}", other.map(|_| ())),
    }
}

#[test]
fn an_event_and_a_codel_of_one_c_name_are_an_error() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let gen = dir.path().join("k.gen");
    std::fs::write(
        &gen,
        "component k {\n  task t { period 10 ms; codel<start> k_start() yield go; codel<go> k_go() yield ether; };\n};\n",
    )
    .expect("writes");
    let spec = bip_lang::read_gen_file(&gen, &[]).unwrap_or_else(|e| panic!("{e:?}"));
    match bip_codegen::c_headers(&spec) {
        Err(CodegenError::Clash { rust, .. }) => assert_eq!(rust, "k_go"),
        other => panic!("expected a clash, got {:?}", other.map(|_| ())),
    }
}

#[test]
fn a_type_that_holds_itself_is_refused_at_once() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let gen = dir.path().join("r.gen");
    // each level holds the next twice: laid out naively, 2^64 visits
    std::fs::write(
        &gen,
        "struct knot { sequence<knot, 2> a; sequence<knot, 2> b; };\ncomponent r {\n  port out knot k;\n  task t { period 10 ms; codel<start> r_start(port out k) yield ether; };\n};\n",
    )
    .expect("writes");
    let spec = bip_lang::read_gen_file(&gen, &[]).unwrap_or_else(|e| panic!("{e:?}"));
    match bip_codegen::c_headers(&spec) {
        Err(CodegenError::CMapping(m)) => assert!(m.contains("`knot` holds itself"), "{m}"),
        other => panic!("expected no C mapping, got {:?}", other.map(|_| ())),
    }
}

#[test]
fn cxx_codels_compile_against_the_headers_too() {
    // GenoM3 components may write codels in C++ (`lang "c"` with `.cc` files): the headers
    // are `extern "C"`, and a bounded sequence has its `_maximum` set and can be assigned
    let (dir, _) = headers();
    let codel = r#"#include "probe_c_types.h"

genom_event
probe_check(const geo_vec *t, double gain, const genom_context self)
{
  sequence8_geo_vec trail;
  sequence8_geo_vec copy;
  trail._length = 1;
  trail._buffer[0] = *t;
  copy = trail;
  return copy._maximum == 8 && copy._buffer[0].v[0] > gain ? probe_ether : genom_ok;
}
"#;
    std::fs::write(dir.path().join("codel.cc"), codel).expect("writes");
    let (ok, said) = compiler(
        dir.path(),
        "g++",
        "-std=c++11",
        &["-c", "codel.cc", "-o", "codel.o"],
    );
    assert!(ok, "a C++ codel does not compile:\n{said}");
}

#[test]
fn a_build_script_rewrites_the_headers_only_when_they_change() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let gen = dir.path().join("b.gen");
    let out = dir.path().join("include");
    let component = "component b {\n  ids { double x; };\n  task t { period 10 ms; codel<start> b_start(inout x) yield ether; };\n};\n";
    std::fs::write(&gen, component).expect("writes");
    let paths = bip_codegen::write_c_headers(&gen, &[], &out).expect("writes the headers");
    let header = out.join("b_c_types.h");
    assert!(paths.contains(&header) && paths.contains(&out.join("genom3/c/context.h")));
    let modified = || {
        std::fs::metadata(&header)
            .and_then(|m| m.modified())
            .expect("written")
    };
    let first = modified();
    std::thread::sleep(std::time::Duration::from_millis(20));
    bip_codegen::write_c_headers(&gen, &[], &out).expect("writes the headers");
    assert_eq!(
        first,
        modified(),
        "an unchanged file leaves the header alone"
    );
    std::fs::write(&gen, component.replace("double x", "float x")).expect("writes");
    bip_codegen::write_c_headers(&gen, &[], &out).expect("writes the headers");
    let text = std::fs::read_to_string(&header).expect("reads");
    assert!(
        text.contains("b_start(float *x, const genom_context self);"),
        "{text}"
    );
    // a file with an error: its summary, with its position
    std::fs::write(&gen, "component b {\n  ids { double x; }\n};\n").expect("writes");
    let err = bip_codegen::write_c_headers(&gen, &[], &out).expect_err("a bad file");
    assert!(err.to_string().contains("b.gen:3:"), "{err}");
}

#[test]
fn every_type_has_a_rust_mirror_a_long_double_its_bytes() {
    let spec = bip_lang::read_gen_file(&fixture(), &[]).expect("reads");
    let mirrors = bip_codegen::c::rust_mirrors(&spec);
    if cfg!(any(target_arch = "x86_64", target_arch = "aarch64")) {
        let text = mirrors.expect("every type has a mirror");
        assert!(text.contains("pub ld: bip_genom_c::LongDouble,"), "{text}");
    } else {
        let err = mirrors.expect_err("no long double here").to_string();
        assert!(
            err.contains("long double") && err.contains("`geo::basics`"),
            "{err}"
        );
    }
}
