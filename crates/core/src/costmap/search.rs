//! Forward search, for maps with obstacles: the minimum-time map computed systematically
//! instead of sampled. (Without obstacles `search` uses the backward method in
//! `backward.rs`, which has no heading to discretise and does much better.)

use super::grid::blocked;
use super::prepared::{Prepared, Segments};
use super::BuildInput;
use crate::motion::Walker;

/// How finely search tells states apart at branch nodes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SearchParams {
    /// Heading bins per turn.
    pub heading_bins: usize,
    /// Position bins per cell side.
    pub sub_cells: usize,
}

impl Default for SearchParams {
    fn default() -> Self {
        SearchParams {
            heading_bins: 64,
            sub_cells: 1,
        }
    }
}

/// A stretch of path: the state it continues from and `len` steps of the compressed
/// graph from step `from`.
#[derive(Clone, Copy)]
struct Stretch {
    parent: u32,
    from: u32,
    len: u32,
}

pub(crate) struct SearchResult {
    pub costs: Vec<Option<u32>>,
    /// Per cell, the stretch of path that first reached it.
    arrivals: Vec<Option<Stretch>>,
    /// Per expanded state, the stretch that led to it; state 0 is the start.
    states: Vec<Stretch>,
    segments: Segments,
    /// Graph edge ids from the start pose to the first branch node.
    lead: Vec<u32>,
    edge_ids: Vec<u32>,
}

#[derive(Clone, Copy)]
struct State {
    node: u32,
    at: Walker,
    index: u32,
}

/// Uniform-cost search over (branch node, position bin, heading bin) on the graph
/// compressed to segments between branch points, in order of frames (a bucket queue:
/// costs are whole frames up to `depth`).
///
/// A walk's only choices are at branch nodes, so states exist only there; every frame of
/// a segment still marks the cells it passes. Two walks that reach the same branch node
/// in the same position and heading bin continue identically up to that discretisation,
/// so only the first (cheapest) is expanded. Merging is the one approximation, and it
/// costs: a merged walk a few centimetres or degrees away might have reached some cell a
/// frame sooner, and small turns merged away do not add up. States only at branch nodes
/// merge far less than states at every frame would.
pub(crate) fn build(
    input: &BuildInput,
    graph: &Prepared,
    nodes: usize,
    depth: u32,
    params: SearchParams,
) -> SearchResult {
    let grid = &input.grid;
    let depth = depth as usize;
    let segments = graph.segments(nodes, true);
    let side = grid.n * params.sub_cells;
    let bins = params.heading_bins;
    let key = |node: u32, at: &Walker| -> Option<usize> {
        let rel = (at.position - grid.origin()) / (grid.cell_m / params.sub_cells as f64);
        let (x, z) = (rel.x.floor(), rel.y.floor());
        if x < 0.0 || z < 0.0 || x >= side as f64 || z >= side as f64 {
            return None;
        }
        let turn = at.heading().rem_euclid(std::f64::consts::TAU) / std::f64::consts::TAU;
        let bin = ((turn * bins as f64) as usize).min(bins - 1);
        Some(((node as usize * side + z as usize) * side + x as usize) * bins + bin)
    };
    let mut seen = vec![0u64; (nodes * side * side * bins).div_ceil(64)];
    let mut visit = |k: usize| -> bool {
        let (word, bit) = (k / 64, 1u64 << (k % 64));
        let fresh = seen[word] & bit == 0;
        seen[word] |= bit;
        fresh
    };
    let mut costs = vec![None; grid.cells()];
    let mut arrivals = vec![None; grid.cells()];
    let root = Stretch {
        parent: u32::MAX,
        from: 0,
        len: 0,
    };
    if let Some(c) = grid.cell_of(Walker::START.position) {
        costs[c] = Some(0);
        arrivals[c] = Some(root);
    }
    // A start inside a segment runs on to the segment's end: there is no choice before.
    let (mut node, mut at, mut t) = (input.start, Walker::START, 0usize);
    let mut lead = Vec::new();
    let mut open = true;
    while !segments.branch[node as usize] {
        let Some(e) = graph.out(node).first() else {
            open = false;
            break;
        };
        t += e.frames as usize;
        at = at.after(&e.step, e.turn);
        let cell = grid.cell_of(at.position);
        if t > depth || blocked(&input.obstacles, at.position) || cell.is_none() {
            open = false;
            break;
        }
        lead.push(e.id);
        node = e.to;
        if let Some(c) = cell.filter(|&c| costs[c].is_none_or(|v| (t as u32) < v)) {
            costs[c] = Some(t as u32);
            arrivals[c] = Some(Stretch {
                parent: u32::MAX,
                from: 0,
                len: lead.len() as u32,
            });
        }
    }
    let mut states = vec![root];
    let mut buckets: Vec<Vec<State>> = vec![Vec::new(); depth + 1];
    if open {
        if let Some(k) = key(node, &at) {
            visit(k);
        }
        buckets[t].push(State { node, at, index: 0 });
    }
    for t in 0..=depth {
        for s in std::mem::take(&mut buckets[t]) {
            for (from, len, to) in segments.out(s.node) {
                let (mut at, mut arrive, mut done) = (s.at, t, 0);
                for k in 0..len {
                    let e = graph.edge(segments.step(from + k));
                    let next = at.after(&e.step, e.turn);
                    if arrive + e.frames as usize > depth
                        || blocked(&input.obstacles, next.position)
                    {
                        break;
                    }
                    let Some(cell) = grid.cell_of(next.position) else {
                        break;
                    };
                    (at, arrive, done) = (next, arrive + e.frames as usize, k + 1);
                    if costs[cell].is_none_or(|c| (arrive as u32) < c) {
                        costs[cell] = Some(arrive as u32);
                        arrivals[cell] = Some(Stretch {
                            parent: s.index,
                            from: from as u32,
                            len: done as u32,
                        });
                    }
                }
                if done == len && key(to, &at).is_some_and(&mut visit) {
                    states.push(Stretch {
                        parent: s.index,
                        from: from as u32,
                        len: len as u32,
                    });
                    buckets[arrive].push(State {
                        node: to,
                        at,
                        index: states.len() as u32 - 1,
                    });
                }
            }
        }
    }
    let edge_ids = (0..graph.edge_count()).map(|i| graph.edge(i).id).collect();
    SearchResult {
        costs,
        arrivals,
        states,
        segments,
        lead,
        edge_ids,
    }
}

impl SearchResult {
    /// The graph edge ids of the path that first reached `cell` (empty if none did).
    pub(super) fn path(&self, cell: usize) -> Vec<u32> {
        let Some(last) = self.arrivals[cell] else {
            return Vec::new();
        };
        let mut stretches = vec![last];
        let mut parent = last.parent;
        while parent != u32::MAX && parent != 0 {
            let s = self.states[parent as usize];
            stretches.push(s);
            parent = s.parent;
        }
        let mut edges = if last.parent == u32::MAX && last.len > 0 {
            // A cell reached before the first branch node: part of the lead.
            return self.lead[..last.len as usize].to_vec();
        } else {
            self.lead.clone()
        };
        for s in stretches.iter().rev().filter(|s| s.parent != u32::MAX) {
            edges.extend(
                (s.from..s.from + s.len).map(|i| self.edge_ids[self.segments.step(i as usize)]),
            );
        }
        edges
    }
}
