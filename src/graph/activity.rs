//! One activity's codel automaton, as written: `ether` (idle), its codel states, each
//! yield (a plain yield runs on in the same cycle, `pause::` waits for the task's next
//! period, `ether` ends the activity), each exception, and the stop path an interrupt
//! takes.

use bip_lang::genom::syntax::{ModuleDef, ServiceDef, ServiceKind};
use bip_lang::syntax::SystemDef;
use bip_picture::{Direction, Edge, End, Graph, Line, Node, Shape};

const ETHER: &str = "ether";
const STOP: &str = "stop";

/// The automaton of activity `name` (`module.Service`), or why there is none.
pub fn graph(def: &SystemDef, name: &str) -> Result<Graph, String> {
    let (module, service) = find(def, name)?;
    let task = service.task.as_ref().map_or("", |t| t.as_str());
    let mut g = Graph::new(
        format!("{}.{}", module.name.as_str(), service.name.as_str()),
        format!(
            "activity {}.{}: its codels (task {task})",
            module.name.as_str(),
            service.name.as_str()
        ),
        Direction::TopDown,
    );
    let ether = g.add(
        Node::new(ETHER, ETHER, "ether")
            .shape(Shape::DoubleCircle)
            .fill("#eeeeee"),
    );
    let mut states = Vec::new();
    for codel in &service.codels {
        let mut node = Node::new(
            format!("codel {}", codel.state.as_str()),
            codel.state.as_str(),
            "codel",
        )
        .fill("#eef5ff");
        let mut notes = Vec::new();
        if !codel.writes.is_empty() {
            let ports: Vec<&str> = codel.writes.iter().map(|p| p.as_str()).collect();
            notes.push(format!("writes {}", ports.join(", ")));
        }
        if let Some(wcet) = &codel.wcet {
            notes.push(format!("wcet {}", wcet.value));
        }
        if !notes.is_empty() {
            node = node.subtitle(notes.join("; "));
        }
        states.push((codel.state.as_str(), g.add(node)));
    }
    let index = |s: &str| states.iter().find(|(n, _)| *n == s).map(|&(_, k)| k);
    if let Some(start) = index("start") {
        g.connect(
            Edge::new(End::node(ether), End::node(start), "request")
                .label("request, at a period")
                .colour("#1d5e8c"),
        );
    }
    let mut error = None;
    for codel in &service.codels {
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
    if !running.is_empty() {
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

fn find<'a>(def: &'a SystemDef, name: &str) -> Result<(&'a ModuleDef, &'a ServiceDef), String> {
    let activities: Vec<String> = def
        .modules
        .iter()
        .flat_map(|m| {
            m.services
                .iter()
                .filter(|s| s.kind == ServiceKind::Activity)
                .map(move |s| format!("{}.{}", m.name.as_str(), s.name.as_str()))
        })
        .collect();
    let found = name.split_once('.').and_then(|(m, s)| {
        let module = def.modules.iter().find(|d| d.name.as_str() == m)?;
        let service = module
            .services
            .iter()
            .find(|d| d.name.as_str() == s && d.kind == ServiceKind::Activity)?;
        Some((module, service))
    });
    found.ok_or_else(|| {
        if activities.is_empty() {
            format!("the model has no activity `{name}`: it has no activities")
        } else {
            format!(
                "the model has no activity `{name}`\n  help: its activities are {}",
                activities.join(", ")
            )
        }
    })
}
