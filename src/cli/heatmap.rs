//! A cost map as a PNG heat map, like the paper's Figure 6: dark is cheap, unreachable
//! cells are pale blue, obstacles are outlined in red and the start pose is an arrow.
//! A title, the axes' extent, the colour scale in seconds and a legend are drawn around
//! it, so the file explains itself when it is passed around.
//!
//! The picture is a true view from above: x to the right and, because y is up, +z down
//! the page (so the agent's left, −z, is up when it faces right).

use super::canvas::{hot, text_width, Canvas, Rgb, INK, LINE_PX};
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
    annotate(canvas, map, max / map.fps).save(file)
}

/// The map inside its title, extent, colour scale (0 to `max_s`) and legend.
fn annotate(map_picture: Canvas, map: &CostMap, max_s: f64) -> Canvas {
    const PAD: f64 = 6.0;
    let side = (map.grid.n * SCALE) as f64;
    let top = 2.0 * LINE_PX + 3.0 * PAD;
    let mut canvas = map_picture.with_margins(top as usize, 100, 380, WHITE);
    canvas.text(
        DVec2::new(PAD, PAD),
        &format!("\"{}\" cost map ({})", map.behaviour, map.method.name()),
        INK,
    );
    canvas.text(
        DVec2::new(PAD, 2.0 * PAD + LINE_PX),
        "colour: seconds a person needs to reach each cell",
        INK,
    );
    // The extent, under the map: its edges and the start in metres along x.
    let below = top + side + PAD;
    let half = 0.5 * map.grid.size_m;
    let edge = |x: f64| format!("{x:+.1} m");
    canvas.text(DVec2::new(PAD, below), &edge(-half), INK);
    let right = edge(half);
    canvas.text(
        DVec2::new(side - PAD - text_width(&right), below),
        &right,
        INK,
    );
    let middle = format!("x ->, z down; cell {} m", map.grid.cell_m);
    canvas.text(
        DVec2::new(0.5 * (side - text_width(&middle)), below),
        &middle,
        INK,
    );
    let bar = DVec2::new(PAD, below + LINE_PX + 2.0 * PAD);
    let width = (side - 2.0 * PAD).clamp(200.0, 360.0);
    canvas.hot_bar(
        bar,
        DVec2::new(width, 14.0),
        "0 s",
        &format!("{max_s:.1} s"),
    );
    canvas.legend(
        DVec2::new(PAD, bar.y + 14.0 + LINE_PX + 2.0 * PAD),
        &[
            (UNREACHABLE, "not reached"),
            (OBSTACLE, "obstacle"),
            (START, "start, facing +x"),
        ],
    );
    canvas
}

const WHITE: Rgb = [255, 255, 255];
