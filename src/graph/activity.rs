//! One activity's codel automaton, as written: `ether` (idle), its codel states, each
//! yield (a plain yield runs on in the same cycle, `pause::` waits for the task's next
//! period, `ether` ends the activity), each exception, and the stop path an interrupt
//! takes. A task's machine (`module.task`) is drawn the same way: it starts at its task's
//! first period without a request, and nothing interrupts it.

use bip_lang::genom::syntax::{CodelDef, ServiceKind};
use bip_lang::syntax::SystemDef;
use bip_picture::{Direction, Edge, End, Graph, Line, Node, Shape};

const ETHER: &str = "ether";
const STOP: &str = "stop";

/// What `--activity` draws: an activity, or a task's machine.
struct Automaton<'a> {
    module: &'a str,
    name: &'a str,
    task: &'a str,
    codels: &'a [CodelDef],
    machine: bool,
}

/// The automaton of activity `name` (`module.Service`) or of a task's machine
/// (`module.task`), or why there is none.
pub fn graph(def: &SystemDef, name: &str) -> Result<Graph, String> {
    let a = find(def, name)?;
    let what = if a.machine {
        format!(
            "the machine of task {}.{}: its codels, from the start",
            a.module, a.name
        )
    } else {
        format!(
            "activity {}.{}: its codels (task {})",
            a.module, a.name, a.task
        )
    };
    let mut g = Graph::new(format!("{}.{}", a.module, a.name), what, Direction::TopDown);
    let ether = g.add(
        Node::new(ETHER, ETHER, "ether")
            .shape(Shape::DoubleCircle)
            .fill("#eeeeee"),
    );
    let mut states = Vec::new();
    for codel in a.codels {
        let mut node = Node::new(
            format!("codel {}", codel.state.as_str()),
            codel.state.as_str(),
            "codel",
        )
        .fill("#eef5ff");
        let mut notes = Vec::new();
        if codel.asynchronous {
            // docs/genom.md, "Async codels"
            notes.push("async: runs apart from its task".to_string());
        }
        if !codel.writes.is_empty() {
            let ports: Vec<&str> = codel.writes.iter().map(|p| p.as_str()).collect();
            notes.push(format!("writes {}", ports.join(", ")));
        }
        if let Some(wcet) = &codel.wcet {
            notes.push(format!("wcet {}", wcet.value));
        }
        if a.machine && codel.state.as_str() == STOP {
            // GenoM3 runs it when the component shuts down, which the model does not hold
            notes.push("at shutdown: never in the model".to_string());
        }
        if !notes.is_empty() {
            node = node.subtitle(notes.join("; "));
        }
        states.push((codel.state.as_str(), g.add(node)));
    }
    let index = |s: &str| states.iter().find(|(n, _)| *n == s).map(|&(_, k)| k);
    if let Some(start) = index("start") {
        let label = if a.machine {
            "at the first period"
        } else {
            "request, at a period"
        };
        g.connect(
            Edge::new(End::node(ether), End::node(start), "request")
                .label(label)
                .colour("#1d5e8c"),
        );
    }
    let mut error = None;
    for codel in a.codels {
        let Some(from) = index(codel.state.as_str()) else {
            continue;
        };
        for target in &codel.yields {
            let target = target.as_str();
            let (state, paused) = match target.strip_prefix("pause::") {
                Some(s) => (s, true),
                None => (target, false),
            };
            let to = if state == ETHER {
                Some(ether)
            } else {
                index(state)
            };
            let Some(to) = to else { continue };
            let mut edge = Edge::new(End::node(from), End::node(to), "yield");
            edge = if paused {
                edge.label(format!("pause::{state}")).line(Line::Dashed)
            } else if state == ETHER {
                edge.label("ether (done)").colour("#1f6e2e")
            } else {
                edge.label(state)
            };
            g.connect(edge);
        }
        for exception in &codel.throws {
            let to = *error.get_or_insert_with(|| {
                g.add(
                    Node::new("error", "ends with an error", "error")
                        .fill("#fde8e8")
                        .line(Line::Dashed),
                )
            });
            g.connect(
                Edge::new(End::node(from), End::node(to), "throw")
                    .label(exception.as_str())
                    .colour("#b22222"),
            );
        }
    }
    if let Some(&to) = error.as_ref() {
        g.connect(
            Edge::new(End::node(to), End::node(ether), "throw")
                .colour("#b22222")
                .line(Line::Dotted),
        );
    }
    let running: Vec<usize> = states
        .iter()
        .filter(|(s, _)| *s != STOP)
        .map(|&(_, k)| k)
        .collect();
    // nothing interrupts or aborts a task's machine
    if !running.is_empty() && !a.machine {
        let interrupt =
            g.add(Node::new("interrupt", "interrupt, abort", "interrupt").shape(Shape::Point));
        let (to, label) = match index(STOP) {
            Some(stop) => (stop, "stop path (ungated)"),
            None => (ether, "ends at once"),
        };
        g.connect(
            Edge::new(End::node(interrupt), End::node(to), "interrupt")
                .label(label)
                .colour("#b22222")
                .line(Line::Dashed),
        );
    }
    Ok(g)
}

fn find<'a>(def: &'a SystemDef, name: &str) -> Result<Automaton<'a>, String> {
    let mut known: Vec<String> = Vec::new();
    let mut found = None;
    for m in &def.modules {
        let module = m.name.as_str();
        for t in m.tasks.iter().filter(|t| t.has_machine()) {
            known.push(format!("{module}.{} (a task's machine)", t.name.as_str()));
            if format!("{module}.{}", t.name.as_str()) == name {
                found = Some(Automaton {
                    module,
                    name: t.name.as_str(),
                    task: t.name.as_str(),
                    codels: &t.codels,
                    machine: true,
                });
            }
        }
        for s in m
            .services
            .iter()
            .filter(|s| s.kind == ServiceKind::Activity)
        {
            known.push(format!("{module}.{}", s.name.as_str()));
            if format!("{module}.{}", s.name.as_str()) == name {
                found = Some(Automaton {
                    module,
                    name: s.name.as_str(),
                    task: s.task.as_ref().map_or("", |t| t.as_str()),
                    codels: &s.codels,
                    machine: false,
                });
            }
        }
    }
    found.ok_or_else(|| {
        if known.is_empty() {
            format!("the model has no activity `{name}`: it has no activities")
        } else {
            format!(
                "the model has no activity `{name}`\n  help: its activities are {}",
                known.join(", ")
            )
        }
    })
}
