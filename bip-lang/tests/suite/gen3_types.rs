//! The IDL types of a `.gen` file's ports and activity parameters as the model's data
//! types (docs/genom.md, "GenoM3 files", "IDL types"): each kind of IDL type, a bound on a
//! record's size, what `bip import` prints loads with those types, and the rover's `.gen`
//! files give the types its RON twin declares.

use std::path::Path;

use crate::gen3::TempDir;
use bip_lang::{import_gen_file, load_file, load_str};
use bip_model::genom::map::{DataType, GenomMap};

const TYPES: &str = r#"
module geo {
  struct point { double x, y; };
  struct tagged { point p; enum side { left, right } s; boolean on; };
  struct with_array { double m[3]; };
  struct with_text { string name; };
  typedef point alias;
  typedef alias alias2;
  typedef sequence<point, 8> points;
  typedef double vec3[3];
  enum colour { red, green, blue };
  union u switch (short) { case 1: long a; default: double b; };
  native handle;
  module inner {
    typedef long count;
    struct uses_outer { point p; count n; };
  };
};

component types {
  port out boolean p_bool;
  port out short p_short;
  port out unsigned short p_ushort;
  port out long p_long;
  port out unsigned long p_ulong;
  port out long long p_llong;
  port out unsigned long long p_ullong;
  port out octet p_octet;
  port out char p_char;
  port out int8 p_int8;
  port out uint32 p_uint32;
  port out wchar p_wchar;
  port out float p_float;
  port out double p_double;
  port out geo::point p_point;
  port out geo::tagged p_tagged;
  port out geo::with_array p_with_array;
  port out geo::with_text p_with_text;
  port out geo::alias2 p_alias;
  port out geo::points p_points;
  port out geo::vec3 p_vec3;
  port out geo::colour p_colour;
  port out geo::u p_union;
  port out geo::handle p_native;
  port out geo::inner::uses_outer p_scoped;
  port out ::geo::point p_absolute;
  port out sequence<double> p_seq;
  port out sequence<geo::point, 4> p_seq_named;
  port out string<16> p_string;
  port out optional<long> p_optional;
  port out or::pose::state p_undeclared;
  port in double p_in;

  task t { period 10 ms; };

  activity One(in double x) { task t; codel<start> one() yield ether; };
  activity Several(in long n, in geo::point at, out boolean done, inout double gain) {
    task t; codel<start> several() yield ether;
  };
  activity Opaque(in geo::points route, in double speed, out double m[3]) {
    task t; codel<start> opaque() yield ether;
  };
  activity Nothing() { task t; codel<start> nothing() yield ether; };
  function F(in double x, out double y) { codel f(in x, out y); };
  attribute A(in x = 1);
};
"#;

fn int(lo: i64, hi: i64) -> DataType {
    DataType::Int { lo, hi }
}

fn rust(path: &str) -> DataType {
    DataType::Rust(path.to_string())
}

fn record(name: &str, fields: &[(&str, DataType)]) -> DataType {
    DataType::Record {
        name: name.to_string(),
        fields: fields
            .iter()
            .map(|(n, t)| (n.to_string(), t.clone()))
            .collect(),
    }
}

/// `TYPES` imported, printed as `bip import` prints it and loaded back: its GenoM map.
fn loaded() -> GenomMap {
    let dir = TempDir::new();
    let path = dir.write("types.gen", TYPES);
    let def = import_gen_file(&path, &[]).unwrap_or_else(|e| panic!("{}", e.summary()));
    let text = def.to_ron_nested(6).expect("prints");
    let system =
        load_str("imported.ron", &text).unwrap_or_else(|e| panic!("{}\n{text}", e.summary()));
    system.genom.expect("a GenoM layer")
}

#[test]
fn each_kind_of_idl_type_becomes_its_data_type() {
    let genom = loaded();
    let m = &genom.modules[0];
    let port = |name: &str| {
        m.ports
            .iter()
            .find(|p| p.name == name)
            .unwrap_or_else(|| panic!("port {name}"))
            .ty
            .clone()
    };
    let point = record("point", &[("x", DataType::Float), ("y", DataType::Float)]);
    let expected = [
        ("p_bool", DataType::Bool),
        ("p_short", int(-32_768, 32_767)),
        ("p_ushort", int(0, 65_535)),
        ("p_long", int(-2_147_483_648, 2_147_483_647)),
        ("p_ulong", int(0, 4_294_967_295)),
        ("p_llong", int(i64::MIN, i64::MAX)),
        // beyond an Int's i64
        ("p_ullong", rust("u64")),
        ("p_octet", int(0, 255)),
        ("p_char", int(0, 255)),
        ("p_int8", int(-128, 127)),
        ("p_uint32", int(0, 4_294_967_295)),
        ("p_wchar", rust("char")),
        ("p_float", DataType::Float),
        ("p_double", DataType::Float),
        ("p_point", point.clone()),
        // a structure within, an inline enumeration
        (
            "p_tagged",
            record(
                "tagged",
                &[
                    ("p", point.clone()),
                    ("s", int(0, 1)),
                    ("on", DataType::Bool),
                ],
            ),
        ),
        // a field without a model type: the structure is named
        ("p_with_array", rust("geo::with_array")),
        ("p_with_text", rust("geo::with_text")),
        // typedefs resolved, through each other
        ("p_alias", point.clone()),
        ("p_points", rust("geo::points")),
        ("p_vec3", rust("geo::vec3")),
        ("p_colour", int(0, 2)),
        ("p_union", rust("geo::u")),
        ("p_native", rust("geo::handle")),
        // names resolved from the enclosing scopes
        (
            "p_scoped",
            record(
                "uses_outer",
                &[
                    ("p", point.clone()),
                    ("n", int(-2_147_483_648, 2_147_483_647)),
                ],
            ),
        ),
        ("p_absolute", point.clone()),
        // anonymous types, spelt in Rust
        ("p_seq", rust("Vec<f64>")),
        ("p_seq_named", rust("Vec<geo::point>")),
        ("p_string", rust("String")),
        ("p_optional", rust("Option<i32>")),
        ("p_undeclared", rust("or::pose::state")),
    ];
    for (name, ty) in expected {
        assert_eq!(port(name), Some(ty), "port {name}");
    }
    assert_eq!(m.ports.len(), 31, "out ports only");

    let service = |name: &str| {
        let s = m
            .services
            .iter()
            .find(|s| s.name == name)
            .unwrap_or_else(|| panic!("service {name}"));
        (s.args.clone(), s.output.clone())
    };
    // one argument: its type
    assert_eq!(service("One"), (Some(DataType::Float), None));
    // several: a record; `inout` is an argument and an output
    assert_eq!(
        service("Several"),
        (
            Some(record(
                "Several_input",
                &[
                    ("n", int(-2_147_483_648, 2_147_483_647)),
                    ("at", point.clone()),
                    ("gain", DataType::Float),
                ],
            )),
            Some(record(
                "Several_output",
                &[("done", DataType::Bool), ("gain", DataType::Float)],
            )),
        )
    );
    // a field without a model type, an anonymous array: named after the service
    assert_eq!(
        service("Opaque"),
        (
            Some(rust("types::Opaque_input")),
            Some(rust("types::Opaque_output"))
        )
    );
    assert_eq!(service("Nothing"), (None, None));
    // a function's codel reads its arguments and gives its output; an attribute without
    // a codel has none
    assert_eq!(service("F"), (Some(DataType::Float), Some(DataType::Float)));
    assert_eq!(service("A"), (None, None));
}

#[test]
fn bip_import_prints_the_types_as_the_model_writes_them() {
    let dir = TempDir::new();
    let path = dir.write("types.gen", TYPES);
    let text = import_gen_file(&path, &[])
        .unwrap_or_else(|e| panic!("{}", e.summary()))
        .to_ron_nested(6)
        .expect("prints");
    for line in [
        "ty: Int(-32768, 32767)",
        "ty: Rust(\"geo::points\")",
        "ty: Rust(\"Vec<f64>\")",
        "fields: [(name: \"x\", ty: Float), (name: \"y\", ty: Float)]",
        "args: Float",
    ] {
        assert!(text.contains(line), "`{line}` in\n{text}");
    }
    assert!(
        !text.contains("FieldDef"),
        "fields print as model.md writes them"
    );
}

#[test]
fn the_gen_rover_has_the_types_of_its_ron_twin() {
    let robots = Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots");
    let load = |name: &str| {
        load_file(robots.join(name))
            .unwrap_or_else(|e| panic!("{}", e.summary()))
            .genom
            .expect("a GenoM layer")
    };
    let (from_gen, written) = (load("genom3-rover.ron"), load("genom3-rover-written.ron"));
    let types = |g: &GenomMap| {
        let mut out = Vec::new();
        for m in &g.modules {
            for p in &m.ports {
                out.push((format!("{}.{}", m.name, p.name), p.ty.clone(), None));
            }
            for s in &m.services {
                out.push((
                    format!("{}.{}", m.name, s.name),
                    s.args.clone(),
                    s.output.clone(),
                ));
            }
        }
        out
    };
    let from_gen = types(&from_gen);
    assert!(
        from_gen.iter().any(|(_, a, _)| a.is_some()),
        "the rover's types are carried over: {from_gen:?}"
    );
    assert_eq!(from_gen, types(&written));
}

#[test]
fn a_structure_that_would_grow_without_bound_is_named() {
    // each structure holds the one before twice: 2^40 fields in all, as a record
    let mut text = String::from("struct s0 { double x; };\n");
    for k in 1..=40 {
        text.push_str(&format!("struct s{k} {{ s{} a, b; }};\n", k - 1));
    }
    text.push_str(
        "component c { port out s40 big; port out s3 small; task t { period 10 ms; }; };\n",
    );
    let dir = TempDir::new();
    let path = dir.write("c.gen", &text);
    let def = import_gen_file(&path, &[]).unwrap_or_else(|e| panic!("{}", e.summary()));
    let text = def.to_ron_nested(6).expect("prints");
    let genom = load_str("imported.ron", &text)
        .unwrap_or_else(|e| panic!("{}", e.summary()))
        .genom
        .expect("a GenoM layer");
    let ports = &genom.modules[0].ports;
    assert_eq!(ports[0].ty, Some(rust("s40")));
    assert!(
        matches!(&ports[1].ty, Some(DataType::Record { name, .. }) if name == "s3"),
        "{:?}",
        ports[1].ty
    );
}
