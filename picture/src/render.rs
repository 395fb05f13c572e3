//! A graph drawn as SVG with the project's own layered layout: no external program.
//! Each node is a group of class `node <class>` whose tooltip is its id; each edge a group
//! of class `edge <class>`.

use std::collections::BTreeMap;
use std::fmt::Write;

use crate::graph::{Direction, End, Graph, Line, Node, Shape};
use crate::layout::{layered, LayoutEdge, Point, Size};
use crate::svg::{arrow_marker, num, text_width, Anchor, Font, Paint, Svg};

const TITLE: f64 = 12.0;
const TEXT: f64 = 11.0;
const SMALL: f64 = 10.0;
const ROW: f64 = 17.0;
const HEAD: f64 = 22.0;
const PAD: f64 = 10.0;
const MARGIN: f64 = 20.0;
const HEADING: f64 = 30.0;
const DOT: f64 = 5.0;

/// The graph as an SVG document.
pub fn to_svg(graph: &Graph) -> String {
    let sizes: Vec<Size> = graph.nodes.iter().map(size_of).collect();
    let edges: Vec<LayoutEdge> = graph
        .edges
        .iter()
        .map(|e| LayoutEdge {
            from: e.from.node,
            to: e.to.node,
            label: e.label.as_ref().map(|l| Size {
                w: text_width(l, SMALL) + 6.0,
                h: SMALL + 6.0,
            }),
        })
        .collect();
    let placed = layered(&sizes, &edges, graph.direction);
    let origin = Point {
        x: MARGIN,
        y: MARGIN + HEADING,
    };
    let shift = |p: Point| Point {
        x: p.x + origin.x,
        y: p.y + origin.y,
    };
    let centres: Vec<Point> = placed.nodes.iter().map(|&p| shift(p)).collect();

    let mut svg = Svg::new();
    let mut markers: BTreeMap<&str, String> = BTreeMap::new();
    for edge in &graph.edges {
        if edge.directed && !markers.contains_key(edge.colour) {
            let (id, def) = arrow_marker(edge.colour);
            svg.define(&def);
            markers.insert(edge.colour, id);
        }
    }
    svg.text(MARGIN, MARGIN + 8.0, &graph.title, Font::new(14.0).bold());
    let mut width = placed.width + 2.0 * MARGIN;
    let height = placed.height + 2.0 * MARGIN + HEADING;
    for (k, edge) in graph.edges.iter().enumerate() {
        let from = centres[edge.from.node];
        let to = centres[edge.to.node];
        let bends: Vec<Point> = placed.bends[k].iter().map(|&p| shift(p)).collect();
        svg.open(&format!("edge {}", edge.class), edge.label.as_deref());
        let mut paint = Paint::stroke(edge.colour).width(if edge.bold { 2.2 } else { 1.1 });
        paint = match edge.line {
            Line::Solid => paint,
            Line::Dashed => paint.dash("6 4"),
            Line::Dotted => paint.dash("2 3"),
        };
        let marker = edge
            .directed
            .then(|| markers.get(edge.colour).map(String::as_str))
            .flatten();
        let label_at;
        if edge.from.node == edge.to.node {
            let node = &graph.nodes[edge.from.node];
            let size = sizes[edge.from.node];
            let right = from.x + size.w / 2.0;
            let y = edge.from.row.map_or(from.y, |r| row_y(node, from, size, r));
            let d = format!(
                "M{},{} C{},{} {},{} {},{}",
                num(right),
                num(y - 5.0),
                num(right + 30.0),
                num(y - 18.0),
                num(right + 30.0),
                num(y + 18.0),
                num(right + 1.0),
                num(y + 5.0)
            );
            svg.path(&d, paint, marker);
            label_at = Point { x: right + 34.0, y };
            if let Some(label) = &edge.label {
                width = width.max(label_at.x + text_width(label, SMALL) + MARGIN);
            }
        } else {
            let first = bends.first().copied().unwrap_or(to);
            let last = bends.last().copied().unwrap_or(from);
            let start = attach(graph, &sizes, &centres, edge.from, first, graph.direction);
            let end = attach(graph, &sizes, &centres, edge.to, last, graph.direction);
            let mut points = vec![start];
            points.extend(bends.iter().copied());
            points.push(end);
            svg.path(&smooth(&points), paint, marker);
            label_at = placed.labels[k].map(shift).unwrap_or(Point {
                x: (start.x + end.x) / 2.0,
                y: (start.y + end.y) / 2.0,
            });
        }
        if let Some(label) = &edge.label {
            let w = text_width(label, SMALL);
            let anchored = if edge.from.node == edge.to.node {
                Anchor::Start
            } else {
                Anchor::Middle
            };
            let left = match anchored {
                Anchor::Middle => label_at.x - w / 2.0,
                _ => label_at.x,
            };
            svg.rect(
                left - 2.0,
                label_at.y - SMALL / 2.0 - 2.0,
                w + 4.0,
                SMALL + 4.0,
                2.0,
                Paint::filled("#ffffff", "none"),
            );
            svg.text(
                label_at.x,
                label_at.y + SMALL * 0.35,
                label,
                Font::new(SMALL).colour(edge.colour).anchor(anchored),
            );
        }
        svg.close();
    }
    for (k, node) in graph.nodes.iter().enumerate() {
        draw_node(&mut svg, node, centres[k], sizes[k], graph.direction);
    }
    let heading = text_width(&graph.title, 14.0) * 1.05 + 2.0 * MARGIN;
    svg.finish(width.max(heading), height, &graph.title)
}

fn size_of(node: &Node) -> Size {
    let title = text_width(&node.title, TITLE) * 1.08;
    let sub = node
        .subtitle
        .as_deref()
        .map_or(0.0, |s| text_width(s, SMALL));
    match node.shape {
        Shape::Point => Size {
            w: title.max(2.0 * DOT) + 4.0,
            h: 2.0 * DOT + TEXT + 4.0,
        },
        Shape::Box if !node.rows.is_empty() => {
            let rows = node
                .rows
                .iter()
                .map(|r| text_width(&r.text, TEXT))
                .fold(0.0, f64::max);
            Size {
                w: title.max(sub).max(rows) + 2.0 * PAD,
                h: head_height(node) + ROW * node.rows.len() as f64 + 4.0,
            }
        }
        Shape::Box => Size {
            w: title.max(sub) + 2.0 * PAD,
            h: head_height(node),
        },
        Shape::Ellipse => Size {
            w: title.max(sub) * 1.2 + 2.0 * PAD,
            h: head_height(node) + 8.0,
        },
        Shape::DoubleCircle => {
            let d = title.max(sub).max(20.0) + 14.0;
            Size { w: d, h: d }
        }
    }
}

fn head_height(node: &Node) -> f64 {
    HEAD + if node.subtitle.is_some() { 12.0 } else { 0.0 }
}

/// The vertical centre of row `row` of a node centred at `at`.
fn row_y(node: &Node, at: Point, size: Size, row: usize) -> f64 {
    at.y - size.h / 2.0 + head_height(node) + ROW * row as f64 + ROW / 2.0
}

/// Where an edge leaves or enters its node, coming from or going to `towards`: the row's
/// side for a row, else the node's outline on the line to its centre.
fn attach(
    graph: &Graph,
    sizes: &[Size],
    centres: &[Point],
    end: End,
    towards: Point,
    direction: Direction,
) -> Point {
    let node = &graph.nodes[end.node];
    let size = sizes[end.node];
    let c = centres[end.node];
    if let Some(row) = end.row {
        let y = row_y(node, c, size, row);
        let side = if towards.x >= c.x { 1.0 } else { -1.0 };
        return Point {
            x: c.x + side * size.w / 2.0,
            y,
        };
    }
    match node.shape {
        Shape::Point => along(dot_centre(c, size, direction), towards, DOT),
        Shape::Ellipse | Shape::DoubleCircle => {
            let (rx, ry) = (size.w / 2.0, size.h / 2.0);
            let (dx, dy) = (towards.x - c.x, towards.y - c.y);
            let len = ((dx / rx).powi(2) + (dy / ry).powi(2)).sqrt();
            if len == 0.0 {
                c
            } else {
                Point {
                    x: c.x + dx / len,
                    y: c.y + dy / len,
                }
            }
        }
        Shape::Box => {
            let (dx, dy) = (towards.x - c.x, towards.y - c.y);
            let sx = if dx == 0.0 {
                f64::INFINITY
            } else {
                (size.w / 2.0) / dx.abs()
            };
            let sy = if dy == 0.0 {
                f64::INFINITY
            } else {
                (size.h / 2.0) / dy.abs()
            };
            let s = sx.min(sy);
            if s.is_finite() {
                Point {
                    x: c.x + dx * s,
                    y: c.y + dy * s,
                }
            } else {
                c
            }
        }
    }
}

/// A point node's dot: under its label when layers go down (the edges then leave the label
/// alone), above it when they go right.
fn dot_centre(c: Point, size: Size, direction: Direction) -> Point {
    let y = match direction {
        Direction::TopDown => c.y + size.h / 2.0 - DOT - 1.0,
        Direction::LeftRight => c.y - size.h / 2.0 + DOT + 1.0,
    };
    Point { x: c.x, y }
}

/// The point `r` away from `from` towards `to`.
fn along(from: Point, to: Point, r: f64) -> Point {
    let (dx, dy) = (to.x - from.x, to.y - from.y);
    let len = (dx * dx + dy * dy).sqrt();
    if len == 0.0 {
        from
    } else {
        Point {
            x: from.x + dx / len * r,
            y: from.y + dy / len * r,
        }
    }
}

/// A smooth path through `points` (Catmull-Rom splines as cubic Béziers).
fn smooth(points: &[Point]) -> String {
    let mut d = format!("M{},{}", num(points[0].x), num(points[0].y));
    for i in 0..points.len() - 1 {
        let p0 = points[i.saturating_sub(1)];
        let p1 = points[i];
        let p2 = points[i + 1];
        let p3 = points[(i + 2).min(points.len() - 1)];
        let c1 = Point {
            x: p1.x + (p2.x - p0.x) / 6.0,
            y: p1.y + (p2.y - p0.y) / 6.0,
        };
        let c2 = Point {
            x: p2.x - (p3.x - p1.x) / 6.0,
            y: p2.y - (p3.y - p1.y) / 6.0,
        };
        let _ = write!(
            d,
            " C{},{} {},{} {},{}",
            num(c1.x),
            num(c1.y),
            num(c2.x),
            num(c2.y),
            num(p2.x),
            num(p2.y)
        );
    }
    d
}

fn draw_node(svg: &mut Svg, node: &Node, c: Point, size: Size, direction: Direction) {
    svg.open(&format!("node {}", node.class), Some(&node.id));
    let left = c.x - size.w / 2.0;
    let top = c.y - size.h / 2.0;
    let dash = if node.line == Line::Dashed { "5 3" } else { "" };
    let outline = Paint::filled(node.fill, "#444444").dash(dash);
    let title_font = Font::new(TITLE).bold().anchor(Anchor::Middle);
    match node.shape {
        Shape::Point => {
            let dot = dot_centre(c, size, direction);
            let w = text_width(&node.title, TEXT);
            let base = match direction {
                Direction::TopDown => top + TEXT,
                Direction::LeftRight => dot.y + DOT + TEXT,
            };
            svg.rect(
                c.x - w / 2.0 - 1.0,
                base - TEXT,
                w + 2.0,
                TEXT + 3.0,
                2.0,
                Paint::filled("#ffffff", "none"),
            );
            svg.ellipse(dot.x, dot.y, DOT, DOT, Paint::filled("#333333", "#333333"));
            svg.text(
                c.x,
                base,
                &node.title,
                Font::new(TEXT).anchor(Anchor::Middle),
            );
        }
        Shape::Ellipse => {
            svg.ellipse(c.x, c.y, size.w / 2.0, size.h / 2.0, outline);
            title_and_subtitle(svg, node, c, c.y + TITLE * 0.35);
        }
        Shape::DoubleCircle => {
            let r = size.w / 2.0;
            svg.ellipse(c.x, c.y, r, r, outline);
            svg.ellipse(c.x, c.y, r - 4.0, r - 4.0, Paint::stroke("#444444"));
            title_and_subtitle(svg, node, c, c.y + TITLE * 0.35);
        }
        Shape::Box => {
            svg.rect(left, top, size.w, size.h, 5.0, outline);
            if node.rows.is_empty() {
                title_and_subtitle(
                    svg,
                    node,
                    c,
                    c.y + TITLE * 0.35 - if node.subtitle.is_some() { 6.0 } else { 0.0 },
                );
            } else {
                svg.text(c.x, top + 15.0, &node.title, title_font);
                if let Some(sub) = &node.subtitle {
                    svg.text(
                        c.x,
                        top + 28.0,
                        sub,
                        Font::new(SMALL)
                            .italic()
                            .colour("#555555")
                            .anchor(Anchor::Middle),
                    );
                }
                let rule = top + head_height(node) - 2.0;
                svg.line(left, rule, left + size.w, rule, Paint::stroke("#999999"));
                for (k, row) in node.rows.iter().enumerate() {
                    let y = row_y(node, c, size, k);
                    svg.open(&format!("row {}", row.class), None);
                    svg.text(
                        left + PAD,
                        y + TEXT * 0.35,
                        &row.text,
                        Font::new(TEXT).colour(row.colour()),
                    );
                    svg.close();
                }
            }
        }
    }
    svg.close();
}

fn title_and_subtitle(svg: &mut Svg, node: &Node, c: Point, baseline: f64) {
    svg.text(
        c.x,
        baseline,
        &node.title,
        Font::new(TITLE).bold().anchor(Anchor::Middle),
    );
    if let Some(sub) = &node.subtitle {
        svg.text(
            c.x,
            baseline + 13.0,
            sub,
            Font::new(SMALL)
                .italic()
                .colour("#555555")
                .anchor(Anchor::Middle),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{Edge, Node};

    #[test]
    fn every_node_row_and_label_is_in_the_svg() {
        let mut g = Graph::new("g", "A & B", Direction::LeftRight);
        let mut m = Node::new("m", "module m", "module");
        let s = m.row("Service <1>", "activity");
        let a = g.add(m);
        let b = g.add(Node::new("c", "conn", "connector").shape(Shape::Point));
        let c = g.add(Node::new("d", "end", "state").shape(Shape::DoubleCircle));
        g.connect(Edge::new(End::row(a, s), End::node(b), "x").label("writes"));
        g.connect(Edge::new(End::node(b), End::node(c), "y").line(Line::Dashed));
        g.connect(Edge::new(End::node(c), End::node(a), "z"));
        g.connect(Edge::new(End::node(c), End::node(c), "loop").label("again"));
        let doc = to_svg(&g);
        let texts = crate::xml::read::texts(&doc);
        for want in [
            "A & B",
            "module m",
            "Service <1>",
            "conn",
            "end",
            "writes",
            "again",
        ] {
            assert!(
                texts.iter().any(|t| t == want),
                "{want} missing from {texts:?}"
            );
        }
        let classes = crate::xml::read::classes(&doc);
        let groups = |prefix: &str| classes.iter().filter(|c| c.starts_with(prefix)).count();
        assert_eq!(groups("node "), 3);
        assert_eq!(groups("edge "), 4);
    }
}
