//! The GenoM3 constructs of the importer's second round, each with what GenoM3 makes of
//! it: the other keyword spellings and keywords as names, `ids::T`, task `delay`, `wcet`,
//! `before`, `interrupts all`, activities GenoM3 accepts that bip refused (no path from
//! `start` to `ether`, a loop of plain yields), `uses` (ports reversed), `provides` with
//! its services refined, codel parameters resolved, a component without services; and
//! each one's bad input, an error at its place. `tests/gen3/constructs.gen` uses them all.

use std::path::Path;

use crate::gen3::TempDir;
use bip_lang::gen3::ast::PortDir;
use bip_lang::source::ConstValue;
use bip_lang::syntax::{DataTypeDef, ModuleDef, SystemDef};
use bip_lang::{import_gen_file, load_str, LoadError};

fn import(text: &str) -> Result<SystemDef, LoadError> {
    let dir = TempDir::new();
    let path = dir.write("c.gen", text);
    import_gen_file(&path, &[])
}

fn module(text: &str) -> ModuleDef {
    let def = import(text).unwrap_or_else(|e| panic!("imports: {}", e.summary()));
    // and what it prints loads
    load_str("imported.ron", &def.to_ron().expect("prints"))
        .unwrap_or_else(|e| panic!("reloads: {}", e.summary()));
    def.modules.into_iter().next().expect("a module")
}

/// The first error's message, line and column in `c.gen`.
fn error(text: &str) -> (String, usize, usize) {
    let e = import(text).expect_err("an error");
    let first = e.summary().lines().next().unwrap_or_default().to_string();
    let (place, message) = first.split_once(": ").expect("file:line:col: message");
    let mut parts = place.rsplitn(3, ':');
    let col = parts.next().and_then(|c| c.parse().ok()).expect("a column");
    let line = parts.next().and_then(|l| l.parse().ok()).expect("a line");
    assert!(
        parts.next().is_some_and(|f| f.ends_with("c.gen")),
        "{first}"
    );
    (message.to_string(), line, col)
}

fn expect_error(text: &str, message: &str, line: usize, col: usize) {
    let (m, l, c) = error(text);
    assert!(m.contains(message), "`{m}` says `{message}`");
    assert_eq!((l, c), (line, col), "position of `{m}`");
}

fn int(v: &Option<bip_lang::source::ConstExpr>) -> Option<i64> {
    match v.as_ref().map(|c| &c.value) {
        Some(ConstValue::Int(i)) => Some(*i),
        _ => None,
    }
}

/// A constant written as text (`"20us"`).
fn written(v: &Option<bip_lang::source::ConstExpr>) -> Option<String> {
    match v.as_ref().map(|c| &c.value) {
        Some(ConstValue::Expr(e)) => Some(e.clone()),
        _ => None,
    }
}

fn names(v: &[bip_lang::source::Text]) -> Vec<&str> {
    v.iter().map(|t| t.as_str()).collect()
}

#[test]
fn the_fixture_imports_with_every_construct() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/gen3/constructs.gen");
    let def = import_gen_file(&path, &[]).unwrap_or_else(|e| panic!("{}", e.summary()));
    load_str("constructs.ron", &def.to_ron().expect("prints"))
        .unwrap_or_else(|e| panic!("{}", e.summary()));
    let m = &def.modules[0];
    // 20 ms ticks: `delay 20 ms` is one tick, `delay 0 ms` none
    let delays: Vec<Option<i64>> = m.tasks.iter().map(|t| int(&t.delay)).collect();
    assert_eq!(delays, [Some(0), Some(1)]);
    // out ports: its own, the provided interface's out port, the used one's in port
    let ports: Vec<&str> = m.ports.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        ports,
        ["tuning", "tuning_copy", "odometry", "beacon_request"]
    );
    // in ports: the provided interface's in port, the used one's out port
    let in_ports: Vec<&str> = m.in_ports.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(in_ports, ["setpoint", "beacon"]);
    // `ids::gains` and `drive::ids::gains` are the ids' structure
    for p in &m.ports[..2] {
        assert!(
            matches!(&p.ty, Some(DataTypeDef::Record { name, .. }) if name.as_str() == "gains"),
            "{:?}",
            p.ty
        );
    }
    let service = |n: &str| m.services.iter().find(|s| s.name.as_str() == n).expect(n);
    // the provided `Move` refined: its interface's doc and throws, the component's task
    // and codels (with their WCETs in microseconds)
    let mv = service("Move");
    assert_eq!(mv.task.as_ref().map(|t| t.as_str()), Some("control"));
    assert_eq!(
        mv.doc.as_ref().map(|d| d.as_str()),
        Some("moves at a speed")
    );
    assert_eq!(names(&mv.codels[0].throws), ["e_stalled"]);
    let wcets: Vec<Option<String>> = mv.codels.iter().map(|c| written(&c.wcet)).collect();
    assert_eq!(wcets, [Some("2000us".into()), Some("5000us".into()), None]);
    assert_eq!(names(&service("Calibrate").before), ["Move"]);
    assert_eq!(
        names(&service("Halt").interrupts),
        ["Move", "Calibrate", "Halt"]
    );
    assert_eq!(names(&service("Stop").interrupts), ["Move"]);
}

#[test]
fn every_spelling_of_the_keywords_reads() {
    let m = module(
        r#"
interface base { port out long level; };
interface more { extend base; };
component c <%
  require "a"; requires "b"; codels-require "c"; codels-requires "d";
  provide more;
  exception e;
  task t { period 10 ms; };
  activity A() {
    task t;
    throw e;
    interrupt A;
    codel <start> f(port out level) yield pause::start, ether;
  };
  activity B() {
    task t;
    throws e;
    interrupts A;
    codel <start> g() yields ether;
  };
%>;
"#,
    );
    assert_eq!(m.ports[0].name.as_str(), "level");
    assert_eq!(names(&m.services[0].interrupts), ["A"]);
    assert_eq!(names(&m.services[1].interrupts), ["A"]);
    assert_eq!(names(&m.services[1].codels[0].throws), ["e"]);
    // the operator words are punctuation, in constant expressions too
    let m = module(
        "component c { task t { period (12 bitand 10) bitor (1 xor 3) ms; }; activity A() { task t; codel <start> f() yield ether; }; };",
    );
    // (12 & 10) | (1 ^ 3) = 8 | 2 = 10 ms, one tick of the 10 ms the import chooses
    assert!(matches!(
        m.tasks[0].period.as_ref().expect("a period").value,
        ConstValue::Int(1)
    ));
}

#[test]
fn keywords_are_names_where_genom3_allows_them() {
    let m = module(
        r#"
typedef double port;
component c {
  ids { long period; double delay; };
  port out port task;
  task control { period 10 ms; };
  activity before(in double after) {
    task control;
    codel <start> run(ids in period, local in after, port out task) yield pause::wait, ether;
    codel <wait> wait(ids out delay) yield ether;
  };
  function yield();
};
"#,
    );
    assert_eq!(m.ports[0].name.as_str(), "task");
    assert_eq!(m.services[0].name.as_str(), "before");
    assert_eq!(names(&m.services[0].codels[0].writes), ["task"]);
    assert_eq!(m.services[1].name.as_str(), "yield");
}

#[test]
fn ids_types_are_named_from_the_ids_scope() {
    let m = module(
        r#"
component c {
  ids { struct pair { long a; long b; } last; enum mode { idle, busy } m; };
  port out ids::pair p1;
  port out c::ids::pair p2;
  port out ::c::ids::mode p3;
};
"#,
    );
    assert!(
        matches!(&m.ports[0].ty, Some(DataTypeDef::Record { name, .. }) if name.as_str() == "pair")
    );
    assert!(
        matches!(&m.ports[1].ty, Some(DataTypeDef::Record { name, .. }) if name.as_str() == "pair")
    );
    assert!(
        matches!(&m.ports[2].ty, Some(DataTypeDef::Int(..))),
        "{:?}",
        m.ports[2].ty
    );
}

/// An attribute's parameter that is an ids member (`in limits.lo`) is named by its last
/// member in its codels (`local in lo`), as GenoM3 names it.
#[test]
fn an_attributes_ids_member_is_named_by_its_last_member() {
    let m = module(
        r#"
component c {
  ids { struct range { double lo, hi; } limits; };
  attribute SetLimits(in limits.lo, in limits.hi) {
    validate c_check(local in lo, local in hi, inout limits);
  };
};
"#,
    );
    assert_eq!(m.services[0].name.as_str(), "SetLimits");
    expect_error(
        "component c {\n  ids { double x; };\n  attribute Set(in x) { validate c_check(local in y); };\n};\n",
        "codel `c_check`: no parameter or local of the service is named `y`",
        3,
        51,
    );
}

#[test]
fn a_delay_is_the_first_release_offset_in_ticks() {
    let text = |delay: &str| {
        format!("component c {{ task t {{ period 40 ms; {delay} }}; task u {{ period 10 ms; }}; activity A() {{ task t; codel <start> f() yield ether; }}; }};")
    };
    for (written, ticks) in [
        ("delay 0 ms;", Some(0)),
        ("delay 30 ms;", Some(3)),
        ("", None),
    ] {
        assert_eq!(
            int(&module(&text(written)).tasks[0].delay),
            ticks,
            "{written}"
        );
    }
    let line = "component c { task t { period 40 ms; delay 40 ms; }; };";
    expect_error(
        line,
        "the delay of task `t` is not less than its period",
        1,
        44,
    );
    // `bip import` chooses a tick that divides the delays too
    let def =
        import("component c { task t { period 40 ms; delay 15 ms; }; task u { period 10 ms; }; };")
            .unwrap_or_else(|e| panic!("{}", e.summary()));
    assert!(matches!(
        def.tick_ms.as_ref().map(|t| &t.value),
        Some(ConstValue::Int(5))
    ));
    assert_eq!(int(&def.modules[0].tasks[0].delay), Some(3));
    let line = "component c { task t { delay 10 ms; }; };";
    expect_error(line, "task `t` has a delay and no period", 1, 30);
    let line = "component c { task t { period 10 ms; delay -1 ms; }; };";
    expect_error(line, "a duration is zero or more", 1, 44);
}

#[test]
fn wcet_is_the_codel_s_budget() {
    let m = module(
        r#"
component c {
  task t { period 10 ms; };
  activity A(in long x) {
    task t;
    validate check(local in x) wcet 1 ms;
    codel <start> f() yield pause::main wcet 20 us;
    codel <main> g() yield pause::main, ether wcet 2 ms;
  };
};
"#,
    );
    // written with their unit, so that a budget below 100 µs is no slip for milliseconds
    let wcets: Vec<Option<String>> = m.services[0]
        .codels
        .iter()
        .map(|c| written(&c.wcet))
        .collect();
    assert_eq!(wcets, [Some("20us".into()), Some("2000us".into())]);
    let line = "component c { task t { period 10 ms; }; activity A() { task t; codel <start> f() yield ether wcet 0 ms; }; };";
    expect_error(line, "a duration is positive", 1, 99);
    let line = "component c { task t { period 10 ms; }; activity A() { task t; codel <start> f() yield ether wcet; }; };";
    expect_error(line, "expected a constant", 1, 98);
}

#[test]
fn before_and_interrupts_all() {
    let m = module(
        r#"
component c {
  task t { period 10 ms; };
  function Init() { before Go, Calibrate; };
  activity Go() { task t; codel <start> f() yield pause::start, ether; };
  activity Calibrate() { task t; after Init; codel <start> f() yield ether; };
  activity Panic() { task t; interrupts all; codel <start> f() yield ether; };
};
"#,
    );
    assert_eq!(names(&m.services[0].before), ["Go", "Calibrate"]);
    // every activity, itself included; a function ends at once and is not listed
    assert_eq!(
        names(&m.services[3].interrupts),
        ["Go", "Calibrate", "Panic"]
    );
    let line = "component c { function f() { before g; }; };";
    expect_error(line, "module `c` has no service `g`", 1, 37);
    let line = "component c { function all(); };";
    expect_error(line, "`all` is a reserved service name", 1, 24);
}

#[test]
fn activities_genom3_accepts_import() {
    // runs until interrupted: no path from `start` to `ether`, but `stop` ends it
    let m = module(
        r#"
component c {
  task t { period 10 ms; };
  activity Watch() { task t; codel <start> w() yield pause::start; codel <stop> s() yield ether; };
  activity Spin() { task t; codel <start> a() yield work, ether; codel <work> b() yield start; };
};
"#,
    );
    assert_eq!(m.services.len(), 2);
    // `stop` must still reach `ether`
    let line = "component c { task t { period 10 ms; }; activity A() { task t; codel <start> w() yield ether; codel <stop> s() yield pause::stop; }; };";
    expect_error(line, "no path from `stop` to `ether`", 1, 102);
}

#[test]
fn uses_reverses_the_ports_and_provides_refines_the_services() {
    let dir = TempDir::new();
    let path = dir.write(
        "c.gen",
        r#"
interface sensor { port out double reading; port in double command; function Ping(); };
interface server { activity Serve(in double rate) { doc "serves"; }; };
component c {
  uses sensor;
  provides server;
  task t { period 10 ms; };
  activity Serve(in double rate) { task t; codel <start> f(port in reading, port out command) yield pause::start, ether; };
};
"#,
    );
    let mut files = bip_lang::source_map::SourceMap::default();
    let spec = bip_lang::gen3::read(&path, "c.gen", &[], &mut files, 0, Default::default())
        .unwrap_or_else(|e| panic!("{}", e.message));
    let c = &spec.components[0];
    let dirs: Vec<(&str, PortDir)> = c.ports.iter().map(|p| (p.name.as_str(), p.dir)).collect();
    assert_eq!(dirs, [("reading", PortDir::In), ("command", PortDir::Out)]);
    assert_eq!(names(&c.remotes), ["Ping"]);
    let m = &import_gen_file(&path, &[])
        .unwrap_or_else(|e| panic!("{}", e.summary()))
        .modules[0];
    assert_eq!(m.services.len(), 1, "refined, not declared twice");
    assert_eq!(
        m.services[0].doc.as_ref().map(|d| d.as_str()),
        Some("serves")
    );
    assert_eq!(names(&m.services[0].codels[0].writes), ["command"]);
    // a refinement repeats the parameters, and gives a property once
    let iface = "interface i { activity A(in double x); }; ";
    let text = format!("{iface}component c {{ provides i; activity A(in long x); }};");
    expect_error(
        &text,
        "parameter `x` differs from its first declaration",
        1,
        88,
    );
    let text = format!("{iface}component c {{ provides i; activity A(); }};");
    expect_error(
        &text,
        "parameter `x` of the first declaration is missing",
        1,
        78,
    );
    let text = "component c { task t { period 1 s; }; activity A() { task t; }; activity A() { task t; }; };";
    expect_error(text, "duplicate `task` of `A`", 1, 85);
}

#[test]
fn codel_parameters_name_what_exists() {
    let head = "component c { ids { long n; }; port out long p; port in long q; task t { period 10 ms; }; ";
    let case = |codel: &str| {
        format!("{head}activity A(in long x) {{ task t; local long y; codel <start> {codel} yield ether; }}; }};")
    };
    for good in [
        "f(in n, local in x, local out y, port out p, port in q, out ::ids)",
        "f(ids in n, in x, out p)",
    ] {
        module(&case(good));
    }
    let col =
        head.len() + "activity A(in long x) { task t; local long y; codel <start> f(".len() + 1;
    expect_error(
        &case("f(out nosuchthing)"),
        "no ids member, parameter, local or port is named `nosuchthing`",
        1,
        col + 4,
    );
    expect_error(
        &case("f(ids in x)"),
        "no ids member is named `x`",
        1,
        col + 7,
    );
    expect_error(
        &case("f(local in n)"),
        "no parameter or local of the service is named `n`",
        1,
        col + 9,
    );
    expect_error(&case("f(port in r)"), "no port is named `r`", 1, col + 8);
    expect_error(&case("f(port out q)"), "port `q` is an in port", 1, col + 9);
    expect_error(
        &case("f(remote in r)"),
        "no remote service is named `r`",
        1,
        col + 10,
    );
}

#[test]
fn a_component_without_services_is_free_of_deadlock() {
    let def = import("component c { task t { period 10 ms; }; };")
        .unwrap_or_else(|e| panic!("{}", e.summary()));
    let sys = load_str("c.ron", &def.to_ron().expect("prints"))
        .unwrap_or_else(|e| panic!("{}", e.summary()));
    // the only step is the tick: a deadlock by the core's definition, which the layer
    // excuses as idle (nothing is outstanding, nothing can be)
    let s = sys.initial_state();
    let mut steps = bip_model::Steps::new();
    sys.enabled_steps(&s, &mut steps).expect("no range error");
    let mut checker = bip_model::LivenessChecker::default();
    assert_eq!(
        sys.liveness(&s, &steps, &mut checker)
            .expect("no range error"),
        bip_model::Liveness::Deadlock
    );
    let excused = sys.properties.iter().any(|p| match &p.kind {
        bip_model::PropertyKind::DeadlockFree { terminal: Some(t) } => {
            sys.holds(t, &s, "terminal").expect("evaluates")
        }
        _ => false,
    });
    assert!(excused, "the idle state is excused");
    // with a component of the model's own, its progress is the model's: no excuse
    let own = def.to_ron().expect("prints").replacen(
        "modules:",
        r#"atoms: {"A": Atom(locations: ["l"], initial: "l")}, components: [(name: "a", atom: "A")], modules:"#,
        1,
    );
    let sys = load_str("own.ron", &own).unwrap_or_else(|e| panic!("{}", e.summary()));
    assert!(sys.properties.iter().all(|p| !matches!(
        &p.kind,
        bip_model::PropertyKind::DeadlockFree { terminal: Some(_) }
    )));
}

#[test]
fn the_preprocessor_is_bounded() {
    let nested = |n: usize| {
        format!(
            "#define F(x) x\ncomponent c {{ task t {{ period {}10{} ms; }}; }};\n",
            "F(".repeat(n),
            ")".repeat(n)
        )
    };
    // within the bound, the calls nest as C's do
    assert!(matches!(
        module(&nested(60)).tasks[0]
            .period
            .as_ref()
            .expect("a period")
            .value,
        ConstValue::Int(1)
    ));
    // past it, an error at the call that passes it (the 65th `F`, 2 columns each)
    let col = "component c { task t { period ".len() + 64 * 2 + 1;
    expect_error(&nested(1000), "macros nested more than 64 deep", 2, col);
    // deeper, the copies of the arguments pass the bound on what is written first
    let (m, line, _) = error(&nested(8000));
    assert!(m.contains("too many tokens") && line == 2, "{m}");
    let ifs = |n: usize| {
        format!(
            "{}component c;\n{}",
            "#if 1\n".repeat(n),
            "#endif\n".repeat(n)
        )
    };
    assert_eq!(module(&ifs(256)).name.as_str(), "c");
    expect_error(&ifs(100_000), "`#if` nested more than 256 deep", 257, 1);
}
