//! GenoM3 `.gen` files read: every construct the parser reads (and what it becomes), each
//! preprocessor feature, a malformed input per construct with its message and position.
//! How they take their place in a model is `gen3_layer`.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::robustness::render;
use bip_lang::gen3::ast::{Dir, Kind, PortDir, Spec};
use bip_lang::source_map::SourceMap;
use bip_lang::syntax::{ServiceKind, SystemDef};
use bip_lang::{import_gen_file, load_str, LoadError};

/// A fresh directory, removed at the end of the test.
pub(crate) struct TempDir(pub(crate) PathBuf);

impl TempDir {
    pub(crate) fn new() -> TempDir {
        static N: AtomicUsize = AtomicUsize::new(0);
        let dir = std::env::temp_dir().join(format!(
            "bip-gen3-{}-{}",
            std::process::id(),
            N.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(dir.join("idl")).expect("a temporary directory");
        TempDir(dir)
    }

    pub(crate) fn write(&self, name: &str, text: &str) -> PathBuf {
        let path = self.0.join(name);
        std::fs::write(&path, text).expect("writes");
        path
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// `text` as `c.gen`, imported with `idl/` on the search path.
fn import(text: &str) -> Result<SystemDef, LoadError> {
    let dir = TempDir::new();
    let path = dir.write("c.gen", text);
    import_gen_file(&path, &[dir.0.join("idl")])
}

fn imported(text: &str) -> SystemDef {
    import(text).unwrap_or_else(|e| panic!("imports: {}", e.summary()))
}

/// `text` as `c.gen`, parsed.
fn spec(text: &str) -> Spec {
    let dir = TempDir::new();
    let path = dir.write("c.gen", text);
    bip_lang::gen3::read(
        &path,
        "c.gen",
        &[],
        &mut SourceMap::default(),
        0,
        Default::default(),
    )
    .unwrap_or_else(|e| panic!("parses: {}", e.message))
}

/// The one error of importing `text`: its message and its line and column in `c.gen`,
/// after checking that it renders with a caret in that file.
fn error(text: &str) -> (String, usize, usize) {
    let e = import(text).expect_err("an error");
    let summary = e.summary();
    let first = summary.lines().next().unwrap_or_default().to_string();
    let rendered = render(&e);
    let (place, message) = first.split_once(": ").expect("file:line:col: message");
    let mut parts = place.rsplitn(3, ':');
    let col: usize = parts.next().and_then(|c| c.parse().ok()).expect("a column");
    let line: usize = parts.next().and_then(|l| l.parse().ok()).expect("a line");
    let file = parts.next().expect("a file");
    assert!(
        file.ends_with("c.gen"),
        "the error is in the .gen file: {first}"
    );
    assert!(
        rendered.contains(&format!("c.gen:{line}:{col}]")),
        "the caret is in the .gen file:\n{rendered}"
    );
    (message.to_string(), line, col)
}

fn expect_error(text: &str, message: &str, line: usize, col: usize) {
    let (m, l, c) = error(text);
    assert!(m.contains(message), "`{m}` says `{message}`");
    assert_eq!((l, c), (line, col), "position of `{m}`");
}

const FULL: &str = r#"
#pragma require "openrobots2-idl >= 2.0"
/* a block comment */ // and a line comment
component full {
  version "1.2"; email "me@example.org"; lang "c";
  require "genom3 >= 2.99.26", "other";
  codels-require "eigen3";
  doc "The whole " "language.";

  exception e_one, e_two;
  exception e_sys { short code; string<128> what; };
  native handle_s;
  const unsigned long period_ms = 50;

  ids {
    double speed[3];
    sequence<long, 8> history;
    struct inner_s { boolean on; octet raw; } inner;
    handle_s handle;
  };

  port out double odom { doc "odometry"; };
  port in string<32> command;
  port multiple out unsigned long long samples;

  task main {
    period period_ms ms;
    priority 20;
    stack 64k;
    scheduling real-time;
    codel<start> main_start(out ::ids) yield ether;
    throw e_sys;
  };
  task slow { period 0.5 s; };
  task events { codel<start> events_start() yield ether; };

  attribute SetSpeed(in speed = { [0] = 1, [1] = 2.5 : "y", [2] = : "z" }) {
    doc "Set the speed.";
    validate check_speed(local in speed);
    throw e_one;
  };
  function Reset(in double value = 0 : "the value", out long count) {
    codel reset(in value, out count);
    interrupt Run;
  };
  activity Run(in double target) {
    task main;
    after Reset;
    interrupts Run, Other;
    local long counter, ticks;
    async codel<start> run_start(in target, out counter) yield step;
    codel<step, again> run_step(inout counter, out odom, port out samples)
      yield pause::again, ether;
    codel<stop> run_stop(ids in speed) yield ether;
    throw e_one, e_two;
  };
  activity Other() {
    task slow;
    codel<start> other_start(out speed) yield ether;
  };
};
"#;

#[test]
fn a_component_with_every_construct_reads_with_its_information() {
    let s = spec(FULL);
    let c = &s.components[0];
    assert_eq!(c.name.value, "full");
    assert_eq!(c.version.as_ref().map(|v| v.value.as_str()), Some("1.2"));
    assert_eq!(c.lang.as_ref().map(|v| v.value.as_str()), Some("c"));
    assert_eq!(c.require.len(), 2);
    assert_eq!(c.codels_require[0].value, "eigen3");
    assert_eq!(c.doc[0].value, "The whole language.");
    let ids: Vec<(&str, &str)> = c
        .ids
        .iter()
        .map(|m| (m.name.value.as_str(), m.ty.as_str()))
        .collect();
    assert_eq!(
        ids,
        [
            ("speed", "double[3]"),
            ("history", "sequence<long, 8>"),
            ("inner", "struct inner_s"),
            ("handle", "handle_s")
        ]
    );
    let ports: Vec<(&str, PortDir, bool, &str)> = c
        .ports
        .iter()
        .map(|p| (p.name.value.as_str(), p.dir, p.multiple, p.ty.as_str()))
        .collect();
    assert_eq!(
        ports,
        [
            ("odom", PortDir::Out, false, "double"),
            ("command", PortDir::In, false, "string<32>"),
            ("samples", PortDir::Out, true, "unsigned long long"),
        ]
    );
    let main = &c.tasks[0];
    assert_eq!(main.period.map(|p| p.0), Some(50_000));
    assert_eq!(main.priority.map(|p| p.0), Some(20));
    assert_eq!(main.stack.map(|p| p.0), Some(64 * 1024));
    assert!(main.real_time);
    assert_eq!(main.codels[0].states[0].value, "start");
    assert_eq!(main.throws[0].value, "e_sys");
    assert_eq!(c.tasks[1].period.map(|p| p.0), Some(500_000));
    let kinds: Vec<Kind> = c.services.iter().map(|s| s.kind).collect();
    assert_eq!(
        kinds,
        [
            Kind::Attribute,
            Kind::Function,
            Kind::Activity,
            Kind::Activity
        ]
    );
    let attr = &c.services[0];
    assert_eq!(attr.params[0].name.value, "speed");
    assert!(attr.params[0].ty.is_none() && attr.params[0].init.is_some());
    assert!(attr.validate.is_some());
    let reset = &c.services[1];
    let params: Vec<(Dir, &str, Option<&str>)> = reset
        .params
        .iter()
        .map(|p| (p.dir, p.name.value.as_str(), p.ty.as_deref()))
        .collect();
    assert_eq!(
        params,
        [
            (Dir::In, "value", Some("double")),
            (Dir::Out, "count", Some("long"))
        ]
    );
    assert_eq!(reset.simple[0].function.value, "reset");
    let run = &c.services[2];
    assert_eq!(run.locals.len(), 2);
    assert!(run.codels[0].asynchronous);
    let states: Vec<&str> = run.codels[1]
        .states
        .iter()
        .map(|s| s.value.as_str())
        .collect();
    assert_eq!(states, ["step", "again"]);
    let yields: Vec<&str> = run.codels[1]
        .yields
        .iter()
        .map(|s| s.value.as_str())
        .collect();
    assert_eq!(yields, ["pause::again", "ether"]);
    assert_eq!(c.exceptions.len(), 3);
    assert!(c
        .types
        .iter()
        .any(|t| t.kind == "native" && t.name.value == "full::handle_s"
            || t.name.value == "handle_s"));
}

/// A codel's state, yields, throws and writes.
type CodelRow<'a> = (&'a str, Vec<&'a str>, Vec<&'a str>, Vec<&'a str>);

#[test]
fn a_component_becomes_a_module_of_the_genom_layer() {
    let def = imported(FULL);
    // the tick is the greatest common divisor of the periods
    assert_eq!(
        def.tick_ms.as_ref().map(|t| t.value.to_string()),
        Some("50".into())
    );
    let m = &def.modules[0];
    assert_eq!(m.name.value, "full");
    assert!(m.ids.is_empty(), "data are abstracted");
    let tasks: Vec<(&str, Option<String>)> = m
        .tasks
        .iter()
        .map(|t| {
            let period = t.period.as_ref().map(|p| p.value.to_string());
            (t.name.value.as_str(), period)
        })
        .collect();
    // `events` has no period: an aperiodic task, with its machine
    assert_eq!(
        tasks,
        [
            ("main", Some("1".to_string())),
            ("slow", Some("10".to_string())),
            ("events", None)
        ]
    );
    assert_eq!(m.tasks[2].codels.len(), 1);
    let ports: Vec<&str> = m.ports.iter().map(|p| p.name.value.as_str()).collect();
    assert_eq!(ports, ["odom", "samples"], "out ports only");
    let kinds: Vec<ServiceKind> = m.services.iter().map(|s| s.kind).collect();
    assert_eq!(
        kinds,
        [
            ServiceKind::Attribute,
            ServiceKind::Function,
            ServiceKind::Activity,
            ServiceKind::Activity
        ]
    );
    let reset = &m.services[1];
    assert_eq!(reset.interrupts[0].value, "Run");
    // a function's codel runs at its request: `start`, yielding `ether`
    let [codel] = reset.codels.as_slice() else {
        panic!("{:?}", reset.codels)
    };
    assert_eq!((codel.state.as_str(), codel.yields.len()), ("start", 1));
    assert_eq!(codel.yields[0].as_str(), "ether");
    let run = &m.services[2];
    assert_eq!(run.task.as_ref().map(|t| t.value.as_str()), Some("main"));
    assert_eq!(run.after[0].value, "Reset");
    let codels: Vec<CodelRow> = run
        .codels
        .iter()
        .map(|c| {
            (
                c.state.value.as_str(),
                c.yields.iter().map(|y| y.value.as_str()).collect(),
                c.throws.iter().map(|y| y.value.as_str()).collect(),
                c.writes.iter().map(|y| y.value.as_str()).collect(),
            )
        })
        .collect();
    assert_eq!(
        codels,
        [
            ("start", vec!["step"], vec!["e_one", "e_two"], vec![]),
            (
                "step",
                vec!["pause::again", "ether"],
                vec!["e_one", "e_two"],
                vec!["odom", "samples"]
            ),
            (
                "again",
                vec!["pause::again", "ether"],
                vec!["e_one", "e_two"],
                vec!["odom", "samples"]
            ),
            ("stop", vec!["ether"], vec!["e_one", "e_two"], vec![]),
        ]
    );
    // `out speed` names the ids member, not a port
    assert!(m.services[3].codels[0].writes.is_empty());
    // and the model prints and reads back
    let text = def.to_ron().expect("prints");
    load_str("imported.ron", &text).unwrap_or_else(|e| panic!("{}", e.summary()));
}

#[test]
fn idl_declarations_and_constants_read() {
    let s = spec(
        r#"
#define SIZE (2 + 2)
typedef double sized[SIZE];
typedef sequence<string<SIZE>, SIZE> names;
module geo {
  const long scale = 2 * (3 + 1) - 10 / 5 % 3 << 1 | 1 ^ 0 & 7;
  enum mode { idle, busy, done };
  struct point { double x, y; };
  typedef sequence<point, 4> polygon;
  typedef sequence<sequence<long>> grid;
  typedef double matrix[3][3];
  union value switch (mode) { case idle: long a; case busy: case done: double b; default: octet c; };
  module inner { const unsigned short ms = geo::scale + done; };
};
component c {
  task t { period geo::inner::ms ms; };
};
"#,
    );
    let period = s.components[0].tasks[0].period.map(|p| p.0);
    // scale = ((8 - 2 % 3) << 1) | (1 ^ (0 & 7)) = (6 << 1) | 1 = 13; ms = 13 + 2
    assert_eq!(period, Some(15_000));
    let kinds: Vec<(&str, &str)> = s
        .types
        .iter()
        .map(|t| (t.name.value.as_str(), t.kind))
        .collect();
    for want in [
        ("geo::scale", "const"),
        ("geo::mode", "enum"),
        ("geo::point", "struct"),
        ("geo::polygon", "typedef"),
        ("geo::grid", "typedef"),
        ("geo::matrix", "typedef"),
        ("geo::value", "union"),
        ("geo::inner::ms", "const"),
    ] {
        assert!(kinds.contains(&want), "{want:?} in {kinds:?}");
    }
    let ty = |name: &str| {
        let t = s
            .types
            .iter()
            .find(|t| t.name.value == name)
            .expect("declared");
        t.members[0].ty.clone()
    };
    assert_eq!(ty("geo::grid"), "sequence<sequence<long>>");
    assert_eq!(ty("geo::matrix"), "double[3][3]");
    // sizes from a `#define`
    assert_eq!(ty("sized"), "double[4]");
    assert_eq!(ty("names"), "sequence<string<4>, 4>");
}

#[test]
fn each_preprocessor_feature_reads() {
    let dir = TempDir::new();
    dir.write(
        "idl/types.idl",
        "#ifndef TYPES\n#define TYPES\n#define BASE 20\nstruct pose { double x; };\n#endif\n",
    );
    dir.write(
        "local.gen",
        "#include <types.idl>\n#define LOCAL_MS (BASE * 2)\n",
    );
    let path = dir.write(
        "c.gen",
        r#"
#include "local.gen"
#include "local.gen"
#define FAST
#undef FAST
#if defined(FAST)
#error "not this one"
#elif BASE > 10 && !defined FAST
#define CHOSEN_MS LOCAL_MS
#else
#define CHOSEN_MS 1
#endif
#ifdef TYPES
#ifndef MISSING
component c {
  port out pose where;
  task t { period CHOSEN_MS ms; };
  task u { period \
    BASE ms; };
};
#endif
#endif
"#,
    );
    let def =
        import_gen_file(&path, &[dir.0.join("idl")]).unwrap_or_else(|e| panic!("{}", e.summary()));
    let m = &def.modules[0];
    assert_eq!(
        def.tick_ms.as_ref().map(|t| t.value.to_string()),
        Some("20".into())
    );
    assert_eq!(
        m.tasks[0]
            .period
            .as_ref()
            .expect("a period")
            .value
            .to_string(),
        "2"
    );
    assert_eq!(
        m.tasks[1]
            .period
            .as_ref()
            .expect("a period")
            .value
            .to_string(),
        "1"
    );
    assert_eq!(m.ports[0].name.value, "where");
}

#[test]
fn function_like_macros_expand_with_their_arguments() {
    let def = imported(
        r#"
#define MS(x) ((x) * 1000)
#define PERIOD(base, k) MS(base) / 1000 * k
#define ONE() 1
#define TWICE(f, x) f(f(x))
#define INC(x) (x + 1)
component c {
  task t { period PERIOD(10,
      2) ms; };
  task u { period TWICE(INC, 8) ms; };
  task v { period ONE() * (30) ms; };
  port out double MS;
};
"#,
    );
    let m = &def.modules[0];
    assert_eq!(
        def.tick_ms.as_ref().map(|t| t.value.to_string()),
        Some("10".into())
    );
    let periods: Vec<String> = m
        .tasks
        .iter()
        .map(|t| t.period.as_ref().expect("a period").value.to_string())
        .collect();
    assert_eq!(periods, ["2", "1", "3"]);
    // a function-like macro's name without arguments is not a call
    assert_eq!(m.ports[0].name.value, "MS");
}

#[test]
fn malformed_preprocessor_input_is_an_error_at_its_place() {
    expect_error(
        "#include \"nowhere.gen\"\n",
        "cannot find the included file `nowhere.gen`",
        1,
        10,
    );
    expect_error(
        "#include <nowhere.idl>\n",
        "cannot find the included file `nowhere.idl`",
        1,
        10,
    );
    expect_error("#include\n", "`#include` needs a file", 1, 1);
    expect_error("#define F(x, x) x\n", "parameter `x` is repeated", 1, 14);
    // each call doubles its argument: 2^40 tokens
    let doubling = format!(
        "#define D(x) x x\nconst long k = {}1{};\n",
        "D(".repeat(40),
        ")".repeat(40)
    );
    expect_error(&doubling, "the file expands to too many tokens", 2, 96);
    expect_error(
        "#define F(...) x\n",
        "variadic macros are not supported",
        1,
        11,
    );
    expect_error(
        "#define S(x) #x\n",
        "the `#` and `##` operators are not supported",
        1,
        14,
    );
    expect_error(
        "#define F(x, y) x\ncomponent c { task t { period F(1) ms; }; };\n",
        "macro `F` takes 2 arguments, given 1",
        2,
        31,
    );
    expect_error(
        "#define F(x) x\ncomponent c { task t { period F(1 ms; }; };\n#define G\n",
        "the call of macro `F` has no closing `)`",
        2,
        31,
    );
    expect_error("#if 1\ncomponent c;\n", "this `#if` has no `#endif`", 1, 1);
    expect_error("#endif\n", "`#endif` without `#if`", 1, 1);
    expect_error(
        "#if 1\n#else\n#else\n#endif\n",
        "`#else` after `#else`",
        3,
        1,
    );
    expect_error(
        "#if 1 +\n#endif\n",
        "expected a constant, found the end of the file",
        1,
        8,
    );
    expect_error("#error \"stop here\"\n", "#error \"stop here\"", 1, 1);
    expect_error(
        "#line 4\n",
        "the preprocessor directive `#line` is not supported",
        1,
        1,
    );
    expect_error("#ifdef\n#endif\n", "`#ifdef` needs a name", 1, 1);
    // an include cycle without guards
    let dir = TempDir::new();
    let path = dir.write("c.gen", "#include \"c.gen\"\n");
    let e = import_gen_file(&path, &[]).expect_err("an error");
    assert!(
        e.summary().contains("nested more than 32 deep"),
        "{}",
        e.summary()
    );
}

#[test]
fn malformed_input_of_each_construct_is_an_error_at_its_place() {
    let cases: &[(&str, &str, usize, usize)] = &[
        // lexer
        ("component c { doc \"open", "unterminated string", 1, 19),
        ("/* open", "unterminated comment", 1, 1),
        ("component c { $ };", "unexpected character '$'", 1, 15),
        // component
        ("component { };", "expected the component's name, found `{`", 1, 11),
        ("component c { version 1; };", "expected a string, found `1`", 1, 23),
        ("component c { colour \"red\"; };", "expected a component property or declaration, found `colour`", 1, 15),
        ("component c { doc \"x\" }", "expected `;`, found `}`", 1, 23),
        ("component c {", "expected `}` closing the component, found the end of the file", 1, 14),
        // ids and IDL types
        ("component c { ids { double; }; };", "expected a name, found `;`", 1, 27),
        ("component c { ids { unsigned double x; }; };", "`unsigned double` is not an IDL type", 1, 21),
        ("component c { ids { sequence<long x; }; };", "expected `>`, found `x`", 1, 35),
        ("component c { ids { fixed<4, 2> x; }; };", "IDL `fixed` types are not supported", 1, 21),
        ("component c { ids { double x[-1]; }; };", "expected a positive integer constant", 1, 30),
        ("struct s { double x; }", "expected `;`, found the end of the file", 1, 23),
        ("enum e { };", "expected an enumerator, found `}`", 1, 10),
        ("const long k = unknown;", "unknown constant `unknown`", 1, 16),
        ("const long k = 1 / 0;", "division by zero", 1, 18),
        ("const long k = -(-170141183460469231731687303715884105727 - 1);", "`-` overflows here", 1, 16),
        // task
        ("component c { task t { period; }; };", "expected a constant, found `;`", 1, 30),
        ("component c { task t { period -5 ms; }; };", "a duration is positive", 1, 31),
        ("component c { task t { speed 3; }; };", "expected a task property", 1, 24),
        ("component c { task t { scheduling fast; }; };", "expected `real-time`, found `fast`", 1, 35),
        ("component c { task t { period 10 ms; delay 10 ms; }; };", "the delay of task `t` is not less than its period", 1, 44),
        // port
        ("component c { port sideways double p; };", "expected `in` or `out`, found `sideways`", 1, 20),
        ("component c { port out double; };", "expected the port's name, found `;`", 1, 30),
        ("component c { port out double p { period 1; }; };", "expected `doc` or `}`", 1, 35),
        // services
        ("component c { function f; };", "expected `(`, found `;`", 1, 25),
        ("component c { function f(double x); };", "expected `in`, `out` or `inout`, found `double`", 1, 26),
        ("component c { function f() { codel<start> g() yield ether; }; };", "a function's codel has no states", 1, 30),
        ("component c { activity a() { codel<start> g(); }; };", "expected `yield` and the codel's next states, found `;`", 1, 46),
        ("component c { activity a() { codel<start> g() yield pause:: ; }; };", "expected a state after `pause::`, found `;`", 1, 61),
        ("component c { activity a() { codel g() yield ether; }; };", "a codel that yields needs its states", 1, 40),
        ("component c { activity a() { async g() yield ether; }; };", "expected `codel`, found `g`", 1, 36),
        ("component c { activity a() { colour red; }; };", "expected a service property", 1, 30),
        ("component c { activity a() { local x; }; };", "expected a name, found `;`", 1, 37),
        ("component c { task t { period 1 s; }; activity a() { task t; throw e_none; codel<start> s() yield ether; }; };", "exception `e_none` is not declared", 1, 68),
        ("component c { function f() { before h; }; function g(); };", "module `c` has no service `h`", 1, 37),
        ("component c { attribute a(in x = {); };", "expected a constant, found `)`", 1, 35),
        // what bip's checks of a module find, in the .gen file
        ("component c { task t { period 1 s; }; activity a() { task t; codel<start> s() yield nowhere; }; };", "codel `start` yields to `nowhere`", 1, 85),
        ("component c { activity a() { task missing; codel<start> s() yield ether; }; };", "module `c` has no task `missing`", 1, 35),
        // an aperiodic task: its activity's codel states may not take the wake port's name
        ("component c { task t; activity a() { task t; codel<start> s() yield pause::wake; codel<wake> w() yield ether; }; };", "a codel state cannot be named `wake`", 1, 88),
        // interfaces
        ("interface i { task t { period 1 s; }; };", "interface `i` declares a task", 1, 20),
        ("component c { provides i; };", "interface `i` is not declared", 1, 24),
        ("interface j; component c { uses j, i; };", "interface `i` is not declared", 1, 36),
        ("interface i { function f(); }; component c { provides i; activity f(); };", "activity `f` conflicts with its first declaration, a function", 1, 67),
        // unsupported GenoM3 constructs
        ("template t { };", "`template` is not supported", 1, 1),
        ("", "declares no component", 0, 0),
    ];
    let mut wrong = Vec::new();
    for (text, message, line, col) in cases {
        if *line == 0 {
            let e = import(text).expect_err("an error");
            assert!(e.summary().contains(message), "{}", e.summary());
            continue;
        }
        let (m, l, c) = error(text);
        if !m.contains(message) || (l, c) != (*line, *col) {
            wrong.push(format!(
                "`{text}`: {l}:{c}: `{m}`, expected {line}:{col}: `{message}`"
            ));
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}
