//! `bip-picture`: bip's pictures, with no external program. A [`graph::Graph`] (nodes,
//! rows, edges, as plain data) is written as DOT ([`dot`]) or laid out by the project's
//! own layered layout ([`layout`]) and drawn as SVG ([`render`]); a sequence chart
//! ([`chart`]) draws a run across its participants, a [`timeline`] a run along its steps,
//! one lane per participant. [`xml::escape`] is the one XML escaping function of the
//! workspace.
//!
//! Modules import down these layers only (`tests/suite/layering.rs` checks it), lowest
//! first: `xml`; `svg`, `graph`; `layout`; `dot`, `render`, `chart`, `timeline`.

pub mod chart;
pub mod dot;
pub mod graph;
pub mod layout;
pub mod render;
pub mod svg;
pub mod timeline;
pub mod xml;

pub use graph::{Direction, Edge, End, Graph, Line, Node, Shape};
