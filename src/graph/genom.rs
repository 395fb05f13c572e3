//! The GenoM layer as written: each module a box listing its tasks and services; each out
//! port an oval, with arrows from the services whose codels write it and to those that
//! read it; each in port an oval with an arrow into its module, and one from the out port
//! a connection says it reads; the constraints as labelled edges between the services they tie; the model's
//! own components beside the modules, joined to the services whose connectors they extend.
//! Names are the user's: the expansion's components and connectors never show.

use std::collections::{BTreeMap, BTreeSet};

use bip_lang::genom::syntax::{CodelDef, ConstraintDef, ServiceKind};
use bip_lang::source::Text;
use bip_lang::syntax::SystemDef;
use bip_model::System;
use bip_picture::{Direction, Edge, End, Graph, Line, Node, Shape};

const CONSTRAINT: &str = "#b22222";
const PORT: &str = "#1d5e8c";
const USER: &str = "#555555";

pub fn graph(def: &SystemDef, system: &System) -> Graph {
    let mut g = Graph::new(
        def.name.as_str(),
        format!("{}: modules, ports and constraints", def.name.as_str()),
        Direction::LeftRight,
    );
    let mut services: BTreeMap<String, End> = BTreeMap::new();
    let mut ports: BTreeMap<String, usize> = BTreeMap::new();
    let mut writes = Vec::new();
    for module in &def.modules {
        let m = module.name.as_str();
        let mut node = Node::new(format!("module {m}"), m, "module").fill("#f7f7f2");
        let mut machines = Vec::new();
        for task in &module.tasks {
            let machine = if task.has_machine() {
                ", runs a machine"
            } else {
                ""
            };
            let period = match &task.period {
                Some(p) => format!("period {}", p.value),
                None => "aperiodic".into(),
            };
            let row = node.row(
                format!("task {}, {period}{machine}", task.name.as_str()),
                "task",
            );
            if task.has_machine() {
                machines.push((row, task.name.as_str(), &task.codels));
            }
        }
        let mut rows = Vec::new();
        for service in &module.services {
            let kind = match service.kind {
                ServiceKind::Activity => "activity",
                ServiceKind::Function => "function",
                ServiceKind::Attribute => "attribute",
            };
            let mut text = format!("{} ({kind}", service.name.as_str());
            if let Some(task) = &service.task {
                text.push_str(&format!(" in {}", task.as_str()));
            }
            text.push(')');
            if !service.interrupts.is_empty() {
                text.push_str(&format!(", interrupts {}", names(&service.interrupts)));
            }
            if !service.after.is_empty() {
                text.push_str(&format!(", after {}", names(&service.after)));
            }
            rows.push((service, node.row(text, kind)));
        }
        let at = g.add(node);
        // what the services' codels and the tasks' machines write
        let mut written = |end: End, codels: &[CodelDef]| {
            let ports: BTreeSet<&str> = codels
                .iter()
                .flat_map(|c| c.writes.iter().map(|p| p.as_str()))
                .collect();
            for port in ports {
                writes.push((end, format!("{m}.{port}")));
            }
        };
        for (service, row) in rows {
            let end = End::row(at, row);
            services.insert(format!("{m}.{}", service.name.as_str()), end);
            written(end, &service.codels);
        }
        // a machine is named like a service, by its task (constraints name it so)
        for (row, task, codels) in machines {
            let end = End::row(at, row);
            services.insert(format!("{m}.{task}"), end);
            written(end, codels);
        }
        for port in &module.ports {
            let name = format!("{m}.{}", port.name.as_str());
            let node = Node::new(format!("port {name}"), name.as_str(), "port")
                .shape(Shape::Ellipse)
                .fill("#e8f1fa");
            ports.insert(name, g.add(node));
        }
        // an in port: an oval of its own, whose data flows into its module
        for port in &module.in_ports {
            let name = format!("{m}.{}", port.name.as_str());
            let node = Node::new(format!("port {name}"), name.as_str(), "in-port")
                .shape(Shape::Ellipse)
                .fill("#ffffff");
            let p = g.add(node);
            g.connect(Edge::new(End::node(p), End::node(at), "reads").colour(PORT));
            ports.insert(name, p);
        }
    }
    for (from, port) in writes {
        if let Some(&to) = ports.get(&port) {
            g.connect(Edge::new(from, End::node(to), "writes").colour(PORT));
        }
    }
    // the data flow between components: each out port to the in ports connected to it
    for c in &def.connections {
        if let (Some(&from), Some(&to)) = (ports.get(c.reads.as_str()), ports.get(c.port.as_str()))
        {
            g.connect(
                Edge::new(End::node(from), End::node(to), "connection")
                    .label("connected")
                    .colour(PORT),
            );
        }
    }
    let users = user_components(def, &mut g);
    for constraint in &def.constraints {
        constraint_edges(&mut g, constraint, &services, &ports, &users);
    }
    connector_edges(&mut g, def, system, &services, &ports, &users);
    g
}

fn names(list: &[Text]) -> String {
    let names: Vec<&str> = list.iter().map(|t| t.as_str()).collect();
    names.join(", ")
}

/// The model's own components, by name, as nodes.
fn user_components(def: &SystemDef, g: &mut Graph) -> BTreeMap<String, usize> {
    let mut out = BTreeMap::new();
    for component in &def.components {
        let name = component.name.as_str();
        let node = Node::new(format!("component {name}"), name, "component")
            .subtitle(component.atom.as_str())
            .fill("#f3f7ee");
        out.insert(name.to_string(), g.add(node));
    }
    out
}

fn constraint_edges(
    g: &mut Graph,
    constraint: &ConstraintDef,
    services: &BTreeMap<String, End>,
    ports: &BTreeMap<String, usize>,
    users: &BTreeMap<String, usize>,
) {
    let label = |detail: String| match constraint.name() {
        Some(name) => format!("{}: {detail}", name.as_str()),
        None => detail,
    };
    let service = |t: &Text| services.get(t.as_str()).copied();
    let edge = |from: End, to: End, text: String| {
        Edge::new(from, to, "constraint")
            .label(text)
            .colour(CONSTRAINT)
            .line(Line::Dashed)
    };
    match constraint {
        ConstraintDef::Exclusive { services: list, .. } => {
            pairwise(g, list, &service, &|a, b| {
                edge(a, b, label("exclusive".into())).undirected()
            });
        }
        ConstraintDef::AtMost {
            services: list,
            max,
            ..
        } => {
            let text = label(format!("at most {}", max.value));
            pairwise(g, list, &service, &|a, b| {
                edge(a, b, text.clone()).undirected()
            });
        }
        ConstraintDef::Requires {
            service: s, active, ..
        } => {
            for other in active {
                if let (Some(a), Some(b)) = (service(s), service(other)) {
                    g.connect(edge(a, b, label("requires".into())));
                }
            }
        }
        ConstraintDef::Fresh {
            service: s,
            port,
            max_age,
            ..
        } => {
            if let (Some(&p), Some(to)) = (ports.get(port.as_str()), service(s)) {
                g.connect(edge(
                    End::node(p),
                    to,
                    label(format!("age ≤ {}", max_age.value)),
                ));
            }
        }
        ConstraintDef::Guard {
            service: s, when, ..
        } => {
            let Some(to) = service(s) else { return };
            let text = label(format!("guard: {}", when.as_str()));
            let mentioned: Vec<usize> = users
                .iter()
                .filter(|(name, _)| crate::names::mentions(when.as_str(), name))
                .map(|(_, &n)| n)
                .collect();
            if mentioned.is_empty() {
                let note =
                    g.add(Node::new(format!("guard {text}"), "guard", "guard").line(Line::Dashed));
                g.connect(edge(End::node(note), to, text));
            } else {
                for from in mentioned {
                    g.connect(edge(End::node(from), to, text.clone()));
                }
            }
        }
    }
}

fn pairwise(
    g: &mut Graph,
    list: &[Text],
    service: &dyn Fn(&Text) -> Option<End>,
    edge: &dyn Fn(End, End) -> Edge,
) {
    for (k, a) in list.iter().enumerate() {
        for b in &list[k + 1..] {
            if let (Some(a), Some(b)) = (service(a), service(b)) {
                g.connect(edge(a, b));
            }
        }
    }
}

/// The model's own connectors. One that extends a generated connector (a codel's, a
/// request's, a pending request's interrupts, the tick) is an edge from its service (or
/// the clock) to each component of the model's own it adds; another is a dot joining its
/// components and the activities whose ports it takes (`abort`, …). What its guard and
/// action read is drawn too: a port's age, an activity's being active.
fn connector_edges(
    g: &mut Graph,
    def: &SystemDef,
    system: &System,
    services: &BTreeMap<String, End>,
    ports: &BTreeMap<String, usize>,
    users: &BTreeMap<String, usize>,
) {
    let Some(map) = &system.genom else { return };
    // each interaction of the layer, with the service (or the tick) it belongs to
    let mut owner: BTreeMap<u32, String> = BTreeMap::new();
    owner.insert(map.tick, "tick".to_string());
    // each activity's component, with its service
    let mut activity: BTreeMap<u32, String> = BTreeMap::new();
    for module in &map.modules {
        for service in &module.services {
            let name = format!("{}.{}", module.name, service.name);
            for i in service.request.iter().chain(&service.interrupt) {
                owner.insert(*i, name.clone());
            }
            for codel in &service.codels {
                owner.insert(codel.run, name.clone());
                owner.insert(codel.fail, name.clone());
                if let Some(apart) = codel.apart {
                    owner.insert(apart.start, name.clone());
                    owner.insert(apart.returned, name.clone());
                }
            }
            if let Some(c) = service.component {
                activity.insert(c, name.clone());
            }
        }
    }
    let user_of = |component: u32| -> Option<usize> {
        let c = &system.components[component as usize];
        users
            .get(system.families[c.family as usize].name.as_str())
            .copied()
    };
    let mut clock = None;
    let mut drawn = BTreeSet::new();
    for connector in &def.connectors {
        let name = connector.name.as_str();
        let Some(c) = system.connectors.iter().find(|c| c.name == name) else {
            continue;
        };
        let port_refs: Vec<bip_model::PortRef> = c
            .interactions
            .clone()
            .flat_map(|i| system.interactions[i as usize].ports.iter().copied())
            .collect();
        let mut mine: Vec<usize> = port_refs
            .iter()
            .filter_map(|p| user_of(p.component))
            .collect();
        mine.sort_unstable();
        mine.dedup();
        let target = c.interactions.clone().find_map(|i| owner.get(&i)).cloned();
        // where what the connector reads goes: its dot, or the components it adds
        let readers: Vec<End> = match target.as_deref() {
            Some("tick") => {
                let to = *clock.get_or_insert_with(|| {
                    g.add(
                        Node::new("clock", "clock tick", "clock")
                            .shape(Shape::Ellipse)
                            .fill("#eeeeee"),
                    )
                });
                for &from in &mine {
                    g.connect(user_edge(End::node(to), End::node(from), name));
                }
                mine.iter().map(|&n| End::node(n)).collect()
            }
            Some(service) => {
                if let Some(&to) = services.get(service) {
                    for &from in &mine {
                        g.connect(user_edge(to, End::node(from), name));
                    }
                }
                mine.iter().map(|&n| End::node(n)).collect()
            }
            None => {
                let dot = g.add(
                    Node::new(format!("connector {name}"), name, "connector").shape(Shape::Point),
                );
                for &from in &mine {
                    g.connect(
                        Edge::new(End::node(from), End::node(dot), "connector")
                            .undirected()
                            .colour(USER),
                    );
                }
                let mut taken = BTreeSet::new();
                for p in &port_refs {
                    let Some(service) = activity.get(&p.component) else {
                        continue;
                    };
                    let port = &system.atom_of(p.component).ports[p.port as usize];
                    if let Some(&to) = services.get(service) {
                        if taken.insert((service.clone(), port.clone())) {
                            g.connect(
                                Edge::new(End::node(dot), to, "connector")
                                    .label(port.as_str())
                                    .colour(USER),
                            );
                        }
                    }
                }
                vec![End::node(dot)]
            }
        };
        let text = format!(
            "{} {}",
            connector
                .guard
                .as_ref()
                .map(|e| e.to_string())
                .unwrap_or_default(),
            connector
                .action
                .as_ref()
                .map(|a| a.to_string())
                .unwrap_or_default()
        );
        let mut read: Vec<(End, String)> = ports
            .iter()
            .filter(|(port, _)| text.contains(&format!("age({port})")))
            .map(|(port, &p)| (End::node(p), port.clone()))
            .collect();
        read.extend(
            services
                .iter()
                .filter(|(service, _)| text.contains(&format!("active({service})")))
                .map(|(service, &end)| (end, service.clone())),
        );
        for (from, what) in read {
            for &to in &readers {
                if drawn.insert((format!("{from:?}"), format!("{to:?}"), what.clone())) {
                    g.connect(
                        Edge::new(from, to, "reads")
                            .label("reads")
                            .colour(PORT)
                            .line(Line::Dotted),
                    );
                }
            }
        }
    }
}

/// A user connector that extends a generated one: from the service's side to the user's
/// component.
fn user_edge(from: End, to: End, connector: &str) -> Edge {
    Edge::new(from, to, "connector")
        .label(connector)
        .colour(USER)
}
