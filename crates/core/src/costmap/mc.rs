//! The paper's Monte Carlo cost map: random walks on the motion graph from the start pose,
//! each cell keeping the cheapest path that reached it.

use super::grid::blocked;
use super::prepared::Prepared;
use super::{BuildInput, ConvergencePoint};
use crate::motion::Walker;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub(crate) struct McResult {
    pub costs: Vec<Option<u32>>,
    /// Per cell, the edge ids of the cheapest walk up to the cell.
    pub paths: Vec<Vec<u32>>,
    pub convergence: Vec<ConvergencePoint>,
}

/// Runs `iterations` walks of at most `depth` frames. A walk ends when it leaves the
/// grid, enters an obstacle or reaches a node with no enabled edge.
///
/// The cells in `watch` are sampled after every walk that is a checkpoint (about 40,
/// spaced geometrically) to show convergence, as the paper's Figure 4 does.
pub(crate) fn build(
    input: &BuildInput,
    graph: &Prepared,
    iterations: u64,
    depth: u32,
    seed: u64,
    watch: &[usize],
    progress: &mut dyn FnMut(u64),
) -> McResult {
    let grid = &input.grid;
    let mut costs: Vec<Option<u32>> = vec![None; grid.cells()];
    let mut paths: Vec<Vec<u32>> = vec![Vec::new(); grid.cells()];
    if let Some(c) = grid.cell_of(Walker::START.position) {
        costs[c] = Some(0);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut walk: Vec<u32> = Vec::with_capacity(depth as usize);
    let checkpoints = checkpoints(iterations);
    let mut next_checkpoint = 0;
    let mut convergence = Vec::with_capacity(checkpoints.len());
    for iteration in 1..=iterations {
        walk.clear();
        let (mut node, mut at, mut frames) = (input.start, Walker::START, 0u32);
        while frames < depth {
            let out = graph.out(node);
            if out.is_empty() {
                break;
            }
            let e = &out[rng.gen_range(0..out.len())];
            at = at.after(&e.step, e.turn);
            frames += e.frames;
            node = e.to;
            walk.push(e.id);
            if blocked(&input.obstacles, at.position) {
                break;
            }
            let Some(cell) = grid.cell_of(at.position) else {
                break;
            };
            if costs[cell].is_none_or(|c| frames < c) {
                costs[cell] = Some(frames);
                paths[cell].clear();
                paths[cell].extend_from_slice(&walk);
            }
        }
        if checkpoints.get(next_checkpoint) == Some(&iteration) {
            next_checkpoint += 1;
            convergence.push(ConvergencePoint {
                iterations: iteration,
                costs: watch.iter().map(|&c| costs[c]).collect(),
            });
            progress(iteration);
        }
    }
    McResult {
        costs,
        paths,
        convergence,
    }
}

/// About 40 iteration counts from 1 to `n`, spaced geometrically, ending at `n`.
fn checkpoints(n: u64) -> Vec<u64> {
    let mut points: Vec<u64> = (0..=40)
        .map(|k| (n as f64).powf(k as f64 / 40.0).round() as u64)
        .collect();
    points.dedup();
    points
}
