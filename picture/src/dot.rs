//! A graph in graphviz's DOT language, for `dot -Tsvg` and other graphviz tools. Nodes
//! with rows are HTML-like tables whose cells are ports, so an edge attaches to its row.

use std::fmt::Write;

use crate::graph::{Direction, End, Graph, Line, Node, Shape};
use crate::xml::escape;

/// `text` as a DOT quoted string.
pub fn quoted(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c if c.is_control() => {}
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// The graph in DOT.
pub fn to_dot(graph: &Graph) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "digraph {} {{", quoted(&graph.name));
    if graph.direction == Direction::LeftRight {
        let _ = writeln!(s, "  rankdir=LR;");
    }
    let _ = writeln!(s, "  label={}; labelloc=t;", quoted(&graph.title));
    let _ = writeln!(
        s,
        "  node [fontname=\"sans-serif\" fontsize=11]; edge [fontname=\"sans-serif\" fontsize=10];"
    );
    for node in &graph.nodes {
        let _ = writeln!(s, "  {} [{}];", quoted(&node.id), node_attributes(node));
    }
    for edge in &graph.edges {
        let mut attrs = Vec::new();
        if let Some(label) = &edge.label {
            attrs.push(format!("label={}", quoted(label)));
        }
        match edge.line {
            Line::Solid => {}
            Line::Dashed => attrs.push("style=dashed".into()),
            Line::Dotted => attrs.push("style=dotted".into()),
        }
        if !edge.directed {
            attrs.push("dir=none".into());
        }
        if edge.colour != "#333333" {
            attrs.push(format!("color={}", quoted(edge.colour)));
        }
        if edge.bold {
            attrs.push("penwidth=2".into());
        }
        attrs.push(format!("class={}", quoted(&edge.class)));
        let _ = writeln!(
            s,
            "  {} -> {} [{}];",
            end(graph, edge.from),
            end(graph, edge.to),
            attrs.join(" ")
        );
    }
    s.push_str("}\n");
    s
}

fn end(graph: &Graph, end: End) -> String {
    let id = quoted(&graph.nodes[end.node].id);
    match end.row {
        Some(row) => format!("{id}:r{row}"),
        None => id,
    }
}

fn node_attributes(node: &Node) -> String {
    let mut attrs = Vec::new();
    if node.rows.is_empty() {
        let shape = match node.shape {
            Shape::Box => "box",
            Shape::Ellipse => "ellipse",
            Shape::Point => "point",
            Shape::DoubleCircle => "doublecircle",
        };
        attrs.push(format!("shape={shape}"));
        let label = match &node.subtitle {
            Some(sub) => format!("{}\n{sub}", node.title),
            None => node.title.clone(),
        };
        if node.shape == Shape::Point {
            attrs.push(format!("xlabel={}", quoted(&label)));
        } else {
            attrs.push(format!("label={}", quoted(&label)));
        }
        let mut style = vec![];
        if node.shape != Shape::Point {
            style.push("filled");
        }
        if node.shape == Shape::Box {
            style.push("rounded");
        }
        if node.line == Line::Dashed {
            style.push("dashed");
        }
        if !style.is_empty() {
            attrs.push(format!("style={}", quoted(&style.join(","))));
            attrs.push(format!("fillcolor={}", quoted(node.fill)));
        }
    } else {
        attrs.push("shape=plain".into());
        let mut table = format!(
            "<table border=\"1\" cellborder=\"0\" cellspacing=\"0\" cellpadding=\"3\" bgcolor=\"{}\"><tr><td><b>{}</b></td></tr>",
            node.fill,
            escape(&node.title)
        );
        if let Some(sub) = &node.subtitle {
            let _ = write!(table, "<tr><td><i>{}</i></td></tr>", escape(sub));
        }
        for (k, row) in node.rows.iter().enumerate() {
            let _ = write!(
                table,
                "<tr><td port=\"r{k}\" align=\"left\"><font color=\"{}\">{}</font></td></tr>",
                row.colour(),
                escape(&row.text)
            );
        }
        table.push_str("</table>");
        attrs.push(format!("label=<{table}>"));
    }
    attrs.push(format!("class={}", quoted(&node.class)));
    attrs.join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{Edge, Node};

    #[test]
    fn quotes_and_escapes() {
        assert_eq!(quoted("a \"b\" \\ c\nd"), "\"a \\\"b\\\" \\\\ c\\nd\"");
    }

    #[test]
    fn rows_are_ports_of_a_table() {
        let mut g = Graph::new("g", "G", Direction::LeftRight);
        let mut m = Node::new("m", "m <1>", "module");
        let r = m.row("S", "service");
        let a = g.add(m);
        let b = g.add(Node::new("p", "p", "port").shape(Shape::Ellipse));
        g.connect(Edge::new(End::row(a, r), End::node(b), "writes").line(Line::Dashed));
        let dot = to_dot(&g);
        assert!(dot.contains("<b>m &lt;1&gt;</b>"), "{dot}");
        assert!(
            dot.contains("<td port=\"r0\" align=\"left\"><font color=\"#222222\">S</font></td>"),
            "{dot}"
        );
        assert!(
            dot.contains("\"m\":r0 -> \"p\" [style=dashed class=\"writes\"];"),
            "{dot}"
        );
    }
}
