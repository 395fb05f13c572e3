//! The declared priorities as a graph, whose reachability is their transitive closure.
//!
//! A priority names two ranges of interactions (a connector's instances, or one of them).
//! Cutting the interactions at the ends of every range gives *groups*: intervals whose
//! interactions every priority treats alike. A priority leads from each group of its
//! `low` side to each group of its `high` side, and the closure of docs/model.md
//! ("Priorities") is reachability: an interaction is below another under the closure when
//! a path of priorities leads from its group to the other's, under the `when`s along the
//! path. The closure itself is never listed: it grows with the square of the declared
//! relation (a GenoM layer orders its activities in one long chain), while the graph keeps
//! the priorities as nodes between the groups (a group leads to the priorities with it on
//! their low side, a priority to the groups of its high side) and so has the size of what
//! the file declares, however many groups a side spans. [`crate::System`] decides
//! suppression from it: with the masks of `priority_masks` where they fit, and by a search
//! per state for the rest (`suppression`).
//!
//! The order is Kahn's algorithm written here on these range sides, not petgraph's
//! `toposort` on a graph with an edge per incidence: on 2,999 priorities with 2 million
//! incidences (`bip check`, release), that took 0.35 s and 59 MB against 0.12 s and 23 MB.

#[allow(unused_imports)]
use crate::prelude::*;

use core::ops::Range;

use crate::model::Priority;

/// The most (group, priority) incidences a graph may have: sides that span many groups
/// (priorities on single instances cut a family into groups; a priority on the whole
/// family then meets each) make this grow with the product of the two kinds.
pub const MAX_INCIDENCES: u64 = 1 << 22;

#[derive(Clone, Debug, Default)]
pub struct PriorityGraph {
    /// Group `g` is the interactions `cuts[g]..cuts[g + 1]`.
    cuts: Vec<u32>,
    /// Per group `g`, the priorities with it on their low side:
    /// `below[below_at[g]..below_at[g + 1]]`, in declaration order.
    below_at: Vec<u32>,
    below: Vec<u32>,
    /// Per priority, its sides as ranges of groups.
    low: Vec<(u32, u32)>,
    high: Vec<(u32, u32)>,
    /// The groups, each after every group above it; those on a cycle or below one are
    /// left out.
    order: Vec<u32>,
    /// Priorities forming a cycle, if any.
    cycle: Option<Vec<u32>>,
    /// The most priorities along one path.
    depth: u32,
}

/// The ends of every non-empty side, sorted, without repeats.
fn cuts_of(priorities: &[Priority]) -> Vec<u32> {
    let mut cuts: Vec<u32> = priorities
        .iter()
        .flat_map(|p| [p.low.clone(), p.high.clone()])
        .filter(|r| r.start < r.end)
        .flat_map(|r| [r.start, r.end])
        .collect();
    cuts.sort_unstable();
    cuts.dedup();
    cuts
}

/// The groups of `side` (the groups between its two ends, which are cuts).
fn groups_of(cuts: &[u32], side: &Range<u32>) -> (u32, u32) {
    if side.start >= side.end {
        return (0, 0);
    }
    let at = |x: u32| cuts.partition_point(|&c| c < x) as u32;
    (at(side.start), at(side.end))
}

impl PriorityGraph {
    /// How many (group, priority) incidences the graph of `priorities` has: its size, and
    /// the work of building it, known before it is built.
    pub fn incidences(priorities: &[Priority]) -> u64 {
        let cuts = cuts_of(priorities);
        priorities
            .iter()
            .map(|p| {
                let (a, b) = groups_of(&cuts, &p.low);
                let (c, d) = groups_of(&cuts, &p.high);
                u64::from(b - a) + u64::from(d - c)
            })
            .sum()
    }

    /// The graph of `priorities`, with its order and, if they form one, a cycle.
    pub fn new(priorities: &[Priority]) -> PriorityGraph {
        let cuts = cuts_of(priorities);
        let groups = cuts.len().saturating_sub(1);
        let low: Vec<(u32, u32)> = priorities
            .iter()
            .map(|p| groups_of(&cuts, &p.low))
            .collect();
        let high: Vec<(u32, u32)> = priorities
            .iter()
            .map(|p| groups_of(&cuts, &p.high))
            .collect();
        let (below_at, below) = lists(groups, &low);
        let mut g = PriorityGraph {
            cuts,
            below_at,
            below,
            low,
            high,
            ..PriorityGraph::default()
        };
        g.sort();
        g
    }

    /// Orders the groups highest first (Kahn's algorithm on groups and priorities), with
    /// the length of the longest chain; what is left over lies on a cycle or below one.
    fn sort(&mut self) {
        let groups = self.groups() as usize;
        let (above_at, above) = lists(groups, &self.high);
        // what is left to place above each group, and above each priority
        let mut left_g: Vec<u32> = (0..groups)
            .map(|g| self.below_at[g + 1] - self.below_at[g])
            .collect();
        let mut left_p: Vec<u32> = self.high.iter().map(|&(a, b)| b - a).collect();
        // the most priorities on a path up from a group, and from a priority (itself included)
        let mut depth_g = vec![0u32; groups];
        let mut depth_p = vec![1u32; self.high.len()];
        let mut ready: Vec<u32> = (0..groups as u32)
            .filter(|&g| left_g[g as usize] == 0)
            .collect();
        // a priority with an empty high side is placed at once
        let mut placed = Vec::new();
        for (p, &n) in left_p.iter().enumerate() {
            if n == 0 {
                placed.push(p as u32);
            }
        }
        let mut order = Vec::with_capacity(groups);
        loop {
            while let Some(p) = placed.pop() {
                let (a, b) = self.low[p as usize];
                for g in a..b {
                    let d = &mut depth_g[g as usize];
                    *d = (*d).max(depth_p[p as usize]);
                    left_g[g as usize] -= 1;
                    if left_g[g as usize] == 0 {
                        ready.push(g);
                    }
                }
            }
            let Some(g) = ready.pop() else { break };
            order.push(g);
            for &p in &above[above_at[g as usize] as usize..above_at[g as usize + 1] as usize] {
                let d = &mut depth_p[p as usize];
                *d = (*d).max(depth_g[g as usize] + 1);
                left_p[p as usize] -= 1;
                if left_p[p as usize] == 0 {
                    placed.push(p);
                }
            }
        }
        self.depth = depth_g.iter().copied().max().unwrap_or(0);
        if order.len() < groups {
            let mut done = vec![false; groups];
            for &g in &order {
                done[g as usize] = true;
            }
            self.cycle = Some(self.find_cycle(&done, &left_p));
        }
        self.order = order;
    }

    /// A cycle among the groups left unordered: each has a priority not placed above it,
    /// which has a group not placed on its high side, so a walk from one never ends and
    /// comes back to a group it passed.
    fn find_cycle(&self, done: &[bool], left_p: &[u32]) -> Vec<u32> {
        let mut at = vec![u32::MAX; done.len()];
        let mut walk: Vec<u32> = Vec::new();
        let mut g = done.iter().position(|&d| !d).unwrap_or(0) as u32;
        loop {
            if at[g as usize] != u32::MAX {
                return walk[at[g as usize] as usize..].to_vec();
            }
            at[g as usize] = walk.len() as u32;
            let next = self.below(g).iter().find_map(|&p| {
                let (a, b) = self.high[p as usize];
                let z = (left_p[p as usize] > 0)
                    .then(|| (a..b).find(|&z| !done[z as usize]))
                    .flatten()?;
                Some((p, z))
            });
            let Some((p, z)) = next else {
                // (cannot happen: an unordered group has such a priority)
                return walk;
            };
            walk.push(p);
            g = z;
        }
    }

    /// How many groups there are.
    pub fn groups(&self) -> u32 {
        self.cuts.len().saturating_sub(1) as u32
    }

    /// The interactions of group `g`.
    pub fn interactions(&self, g: u32) -> Range<u32> {
        self.cuts[g as usize]..self.cuts[g as usize + 1]
    }

    /// The group of interaction `i`, if a priority names it.
    pub fn group_of(&self, i: u32) -> Option<u32> {
        let g = self.cuts.partition_point(|&c| c <= i);
        (g > 0 && g < self.cuts.len()).then(|| g as u32 - 1)
    }

    /// The priorities with group `g` on their low side, in declaration order.
    pub fn below(&self, g: u32) -> &[u32] {
        let (a, b) = (self.below_at[g as usize], self.below_at[g as usize + 1]);
        &self.below[a as usize..b as usize]
    }

    /// The groups of priority `p`'s high side.
    pub fn high_groups(&self, p: u32) -> Range<u32> {
        let (a, b) = self.high[p as usize];
        a..b
    }

    /// The groups of priority `p`'s low side.
    pub fn low_groups(&self, p: u32) -> Range<u32> {
        let (a, b) = self.low[p as usize];
        a..b
    }

    /// The groups, each after every group above it (none is missing in an acyclic graph).
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// Priorities that form a cycle, each one's high side meeting the next one's low side
    /// and the last one's the first one's; `None` if there is no cycle.
    pub fn cycle(&self) -> Option<&[u32]> {
        self.cycle.as_deref()
    }

    /// The most priorities one chain of the closure goes through.
    pub fn depth(&self) -> u32 {
        self.depth
    }
}

/// Per group, the priorities whose `sides` include it, as offsets and a list.
fn lists(groups: usize, sides: &[(u32, u32)]) -> (Vec<u32>, Vec<u32>) {
    let mut at = vec![0u32; groups + 1];
    for &(a, b) in sides {
        for g in a..b {
            at[g as usize + 1] += 1;
        }
    }
    for g in 0..groups {
        at[g + 1] += at[g];
    }
    let mut fill = at.clone();
    let mut list = vec![0u32; at[groups] as usize];
    for (p, &(a, b)) in sides.iter().enumerate() {
        for g in a..b {
            list[fill[g as usize] as usize] = p as u32;
            fill[g as usize] += 1;
        }
    }
    (at, list)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn prio(low: Range<u32>, high: Range<u32>) -> Priority {
        Priority {
            low,
            high,
            when: None,
            text: String::new(),
        }
    }

    #[test]
    fn groups_cut_at_every_side() {
        // 0..4 < 4..6, 2..3 < 0..1
        let g = PriorityGraph::new(&[prio(0..4, 4..6), prio(2..3, 0..1)]);
        let groups: Vec<Range<u32>> = (0..g.groups()).map(|k| g.interactions(k)).collect();
        assert_eq!(groups, vec![0..1, 1..2, 2..3, 3..4, 4..6]);
        assert_eq!(g.group_of(5), Some(4));
        assert_eq!(g.group_of(6), None);
        assert_eq!(g.below(2), &[0, 1]);
        assert_eq!(g.high_groups(0), 4..5);
        assert!(g.cycle().is_none());
        assert_eq!(g.order().len(), 5);
        // 2..3 < 0..1 < 4..6
        assert_eq!(g.depth(), 2);
        assert_eq!(
            PriorityGraph::incidences(&[prio(0..4, 4..6), prio(2..3, 0..1)]),
            7
        );
    }

    #[test]
    fn order_puts_higher_groups_first() {
        let g = PriorityGraph::new(&[prio(0..1, 1..2), prio(1..2, 2..3), prio(0..1, 2..3)]);
        assert_eq!(g.order(), &[2, 1, 0]);
        assert_eq!(g.depth(), 2);
    }

    #[test]
    fn cycles_are_found() {
        // 0 < 1 < 2 < 0, and 3 < 0 below the cycle
        let g = PriorityGraph::new(&[
            prio(3..4, 0..1),
            prio(0..1, 1..2),
            prio(1..2, 2..3),
            prio(2..3, 0..1),
        ]);
        let mut c = g.cycle().expect("a cycle").to_vec();
        c.sort_unstable();
        assert_eq!(c, vec![1, 2, 3]);
        assert!(g.order().is_empty());
        // a side that meets itself
        let g = PriorityGraph::new(&[prio(0..1, 0..3)]);
        assert_eq!(g.cycle(), Some(&[0][..]));
    }
}
