//! GenoM3 `.gen` files in a model: task periods in model ticks, `Gen(...)` entries among
//! RON modules, the repository's examples against their RON equivalent, a large
//! component, and the interfaces a component provides. Reading them is `gen3`.

use std::path::{Path, PathBuf};

use crate::gen3::TempDir;
use bip_lang::gen3::ast::PortDir;
use bip_lang::source_map::SourceMap;
use bip_lang::{expand_str, import_gen_file, load_file, load_str};

/// Loading `text`, written as `name` in `dir`, fails with one error that says `want`.
fn assert_load_fails(dir: &TempDir, name: &str, text: &str, want: &str) {
    let model = dir.write(name, text);
    let e = load_file(&model).expect_err("an error");
    assert_eq!(e.errors().len(), 1, "{}", e.summary());
    assert!(e.summary().contains(want), "{}", e.summary());
}

#[test]
fn the_period_of_a_gen_task_is_a_whole_number_of_model_ticks() {
    let dir = TempDir::new();
    dir.write("a.gen", "component a { task t { period 25 ms; }; };\n");
    for (name, text, want) in [
        (
            "m.ron",
            r#"System(name: "m", tick_ms: 10, modules: [Gen("a.gen")])"#,
            "a.gen:1:31: the period of task `t` (25000 µs) is not a whole number of ticks of 10000 µs",
        ),
        (
            "n.ron",
            r#"System(name: "m", modules: [Gen("a.gen")])"#,
            "n.ron:1:34: a model with `.gen` modules needs `tick_ms`",
        ),
        (
            "huge.ron",
            r#"System(name: "m", tick_ms: 9223372036854775807, modules: [Gen("a.gen")])"#,
            "huge.ron:1:28: with `.gen` modules, `tick_ms` must be a positive number",
        ),
        (
            "o.ron",
            r#"System(name: "m", tick_ms: 5, modules: [Gen("missing.gen")])"#,
            "o.ron:1:46: cannot read",
        ),
    ] {
        assert_load_fails(&dir, name, text, want);
    }
}

#[test]
fn gen_entries_take_their_places_among_ron_modules() {
    let dir = TempDir::new();
    dir.write("idl/t.idl", "#define P 20\n");
    dir.write("a.gen", "component a { task t { period 10 ms; }; };\n");
    dir.write(
        "b.gen",
        "#include <t.idl>\ncomponent b { task t { period P ms; }; };\n",
    );
    let model = dir.write(
        "m.ron",
        r#"System(name: "m", tick_ms: 10, modules: [
            Gen("a.gen"),
            (name: "r", tasks: [(name: "t", period: 3)]),
            Gen(file: "b.gen", include: ["idl/"]),
        ])"#,
    );
    let text = std::fs::read_to_string(&model).expect("reads");
    let def = bip_lang::parse_str(&model.display().to_string(), &text)
        .unwrap_or_else(|e| panic!("{}", e.summary()));
    let names: Vec<(&str, String)> = def
        .modules
        .iter()
        .map(|m| {
            (
                m.name.value.as_str(),
                m.tasks[0]
                    .period
                    .as_ref()
                    .expect("a period")
                    .value
                    .to_string(),
            )
        })
        .collect();
    assert_eq!(
        names,
        [("a", "1".into()), ("r", "3".into()), ("b", "2".into())]
    );
    load_file(&model).unwrap_or_else(|e| panic!("{}", e.summary()));
    // an entry of that shape with another name is an error at the name
    assert_load_fails(
        &dir,
        "p.ron",
        r#"System(name: "m", tick_ms: 10, modules: [Gem("a.gen"), Gen ( file : "a.gen")])"#,
        "p.ron:1:42: a module from a GenoM3 file is written `Gen(\"file.gen\")`",
    );
    // an unknown field of a Gen entry is an error in the model file
    let model = dir.write(
        "n.ron",
        r#"System(name: "m", tick_ms: 10, modules: [Gen(file: "a.gen", includes: [])])"#,
    );
    assert!(load_file(&model).is_err());
}

fn robots() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots")
}

#[test]
fn the_examples_import_to_their_ron_equivalent() {
    let robots = robots();
    let from_gen = std::fs::read_to_string(robots.join("genom3-rover.ron")).expect("reads");
    let written = std::fs::read_to_string(robots.join("genom3-rover-written.ron")).expect("reads");
    let name = robots.join("genom3-rover.ron").display().to_string();
    let a = expand_str(&name, &from_gen).unwrap_or_else(|e| panic!("{}", e.summary()));
    let b = expand_str("genom3-rover-written.ron", &written)
        .unwrap_or_else(|e| panic!("{}", e.summary()));
    // the same core, transition for transition
    assert_eq!(a.to_ron().expect("prints"), b.to_ron().expect("prints"));
    // each file on its own imports, and what `bip import` prints loads
    for f in ["loco", "loc", "nav"] {
        let path = robots.join("genom3").join(format!("{f}.gen"));
        let def = import_gen_file(&path, &[robots.join("genom3/idl")])
            .unwrap_or_else(|e| panic!("{}", e.summary()));
        let text = def.to_ron_nested(6).expect("prints");
        load_str("imported.ron", &text).unwrap_or_else(|e| panic!("{f}: {}", e.summary()));
    }
}

#[test]
fn a_two_thousand_line_component_imports() {
    let path = robots().join("bench/genom3-component.gen");
    let text = std::fs::read_to_string(&path).expect("reads");
    assert!(text.lines().count() >= 2_000);
    let s = bip_lang::gen3::read(
        &path,
        "big.gen",
        &[],
        &mut SourceMap::default(),
        0,
        Default::default(),
    )
    .unwrap_or_else(|e| panic!("{}", e.message));
    assert_eq!(s.components[0].services.len(), 222);
    let modules = bip_lang::gen3::modules(&s, 10_000).unwrap_or_else(|e| panic!("{e:?}"));
    assert_eq!(modules[0].services.len(), s.components[0].services.len());
}

#[test]
fn a_component_takes_in_the_interfaces_it_provides() {
    let dir = TempDir::new();
    dir.write(
        "idl/pose_estimator.gen",
        r#"
interface pose_estimator {
  exception e_lost;
  ids { double quality; };
  port multiple out double frame;
  function Reset() { throw e_lost; };
  attribute GetQuality(out quality);
};
interface clock { port out long ticks; function Now(out long t); };
"#,
    );
    let path = dir.write(
        "loc.gen",
        r#"
#include <pose_estimator.gen>
component loc {
  uses clock;
  port out double speed;
  provides pose_estimator;
  task t { period 10 ms; };
  activity Track() { task t; codel<start> track(port out frame) yield pause::start, ether; throw e_lost; };
};
"#,
    );
    let mut files = SourceMap::default();
    let s = bip_lang::gen3::read(
        &path,
        "loc.gen",
        &[dir.0.join("idl")],
        &mut files,
        0,
        Default::default(),
    )
    .unwrap_or_else(|e| panic!("parses: {}", e.message));
    assert_eq!(s.interfaces.len(), 2);
    let c = &s.components[0];
    let names =
        |v: &[bip_lang::source::Text]| v.iter().map(|t| t.value.clone()).collect::<Vec<_>>();
    assert_eq!(names(&c.provides), ["pose_estimator"]);
    assert_eq!(names(&c.uses), ["clock"]);
    assert_eq!(names(&c.remotes), ["Now"], "a used service is a remote one");
    // the objects of an interface are in the component where `provides` or `uses` is
    // written; a used interface's out port is an in port of the component
    let ports: Vec<(&str, PortDir)> = c.ports.iter().map(|p| (p.name.as_str(), p.dir)).collect();
    assert_eq!(
        ports,
        [
            ("ticks", PortDir::In),
            ("speed", PortDir::Out),
            ("frame", PortDir::Out)
        ],
    );
    assert_eq!(c.ids[0].name.value, "quality");
    let m = &bip_lang::gen3::modules(&s, 10_000).unwrap_or_else(|e| panic!("{e:?}"))[0];
    let services: Vec<&str> = m.services.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(services, ["Reset", "GetQuality", "Track"]);
    let ports: Vec<&str> = m.ports.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(ports, ["speed", "frame"]);
    // the codel writes the provided port; the provided exception is declared
    assert_eq!(m.services[2].codels[0].writes[0].value, "frame");
    assert_eq!(m.services[2].codels[0].throws[0].value, "e_lost");
    // and the module loads
    let def =
        import_gen_file(&path, &[dir.0.join("idl")]).unwrap_or_else(|e| panic!("{}", e.summary()));
    load_str("imported.ron", &def.to_ron().expect("prints"))
        .unwrap_or_else(|e| panic!("{}", e.summary()));
}

/// A task's own codels (its state machine) become the task's `codels`, with the ports they
/// write and the task's `throw`; the machine then runs without any request.
#[test]
fn a_gen_task_machine_becomes_the_tasks_codels() {
    let dir = TempDir::new();
    dir.write(
        "flight.gen",
        r#"component flight {
  exception e_sensor;
  port out double rotors;
  task main {
    period 2 ms;
    codel<start> fl_start() yield pause::init;
    codel<init> fl_init() yield pause::init, control;
    codel<control> fl_control(port out rotors) yield pause::control, emergency;
    codel<emergency> fl_emergency() yield pause::emergency, pause::control;
    codel<stop> fl_stop() yield ether;
    throw e_sensor;
  };
};
"#,
    );
    let model = dir.write(
        "m.ron",
        r#"System(name: "m", tick_ms: 1, modules: [Gen("flight.gen")],
        properties: [Reachable(name: "controls", expr: "flight.main@control")])"#,
    );
    let sys = load_file(&model).unwrap_or_else(|e| panic!("{}", e.summary()));
    let map = sys.genom.as_ref().expect("a map");
    let main = map.service("flight", "main").expect("the machine");
    assert_eq!(main.request, None);
    let states: Vec<&str> = main.codels.iter().map(|c| c.state.as_str()).collect();
    assert_eq!(states, ["start", "init", "control", "emergency", "stop"]);
    let control = map.codel("flight", "main", "control").expect("control");
    assert_eq!(control.writes, ["rotors"]);
    assert_eq!(control.throws, ["e_sensor"]);
    let def = import_gen_file(&dir.0.join("flight.gen"), &[])
        .unwrap_or_else(|e| panic!("{}", e.summary()));
    let task = &def.modules[0].tasks[0];
    let states: Vec<&str> = task.codels.iter().map(|c| c.state.as_str()).collect();
    assert_eq!(states, ["start", "init", "control", "emergency", "stop"]);
    // the printed model loads, with the machine on its task
    let printed = def.to_ron().expect("prints");
    assert!(printed.contains("codels"), "{printed}");
    let again = load_str("imported.ron", &printed).unwrap_or_else(|e| panic!("{}", e.summary()));
    assert!(again
        .genom
        .as_ref()
        .and_then(|g| g.service("flight", "main"))
        .is_some());
}

/// A codel's `uses` are the ids members and ports among its parameters, whatever their
/// direction, each once by its first name; a service's parameters and locals are not
/// (docs/genom.md, "GenoM3 files"). `::ids`, the whole ids, is every member.
#[test]
fn a_gen_codel_uses_its_ids_members_and_ports() {
    let dir = TempDir::new();
    dir.write(
        "lock.gen",
        r#"component lock {
  ids { double odo; long state; };
  port out double pose;
  port in double laser;
  task main { period 10 ms; };
  activity Go(in double goal) {
    task main;
    codel<start> g_start(in odo, ids in state, in goal) yield step;
    codel<step> g_step(in laser, port out pose, inout odo) yield pause::step, ether;
    codel<stop> g_stop(ids inout ::ids) yield ether;
  };
};
"#,
    );
    let def =
        import_gen_file(&dir.0.join("lock.gen"), &[]).unwrap_or_else(|e| panic!("{}", e.summary()));
    let go = &def.modules[0].services[0];
    let uses = |i: usize| -> Vec<&str> { go.codels[i].uses.iter().map(|u| u.as_str()).collect() };
    assert_eq!(uses(0), ["odo", "state"]);
    assert_eq!(uses(1), ["laser", "pose", "odo"]);
    assert_eq!(uses(2), ["odo", "state"]);
    assert_eq!(go.codels[1].writes[0].value, "pose");
}
