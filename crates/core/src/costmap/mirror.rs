//! The mirror image of a cost map: in a graph built from clips and their mirror images,
//! the map from a node's twin is the map from the node reflected across the body's axis
//! (z → −z), every stored path walked on the twin edges. Search only approximates the
//! cheapest walk, and not alike on both sides; a stance and its twin that each take the
//! better of their own map and the other's reflection are exact mirror images of each
//! other, so a standing body reaches left and right alike.

use super::CostMap;
use crate::motion::{MotionGraph, Walker};
use std::collections::HashMap;

/// `map` (from node `of`) and `twin_map` (from `of`'s mirror twin) each improved, cell by
/// cell, by the other's reflection, where its path has a twin walk on `graph`. Returns
/// how many cells improved.
pub fn symmetrise(graph: &MotionGraph, map: &mut CostMap, twin_map: &mut CostMap) -> usize {
    let twin_edges = twin_edges(graph);
    let reflected = reflect(graph, map, &twin_edges);
    let reflected_twin = reflect(graph, twin_map, &twin_edges);
    take_better(map, &reflected_twin) + take_better(twin_map, &reflected)
}

/// For each edge, the edge from its source's twin to its target's twin, if the graph has
/// one.
fn twin_edges(graph: &MotionGraph) -> Vec<Option<u32>> {
    let index: HashMap<(u32, u32, bool), u32> = graph
        .edges
        .iter()
        .enumerate()
        .map(|(i, e)| ((e.from, e.to, e.transition), i as u32))
        .collect();
    let twins: Vec<Option<u32>> = (0..graph.node_count() as u32)
        .map(|n| graph.mirror_twin(n))
        .collect();
    graph
        .edges
        .iter()
        .map(|e| {
            let key = (twins[e.from as usize]?, twins[e.to as usize]?, e.transition);
            index.get(&key).copied()
        })
        .collect()
}

/// Per cell of the reflected map: its cost and path, where every edge of the path has a
/// twin and the twin walk ends in the cell. (A walk that ends exactly on the body's axis,
/// z = 0, stays on it when reflected, in the cell on the axis's +z side: the start's
/// own cell is one.)
fn reflect(
    graph: &MotionGraph,
    map: &CostMap,
    twin_edges: &[Option<u32>],
) -> Vec<Option<(u32, Vec<u32>)>> {
    let n = map.grid.n;
    (0..map.costs.len())
        .map(|cell| {
            // Row i runs along z: its reflection is row n − 1 − i.
            let (i, j) = (cell / n, cell % n);
            let from = (n - 1 - i) * n + j;
            let cost = map.costs[from]?;
            let path = map.paths[from]
                .iter()
                .map(|&e| twin_edges[e as usize])
                .collect::<Option<Vec<u32>>>()?;
            let end = path.iter().fold(Walker::START, |at, &e| {
                at.step(&graph.edges[e as usize].step)
            });
            (map.grid.cell_of(end.position) == Some(cell)).then_some((cost, path))
        })
        .collect()
}

/// Takes into `map` every cell `other` reaches sooner; returns how many.
fn take_better(map: &mut CostMap, other: &[Option<(u32, Vec<u32>)>]) -> usize {
    let mut better = 0;
    for (cell, o) in other.iter().enumerate() {
        let Some((cost, path)) = o else { continue };
        if map.costs[cell].is_none_or(|c| *cost < c) {
            map.costs[cell] = Some(*cost);
            map.paths[cell] = path.clone();
            better += 1;
        }
    }
    better
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::costmap::{start_states, BuildParams, STANDING_MIRRORED};
    use crate::fixtures::cmu_graph;

    /// On the mirrored CMU footwork, a stance's map and its twin's, symmetrised, are
    /// exact reflections of each other (but for the start's own cell and its reflection,
    /// on either side of the axis), every cost no worse than search's own, and every
    /// stored path replays to its cell from its own start.
    #[test]
    fn symmetrised_stances_are_reflections_with_paths_that_replay() {
        let graph = cmu_graph("defense");
        let states = start_states(&graph);
        let twin = states.iter().find(|s| s.name == STANDING_MIRRORED).unwrap();
        let params = BuildParams {
            depth: 90,
            grid: crate::costmap::Grid::new(8.0, 0.5),
            ..BuildParams::default()
        };
        let mut maps =
            CostMap::build_from(&graph, &params, &[states[0].node, twin.node], &mut |_| {});
        let searched = maps.clone();
        let (a, b) = maps.split_at_mut(1);
        symmetrise(&graph, &mut a[0], &mut b[0]);
        let n = params.grid.n;
        let start = params.grid.cell_of(glam::DVec2::ZERO).unwrap();
        let mirror = |cell: usize| (n - 1 - cell / n) * n + cell % n;
        for cell in 0..n * n {
            if cell != start && cell != mirror(start) {
                assert_eq!(
                    maps[0].costs[cell],
                    maps[1].costs[mirror(cell)],
                    "cell {cell}"
                );
            }
            for (m, s) in maps.iter().zip(&searched) {
                assert!(m.costs[cell].unwrap_or(u32::MAX) <= s.costs[cell].unwrap_or(u32::MAX));
            }
        }
        for m in &maps {
            for cell in (0..n * n).filter(|&c| m.costs[c].is_some()) {
                let mut at = Walker::START;
                let mut node = m.start_node;
                for &e in &m.paths[cell] {
                    let edge = &graph.edges[e as usize];
                    assert_eq!(edge.from, node, "the path is a walk");
                    at = at.step(&edge.step);
                    node = edge.to;
                }
                assert_eq!(m.paths[cell].len() as u32, m.costs[cell].unwrap());
                assert_eq!(params.grid.cell_of(at.position), Some(cell));
            }
        }
    }
}
