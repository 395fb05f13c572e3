//! A layered (Sugiyama-style) layout of a directed graph: cycles broken by reversing the
//! edges a depth-first search finds going back; layers by longest path; long edges cut
//! into chains of dummy nodes; the order within each layer by barycentre sweeps, keeping
//! the order with the fewest crossings; coordinates by pulling each node towards the
//! mean of its neighbours while keeping the order and the gaps.
//!
//! Every edge spans at least two layers, so that its middle is a dummy node: a labelled
//! edge's dummy is as large as its label, and the label is drawn there without overlap.
//! It is meant for pictures of a few hundred nodes, in well under a second.

use std::collections::HashSet;

use petgraph::algo::toposort;
use petgraph::graph::{DiGraph, NodeIndex};
use petgraph::visit::{depth_first_search, DfsEvent};
use petgraph::Direction::Incoming;

use crate::graph::Direction;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Size {
    pub w: f64,
    pub h: f64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    pub x: f64,
    pub y: f64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayoutEdge {
    pub from: usize,
    pub to: usize,
    /// The size of the edge's label, if it has one.
    pub label: Option<Size>,
}

/// Where everything goes: node centres, each edge's bends in its own direction (without
/// its ends; none for a self-loop), each label's centre.
#[derive(Clone, Debug, PartialEq)]
pub struct Placed {
    pub nodes: Vec<Point>,
    pub bends: Vec<Vec<Point>>,
    pub labels: Vec<Option<Point>>,
    pub width: f64,
    pub height: f64,
}

/// Space between neighbours in a layer, and between layers.
const NODE_GAP: f64 = 24.0;
const LAYER_GAP: f64 = 26.0;
const DUMMY: f64 = 8.0;
const SWEEPS: usize = 24;
const PULLS: usize = 12;

struct Virtual {
    layer: usize,
    /// Across the layer, then along the layers.
    w: f64,
    h: f64,
}

/// Lays `sizes` (one per node) out with `edges`, layers going in `direction`.
pub fn layered(sizes: &[Size], edges: &[LayoutEdge], direction: Direction) -> Placed {
    let across = |s: Size| match direction {
        Direction::TopDown => (s.w, s.h),
        Direction::LeftRight => (s.h, s.w),
    };
    let n = sizes.len();
    let reversed = back_edges(n, edges);
    let dag: Vec<Option<(usize, usize)>> = edges
        .iter()
        .zip(&reversed)
        .map(|(e, &r)| match (e.from == e.to, r) {
            (true, _) => None,
            (false, false) => Some((e.from, e.to)),
            (false, true) => Some((e.to, e.from)),
        })
        .collect();
    let layer = layers(n, &dag);

    let mut nodes: Vec<Virtual> = sizes
        .iter()
        .zip(&layer)
        .map(|(&s, &l)| {
            let (w, h) = across(s);
            Virtual { layer: l, w, h }
        })
        .collect();
    let mut chains: Vec<Vec<usize>> = vec![Vec::new(); edges.len()];
    let mut label_at: Vec<Option<usize>> = vec![None; edges.len()];
    let mut links: Vec<(usize, usize)> = Vec::new();
    for (e, pair) in dag.iter().enumerate() {
        let Some((a, b)) = *pair else { continue };
        let (la, lb) = (layer[a], layer[b]);
        let middle = (la + lb) / 2;
        let mut prev = a;
        for l in la + 1..lb {
            let (w, h) = match (l == middle, edges[e].label) {
                (true, Some(s)) => across(s),
                _ => (DUMMY, 0.0),
            };
            nodes.push(Virtual { layer: l, w, h });
            let d = nodes.len() - 1;
            if l == middle {
                label_at[e] = Some(d);
            }
            chains[e].push(d);
            links.push((prev, d));
            prev = d;
        }
        links.push((prev, b));
    }

    let depth = nodes.iter().map(|v| v.layer + 1).max().unwrap_or(0);
    let mut rows: Vec<Vec<usize>> = vec![Vec::new(); depth];
    for (v, node) in nodes.iter().enumerate() {
        rows[node.layer].push(v);
    }
    let mut preds = vec![Vec::new(); nodes.len()];
    let mut succs = vec![Vec::new(); nodes.len()];
    for &(a, b) in &links {
        succs[a].push(b);
        preds[b].push(a);
    }
    order(&mut rows, &preds, &succs);
    let x = positions(&rows, &nodes, &preds, &succs);

    let mut y = vec![0.0; nodes.len()];
    let mut top = 0.0;
    for row in &rows {
        let thick = row.iter().map(|&v| nodes[v].h).fold(0.0, f64::max);
        for &v in row {
            y[v] = top + thick / 2.0;
        }
        top += thick + LAYER_GAP;
    }
    let extent = nodes
        .iter()
        .enumerate()
        .map(|(v, node)| x[v] + node.w / 2.0)
        .fold(0.0, f64::max);
    let at = |v: usize| match direction {
        Direction::TopDown => Point { x: x[v], y: y[v] },
        Direction::LeftRight => Point { x: y[v], y: x[v] },
    };
    let bends = chains
        .iter()
        .zip(&reversed)
        .map(|(chain, &r)| {
            let mut points: Vec<Point> = chain.iter().map(|&d| at(d)).collect();
            if r {
                points.reverse();
            }
            points
        })
        .collect();
    let along = (top - LAYER_GAP).max(0.0);
    let (width, height) = match direction {
        Direction::TopDown => (extent, along),
        Direction::LeftRight => (along, extent),
    };
    Placed {
        nodes: (0..n).map(at).collect(),
        bends,
        labels: label_at.iter().map(|d| d.map(at)).collect(),
        width,
        height,
    }
}

/// For each edge, whether a depth-first search (from the nodes in order, each node's
/// edges in order) meets it going back to a node on its stack: reversing those leaves no
/// cycle.
fn back_edges(n: usize, edges: &[LayoutEdge]) -> Vec<bool> {
    let mut graph = DiGraph::<(), ()>::with_capacity(n, edges.len());
    for _ in 0..n {
        graph.add_node(());
    }
    // petgraph lists a node's edges last added first
    for e in edges.iter().rev() {
        graph.add_edge(NodeIndex::new(e.from), NodeIndex::new(e.to), ());
    }
    let mut back = HashSet::new();
    depth_first_search(&graph, graph.node_indices(), |event| {
        if let DfsEvent::BackEdge(u, v) = event {
            back.insert((u.index(), v.index()));
        }
    });
    // parallel edges are all back or all not: the first makes its end finish
    edges
        .iter()
        .map(|e| e.from != e.to && back.contains(&(e.from, e.to)))
        .collect()
}

/// Each node's layer: even layers only (every edge then has a middle), by longest path
/// from the sources; a source is then moved down next to its nearest successor.
fn layers(n: usize, dag: &[Option<(usize, usize)>]) -> Vec<usize> {
    let mut graph = DiGraph::<(), ()>::with_capacity(n, dag.len());
    for _ in 0..n {
        graph.add_node(());
    }
    for &(a, b) in dag.iter().flatten() {
        graph.add_edge(NodeIndex::new(a), NodeIndex::new(b), ());
    }
    let topo = toposort(&graph, None).expect("reversing the back edges leaves no cycle");
    let mut layer = vec![0usize; n];
    for &v in &topo {
        for s in graph.neighbors(v) {
            layer[s.index()] = layer[s.index()].max(layer[v.index()] + 2);
        }
    }
    // only a source moves, and a source is nobody's successor: the order does not matter
    for v in graph.externals(Incoming) {
        if let Some(nearest) = graph.neighbors(v).map(|s| layer[s.index()]).min() {
            layer[v.index()] = nearest - 2;
        }
    }
    layer
}

/// Orders each layer by barycentre sweeps, down and up, keeping the best order seen.
fn order(rows: &mut [Vec<usize>], preds: &[Vec<usize>], succs: &[Vec<usize>]) {
    let mut pos = vec![0.0f64; preds.len()];
    let index = |rows: &[Vec<usize>], pos: &mut Vec<f64>| {
        for row in rows {
            for (k, &v) in row.iter().enumerate() {
                pos[v] = k as f64;
            }
        }
    };
    index(rows, &mut pos);
    let mut best = rows.to_vec();
    let mut fewest = crossings(rows, succs, &pos);
    for sweep in 0..SWEEPS {
        if fewest == 0 {
            break;
        }
        let down = sweep % 2 == 0;
        let count = rows.len();
        for step in 1..count {
            let l = if down { step } else { count - 1 - step };
            let next = if down { preds } else { succs };
            let mut keyed: Vec<(f64, usize)> = rows[l]
                .iter()
                .map(|&v| {
                    let ns = &next[v];
                    let key = if ns.is_empty() {
                        pos[v]
                    } else {
                        ns.iter().map(|&u| pos[u]).sum::<f64>() / ns.len() as f64
                    };
                    (key, v)
                })
                .collect();
            keyed.sort_by(|a, b| a.0.total_cmp(&b.0));
            rows[l] = keyed.into_iter().map(|(_, v)| v).collect();
            for (k, &v) in rows[l].iter().enumerate() {
                pos[v] = k as f64;
            }
        }
        let now = crossings(rows, succs, &pos);
        if now < fewest {
            fewest = now;
            best = rows.to_vec();
        }
    }
    rows.clone_from_slice(&best);
}

/// Edge crossings between consecutive layers: for each layer, the edges sorted by their
/// ends' positions, the inversions among their lower ends (counted with a Fenwick tree,
/// in O(E log V), so that a wide graph is not quadratic).
fn crossings(rows: &[Vec<usize>], succs: &[Vec<usize>], pos: &[f64]) -> usize {
    let mut total = 0;
    for row in rows {
        let mut pairs: Vec<(usize, usize)> = Vec::new();
        for &u in row {
            for &v in &succs[u] {
                pairs.push((pos[u] as usize, pos[v] as usize));
            }
        }
        pairs.sort_unstable();
        let size = pairs.iter().map(|p| p.1 + 1).max().unwrap_or(0);
        let mut tree = vec![0usize; size + 1];
        for (seen, &(_, v)) in pairs.iter().enumerate() {
            // edges seen so far whose lower end is at most v
            let mut at_most = 0;
            let mut i = v + 1;
            while i > 0 {
                at_most += tree[i];
                i &= i - 1;
            }
            total += seen - at_most;
            let mut i = v + 1;
            while i <= size {
                tree[i] += 1;
                i += i & i.wrapping_neg();
            }
        }
    }
    total
}

/// Coordinates across the layers: packed, then pulled towards the neighbours' mean. The
/// placement of one layer is the mean of two solutions that keep order and gaps, one
/// pushing right from the wished positions and one pushing left; their mean keeps them too.
fn positions(
    rows: &[Vec<usize>],
    nodes: &[Virtual],
    preds: &[Vec<usize>],
    succs: &[Vec<usize>],
) -> Vec<f64> {
    let mut x = vec![0.0f64; nodes.len()];
    for row in rows {
        let mut at = 0.0;
        for &v in row {
            x[v] = at + nodes[v].w / 2.0;
            at += nodes[v].w + NODE_GAP;
        }
    }
    let gap = |a: usize, b: usize| (nodes[a].w + nodes[b].w) / 2.0 + NODE_GAP;
    for pull in 0..PULLS {
        let down = pull % 2 == 0;
        let count = rows.len();
        for step in 0..count {
            let row = &rows[if down { step } else { count - 1 - step }];
            if row.is_empty() {
                continue;
            }
            let wish: Vec<f64> = row
                .iter()
                .map(|&v| {
                    let ns: Vec<usize> = preds[v].iter().chain(&succs[v]).copied().collect();
                    if ns.is_empty() {
                        x[v]
                    } else {
                        ns.iter().map(|&u| x[u]).sum::<f64>() / ns.len() as f64
                    }
                })
                .collect();
            let k = row.len();
            let mut right = wish.clone();
            for i in 1..k {
                right[i] = right[i].max(right[i - 1] + gap(row[i - 1], row[i]));
            }
            let mut left = wish;
            for i in (0..k - 1).rev() {
                left[i] = left[i].min(left[i + 1] - gap(row[i], row[i + 1]));
            }
            for i in 0..k {
                x[row[i]] = (right[i] + left[i]) / 2.0;
            }
        }
    }
    let min = nodes
        .iter()
        .enumerate()
        .map(|(v, node)| x[v] - node.w / 2.0)
        .fold(f64::INFINITY, f64::min);
    if min.is_finite() {
        for v in &mut x {
            *v -= min;
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Numbers below a bound, from a xorshift generator seeded with `seed`.
    fn xorshift(mut seed: u64) -> impl FnMut(usize) -> usize {
        move |bound| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % bound as u64) as usize
        }
    }

    /// On graphs drawn at random (parallel edges and self-loops included), reversing the
    /// back edges leaves no cycle, and an edge is reversed only if it closes one.
    #[test]
    fn reversing_the_back_edges_leaves_a_dag() {
        let mut next = xorshift(0x2545_f491_4f6c_dd1d);
        for _ in 0..500 {
            let n = 1 + next(8);
            let edges: Vec<LayoutEdge> = (0..next(16)).map(|_| edge(next(n), next(n))).collect();
            let back = back_edges(n, &edges);
            let mut graph = DiGraph::<(), ()>::new();
            for _ in 0..n {
                graph.add_node(());
            }
            for (e, &b) in edges.iter().zip(&back) {
                let (a, z) = if b { (e.to, e.from) } else { (e.from, e.to) };
                if a != z {
                    graph.add_edge(NodeIndex::new(a), NodeIndex::new(z), ());
                }
            }
            assert!(
                toposort(&graph, None).is_ok(),
                "{edges:?} reversed {back:?}"
            );
            let original =
                DiGraph::<(), ()>::from_edges(edges.iter().map(|e| (e.from as u32, e.to as u32)));
            for (e, &b) in edges.iter().zip(&back) {
                let closes = petgraph::algo::has_path_connecting(
                    &original,
                    NodeIndex::new(e.to),
                    NodeIndex::new(e.from),
                    None,
                );
                assert!(!b || closes, "{e:?} is reversed but closes no cycle");
            }
        }
    }

    fn edge(from: usize, to: usize) -> LayoutEdge {
        LayoutEdge {
            from,
            to,
            label: None,
        }
    }

    const BOX: Size = Size { w: 40.0, h: 20.0 };

    fn overlap(p: &Placed, sizes: &[Size]) -> bool {
        (0..sizes.len()).any(|a| {
            (a + 1..sizes.len()).any(|b| {
                (p.nodes[a].x - p.nodes[b].x).abs() < (sizes[a].w + sizes[b].w) / 2.0
                    && (p.nodes[a].y - p.nodes[b].y).abs() < (sizes[a].h + sizes[b].h) / 2.0
            })
        })
    }

    #[test]
    fn a_chain_goes_down_and_a_cycle_is_laid_out() {
        let sizes = [BOX; 3];
        let p = layered(
            &sizes,
            &[edge(0, 1), edge(1, 2), edge(2, 0)],
            Direction::TopDown,
        );
        assert!(p.nodes[0].y < p.nodes[1].y && p.nodes[1].y < p.nodes[2].y);
        assert!(!overlap(&p, &sizes));
        // the edge going back up has its bends listed from its source to its target
        let back = &p.bends[2];
        assert!(back.first().unwrap().y >= back.last().unwrap().y);
    }

    #[test]
    fn barycentres_remove_an_avoidable_crossing() {
        // 0 -> 3, 1 -> 2 cross in input order; the sweep uncrosses them
        let sizes = [BOX; 4];
        let edges = [edge(0, 3), edge(1, 2)];
        let p = layered(&sizes, &edges, Direction::TopDown);
        assert_eq!(p.nodes[0].x < p.nodes[1].x, p.nodes[3].x < p.nodes[2].x);
    }

    #[test]
    fn left_right_puts_layers_in_columns_and_labels_between() {
        let sizes = [BOX; 2];
        let label = Size { w: 60.0, h: 14.0 };
        let edges = [LayoutEdge {
            from: 0,
            to: 1,
            label: Some(label),
        }];
        let p = layered(&sizes, &edges, Direction::LeftRight);
        let at = p.labels[0].expect("a labelled edge has a label place");
        assert!(p.nodes[0].x + BOX.w / 2.0 <= at.x - label.w / 2.0);
        assert!(at.x + label.w / 2.0 <= p.nodes[1].x - BOX.w / 2.0);
        assert!(p.width >= 2.0 * BOX.w + label.w);
    }

    #[test]
    fn crossings_are_the_pairs_of_edges_whose_ends_are_in_opposite_orders() {
        let mut next = xorshift(12345);
        for _ in 0..50 {
            let (a, b) = (1 + next(6), 1 + next(6));
            let rows = vec![(0..a).collect::<Vec<_>>(), (a..a + b).collect()];
            let mut succs = vec![Vec::new(); a + b];
            for _ in 0..next(12) {
                succs[next(a)].push(a + next(b));
            }
            let mut pos = vec![0.0; a + b];
            for row in &rows {
                for (k, &v) in row.iter().enumerate() {
                    pos[v] = k as f64;
                }
            }
            let edges: Vec<(f64, f64)> = (0..a)
                .flat_map(|u| succs[u].iter().map(move |&v| (u, v)))
                .map(|(u, v)| (pos[u], pos[v]))
                .collect();
            let quadratic = edges
                .iter()
                .enumerate()
                .flat_map(|(i, x)| edges[i + 1..].iter().map(move |y| (x, y)))
                .filter(|(x, y)| (x.0 - y.0) * (x.1 - y.1) < 0.0)
                .count();
            assert_eq!(crossings(&rows, &succs, &pos), quadratic);
        }
    }

    #[test]
    fn self_loops_and_isolated_nodes_are_placed_apart() {
        let sizes = [BOX; 5];
        let p = layered(&sizes, &[edge(0, 0), edge(1, 2)], Direction::TopDown);
        assert!(p.bends[0].is_empty());
        assert!(!overlap(&p, &sizes));
    }
}
