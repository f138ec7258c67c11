//! Beyond the paper: the minimum-time map computed systematically instead of sampled.

use super::grid::blocked;
use super::prepared::Prepared;
use super::walker::Walker;
use super::BuildInput;

/// How finely search tells states apart.
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
            heading_bins: 16,
            sub_cells: 2,
        }
    }
}

pub(crate) struct SearchResult {
    pub costs: Vec<Option<u32>>,
    /// Per cell, the arena index of the state that reached it first.
    pub arrivals: Vec<u32>,
    /// Every state expanded: (parent arena index, edge id); the start has parent u32::MAX.
    pub arena: Vec<(u32, u32)>,
}

#[derive(Clone, Copy)]
struct State {
    node: u32,
    at: Walker,
    arena: u32,
}

/// Uniform-cost search over (motion-graph node, position bin, heading bin), in order of
/// frames (a bucket queue: costs are whole frames up to `depth`).
///
/// Two walks that reach the same node in the same position and heading bin continue
/// identically up to that discretisation, so only the first (cheapest) is expanded. That
/// is the only approximation: a later walk a few centimetres away might have reached some
/// cell a frame sooner. With two position bins per cell side and 16 heading bins the
/// tests find search at least as cheap as 200,000 Monte Carlo walks in over 99 % of cells.
pub(crate) fn build(
    input: &BuildInput,
    graph: &Prepared,
    nodes: usize,
    depth: u32,
    params: SearchParams,
) -> SearchResult {
    let grid = &input.grid;
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
    let mut arrivals = vec![u32::MAX; grid.cells()];
    let mut arena = vec![(u32::MAX, u32::MAX)];
    let start = State {
        node: input.start,
        at: Walker::START,
        arena: 0,
    };
    if let Some(c) = grid.cell_of(start.at.position) {
        costs[c] = Some(0);
        arrivals[c] = 0;
    }
    if let Some(k) = key(start.node, &start.at) {
        visit(k);
    }
    let mut buckets: Vec<Vec<State>> = vec![Vec::new(); depth as usize + 1];
    buckets[0].push(start);
    for t in 0..=depth as usize {
        let frontier = std::mem::take(&mut buckets[t]);
        for s in frontier {
            for e in graph.out(s.node) {
                let arrive = t + e.frames as usize;
                if arrive > depth as usize {
                    continue;
                }
                let at = s.at.after(&e.step, e.turn);
                if blocked(&input.obstacles, at.position) {
                    continue;
                }
                let (Some(cell), Some(k)) = (grid.cell_of(at.position), key(e.to, &at)) else {
                    continue;
                };
                if !visit(k) {
                    continue;
                }
                let index = arena.len() as u32;
                arena.push((s.arena, e.id));
                if costs[cell].is_none_or(|c| (arrive as u32) < c) {
                    costs[cell] = Some(arrive as u32);
                    arrivals[cell] = index;
                }
                buckets[arrive].push(State {
                    node: e.to,
                    at,
                    arena: index,
                });
            }
        }
    }
    SearchResult {
        costs,
        arrivals,
        arena,
    }
}

impl SearchResult {
    /// The edge ids of the path that first reached `cell`.
    pub fn path(&self, cell: usize) -> Vec<u32> {
        let mut edges = Vec::new();
        let mut i = self.arrivals[cell];
        while i != u32::MAX && i != 0 {
            let (parent, edge) = self.arena[i as usize];
            edges.push(edge);
            i = parent;
        }
        edges.reverse();
        edges
    }
}
