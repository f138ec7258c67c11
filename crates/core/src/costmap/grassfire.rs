//! Blum's grassfire over the grid: the "cost proportional to distance" baseline the paper
//! argues against.

use super::grid::{blocked, Grid, Obstacle};
use crate::motion::Walker;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Distance from the start cell to every cell through free cells, 8-connected with unit
/// straight steps and √2 diagonals (Dijkstra, so the octile metric max + (√2 − 1)·min on
/// open ground), turned into frames at `speed_m_s`: the time a body that could run at top
/// speed in any direction, with no turning or accelerating, would need.
pub(crate) fn build(
    grid: &Grid,
    obstacles: &[Obstacle],
    speed_m_s: f64,
    fps: f64,
) -> Vec<Option<u32>> {
    let n = grid.n;
    let free: Vec<bool> = (0..grid.cells())
        .map(|c| !blocked(obstacles, grid.centre(c)))
        .collect();
    let mut dist = vec![f64::INFINITY; grid.cells()];
    let Some(start) = grid.cell_of(Walker::START.position) else {
        return vec![None; grid.cells()];
    };
    dist[start] = 0.0;
    // Distances are kept as whole micrometres in the heap so they order exactly.
    let mut heap = BinaryHeap::from([Reverse((0u64, start))]);
    while let Some(Reverse((d_um, c))) = heap.pop() {
        if d_um > (dist[c] * 1e6).round() as u64 {
            continue; // a stale entry: the cell was reached more cheaply since
        }
        let d = dist[c];
        let (i, j) = ((c / n) as i64, (c % n) as i64);
        for (di, dj) in [
            (-1, -1),
            (-1, 0),
            (-1, 1),
            (0, -1),
            (0, 1),
            (1, -1),
            (1, 0),
            (1, 1),
        ] {
            let (ni, nj) = (i + di, j + dj);
            if ni < 0 || nj < 0 || ni >= n as i64 || nj >= n as i64 {
                continue;
            }
            let next = ni as usize * n + nj as usize;
            if !free[next] {
                continue;
            }
            let step = if di != 0 && dj != 0 {
                std::f64::consts::SQRT_2
            } else {
                1.0
            } * grid.cell_m;
            if d + step < dist[next] - 1e-9 {
                dist[next] = d + step;
                heap.push(Reverse(((dist[next] * 1e6).round() as u64, next)));
            }
        }
    }
    dist.iter()
        .map(|d| d.is_finite().then(|| (d / speed_m_s * fps).ceil() as u32))
        .collect()
}
