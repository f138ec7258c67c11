//! A cost map as a PNG heat map, like the paper's Figure 6: dark is cheap, unreachable
//! cells are pale blue, obstacles are outlined in red and the start pose is an arrow.
//!
//! The picture is a true view from above: x to the right and, because y is up, +z down
//! the page (so the agent's left, −z, is up when it faces right).

use anyhow::Context;
use fieldhouse::costmap::CostMap;
use glam::DVec2;
use std::path::Path;

/// Pixels per cell side.
const SCALE: usize = 12;
const UNREACHABLE: [u8; 3] = [205, 220, 235];
const OBSTACLE: [u8; 3] = [220, 30, 30];
const START: [u8; 3] = [40, 200, 60];

/// Dark for cheap, through red and yellow to white for the most expensive cell
/// (a "hot" colour map), so the picture reads without a legend.
fn colour(t: f64) -> [u8; 3] {
    let t = t.clamp(0.0, 1.0);
    let channel = |x: f64| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    [
        channel(3.0 * t),
        channel(3.0 * t - 1.0),
        channel(3.0 * t - 2.0),
    ]
}

pub fn write(map: &CostMap, file: &Path) -> anyhow::Result<()> {
    let n = map.grid.n;
    let side = n * SCALE;
    let mut rgb = vec![0u8; side * side * 3];
    let max = map
        .costs
        .iter()
        .flatten()
        .copied()
        .max()
        .unwrap_or(1)
        .max(1) as f64;
    let mut put = |x: usize, y: usize, c: [u8; 3]| {
        if x < side && y < side {
            rgb[(y * side + x) * 3..(y * side + x) * 3 + 3].copy_from_slice(&c);
        }
    };
    for (cell, cost) in map.costs.iter().enumerate() {
        let c = cost.map_or(UNREACHABLE, |f| colour(f as f64 / max));
        let (i, j) = (cell / n, cell % n);
        for y in i * SCALE..(i + 1) * SCALE {
            for x in j * SCALE..(j + 1) * SCALE {
                put(x, y, c);
            }
        }
    }
    let to_px = |p: DVec2| ((p - map.grid.origin()) / map.grid.cell_m * SCALE as f64).round();
    for o in &map.obstacles {
        let (a, b) = (
            to_px(o.min).max(DVec2::ZERO),
            to_px(o.max).min(DVec2::splat(side as f64 - 1.0)),
        );
        for x in a.x as usize..=b.x as usize {
            for t in 0..2 {
                put(x, a.y as usize + t, OBSTACLE);
                put(x, (b.y as usize).saturating_sub(t), OBSTACLE);
            }
        }
        for y in a.y as usize..=b.y as usize {
            for t in 0..2 {
                put(a.x as usize + t, y, OBSTACLE);
                put((b.x as usize).saturating_sub(t), y, OBSTACLE);
            }
        }
    }
    // The start pose: an arrow from the agent along +x, its facing.
    let centre = to_px(DVec2::ZERO);
    let length = 2.5 * SCALE as f64;
    for k in 0..=length as usize {
        let x = centre.x + k as f64;
        for w in -1..=1 {
            put(x as usize, (centre.y + w as f64) as usize, START);
        }
        let head = length - k as f64;
        if head < 0.4 * length {
            for w in 0..=(head as usize) {
                put(x as usize, (centre.y - w as f64) as usize, START);
                put(x as usize, (centre.y + w as f64) as usize, START);
            }
        }
    }
    let out =
        std::fs::File::create(file).with_context(|| format!("cannot create {}", file.display()))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(out), side as u32, side as u32);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder
        .write_header()
        .and_then(|mut w| w.write_image_data(&rgb))
        .with_context(|| format!("cannot write {}", file.display()))?;
    Ok(())
}
