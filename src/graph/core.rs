//! BIP core: each component a box listing the ports its connectors use; each connector
//! (each instance of a `forall`) a dot joining those ports, a broadcast's trigger in bold;
//! each priority a dashed arrow from the lower connector to the higher one.

use std::collections::BTreeMap;

use bip_model::System;
use bip_picture::{Direction, Edge, End, Graph, Line, Node, Shape};

/// The core of `system`; `guards` are the priorities' `when` as written, one per priority,
/// when they are known (a model without a GenoM layer).
pub fn graph(system: &System, guards: Option<Vec<String>>) -> Graph {
    let mut g = Graph::new(
        system.name.as_str(),
        format!("{}: components and connectors", system.name),
        Direction::LeftRight,
    );
    // the ports each component shows: those some connector uses, in the atom's order
    let mut used: BTreeMap<(u32, u32), usize> = BTreeMap::new();
    for i in &system.interactions {
        for p in &i.ports {
            used.insert((p.component, p.port), 0);
        }
    }
    let mut component_node = Vec::new();
    for (c, component) in system.components.iter().enumerate() {
        let atom = system.atom_of(c as u32);
        let mut node = Node::new(
            format!("component {}", component.name),
            component.name.as_str(),
            "component",
        )
        .subtitle(atom.name.as_str())
        .fill("#f3f7ee");
        for (p, port) in atom.ports.iter().enumerate() {
            if let Some(row) = used.get_mut(&(c as u32, p as u32)) {
                *row = node.row(port.as_str(), "port");
            }
        }
        component_node.push(g.add(node));
    }
    let mut interaction_node = Vec::new();
    for interaction in &system.interactions {
        let connector = &system.connectors[interaction.connector as usize];
        let class = if connector.broadcast {
            "connector broadcast"
        } else {
            "connector"
        };
        let node = g.add(
            Node::new(
                format!("connector {}", interaction.name),
                interaction.name.as_str(),
                class,
            )
            .shape(Shape::Point),
        );
        interaction_node.push(node);
        for (k, p) in interaction.ports.iter().enumerate() {
            let from = End::row(
                component_node[p.component as usize],
                used[&(p.component, p.port)],
            );
            // the first port (a broadcast's trigger) leads into the connector and the others
            // out of it, so that the layers follow the connectors through the components
            let leads = interaction.trigger.map_or(k == 0, |t| t as usize == k);
            let mut edge = if leads {
                Edge::new(from, End::node(node), "port")
            } else {
                Edge::new(End::node(node), from, "port")
            }
            .undirected();
            if interaction.trigger == Some(k as u32) {
                edge = edge.bold().label("trigger").colour("#b8590b");
            }
            g.connect(edge);
        }
    }
    for (k, priority) in system.priorities.iter().enumerate() {
        for low in priority.low.clone() {
            for high in priority.high.clone() {
                let mut edge = Edge::new(
                    End::node(interaction_node[low as usize]),
                    End::node(interaction_node[high as usize]),
                    "priority",
                )
                .line(Line::Dashed)
                .colour("#7b3294");
                if priority.when.is_some() {
                    edge = edge.label(match guards.as_ref().and_then(|g| g.get(k)) {
                        Some(when) => format!("when {when}"),
                        None => "when its guard holds".to_string(),
                    });
                }
                g.connect(edge);
            }
        }
    }
    g
}
