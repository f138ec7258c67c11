//! A cost map as a PNG heat map, like the paper's Figure 6: dark is cheap, unreachable
//! cells are pale blue, obstacles are outlined in red and the start pose is an arrow.
//!
//! The picture is a true view from above: x to the right and, because y is up, +z down
//! the page (so the agent's left, −z, is up when it faces right).

use super::canvas::{hot, Canvas, Rgb};
use fieldhouse::costmap::CostMap;
use glam::DVec2;
use std::path::Path;

/// Pixels per cell side.
const SCALE: usize = 12;
pub(super) const UNREACHABLE: Rgb = [205, 220, 235];
const OBSTACLE: Rgb = [220, 30, 30];
pub(super) const START: Rgb = [40, 200, 60];

pub(super) fn write(map: &CostMap, file: &Path) -> anyhow::Result<()> {
    let n = map.grid.n;
    let side = n * SCALE;
    let mut canvas = Canvas::new(side, side, UNREACHABLE);
    let max = map
        .costs
        .iter()
        .flatten()
        .copied()
        .max()
        .unwrap_or(1)
        .max(1) as f64;
    let s = SCALE as f64;
    for (cell, cost) in map.costs.iter().enumerate() {
        if let Some(f) = cost {
            let corner = DVec2::new((cell % n) as f64, (cell / n) as f64) * s;
            canvas.fill(corner, corner + DVec2::splat(s), hot(f64::from(*f) / max));
        }
    }
    let to_px = |p: DVec2| (p - map.grid.origin()) / map.grid.cell_m * s;
    for o in &map.obstacles {
        canvas.outline(to_px(o.min), to_px(o.max), 2, OBSTACLE);
    }
    // The start pose: an arrow from the agent along +x, its facing.
    canvas.arrow(to_px(DVec2::ZERO), DVec2::X, 2.5 * s, START);
    canvas.save(file)
}
