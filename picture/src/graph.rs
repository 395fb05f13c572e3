//! A graph to draw, as plain data: nodes (a title and optional rows, each row a place an
//! edge may attach to) and edges with a style. The DOT writer and the SVG renderer both
//! read it, so a picture and its DOT source always show the same thing.

/// Which way the layers of a layered drawing go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    TopDown,
    LeftRight,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// A rectangle with rounded corners; with rows, a table whose first line is the title.
    Box,
    Ellipse,
    /// A small filled dot, its title beside it.
    Point,
    /// A circle drawn twice: an end state.
    DoubleCircle,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Line {
    Solid,
    Dashed,
    Dotted,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Row {
    pub text: String,
    /// A class for the row (`service`, `port`, …): it names what the row stands for in
    /// the SVG and colours it.
    pub class: String,
}

impl Row {
    /// Rows are coloured by what they stand for, so a module's parts read apart at a
    /// glance.
    pub fn colour(&self) -> &'static str {
        match self.class.as_str() {
            "task" => "#7a4f01",
            "port" => "#1d5e8c",
            "activity" => "#1f6e2e",
            _ => "#222222",
        }
    }
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Node {
    /// Unique in its graph.
    pub id: String,
    pub title: String,
    /// A smaller line under the title (a type, a kind).
    pub subtitle: Option<String>,
    pub rows: Vec<Row>,
    pub shape: Shape,
    /// What the node stands for (`module`, `component`, `connector`, …): the SVG group's
    /// class.
    pub class: String,
    pub fill: &'static str,
    pub line: Line,
}

impl Node {
    pub fn new(id: impl Into<String>, title: impl Into<String>, class: &str) -> Self {
        Node {
            id: id.into(),
            title: title.into(),
            subtitle: None,
            rows: Vec::new(),
            shape: Shape::Box,
            class: class.to_string(),
            fill: "#ffffff",
            line: Line::Solid,
        }
    }

    pub fn shape(mut self, shape: Shape) -> Self {
        self.shape = shape;
        self
    }

    pub fn fill(mut self, fill: &'static str) -> Self {
        self.fill = fill;
        self
    }

    pub fn subtitle(mut self, text: impl Into<String>) -> Self {
        self.subtitle = Some(text.into());
        self
    }

    pub fn line(mut self, line: Line) -> Self {
        self.line = line;
        self
    }

    /// Adds a row and returns its index, to attach edges to.
    pub fn row(&mut self, text: impl Into<String>, class: &str) -> usize {
        self.rows.push(Row {
            text: text.into(),
            class: class.to_string(),
        });
        self.rows.len() - 1
    }
}

/// One end of an edge: a node, or one of its rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct End {
    pub node: usize,
    pub row: Option<usize>,
}

impl End {
    pub fn node(node: usize) -> Self {
        End { node, row: None }
    }

    pub fn row(node: usize, row: usize) -> Self {
        End {
            node,
            row: Some(row),
        }
    }
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Edge {
    pub from: End,
    pub to: End,
    pub label: Option<String>,
    pub line: Line,
    /// False for a relation without a direction (drawn without arrowhead).
    pub directed: bool,
    pub colour: &'static str,
    pub bold: bool,
    /// What the edge stands for (`writes`, `constraint`, `priority`, …).
    pub class: String,
}

impl Edge {
    pub fn new(from: End, to: End, class: &str) -> Self {
        Edge {
            from,
            to,
            label: None,
            line: Line::Solid,
            directed: true,
            colour: "#333333",
            bold: false,
            class: class.to_string(),
        }
    }

    pub fn label(mut self, label: impl Into<String>) -> Self {
        self.label = Some(label.into());
        self
    }

    pub fn line(mut self, line: Line) -> Self {
        self.line = line;
        self
    }

    pub fn undirected(mut self) -> Self {
        self.directed = false;
        self
    }

    pub fn colour(mut self, colour: &'static str) -> Self {
        self.colour = colour;
        self
    }

    pub fn bold(mut self) -> Self {
        self.bold = true;
        self
    }
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Graph {
    /// The graph's name in DOT.
    pub name: String,
    /// A heading drawn above the picture.
    pub title: String,
    pub direction: Direction,
    pub nodes: Vec<Node>,
    pub edges: Vec<Edge>,
}

impl Graph {
    pub fn new(name: impl Into<String>, title: impl Into<String>, direction: Direction) -> Self {
        Graph {
            name: name.into(),
            title: title.into(),
            direction,
            nodes: Vec::new(),
            edges: Vec::new(),
        }
    }

    /// Adds a node and returns its index.
    pub fn add(&mut self, node: Node) -> usize {
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    pub fn connect(&mut self, edge: Edge) {
        self.edges.push(edge);
    }

    /// The index of the node with this id.
    pub fn find(&self, id: &str) -> Option<usize> {
        self.nodes.iter().position(|n| n.id == id)
    }
}
