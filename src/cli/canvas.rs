//! A small RGB raster for the PNG pictures (cost-map heat maps, basketball decisions):
//! filled rectangles, outlines and arrows, written with the `png` crate.

use anyhow::Context;
use glam::DVec2;
use std::path::Path;

pub(super) type Rgb = [u8; 3];

pub(super) struct Canvas {
    width: usize,
    height: usize,
    rgb: Vec<u8>,
}

/// Dark for cheap, through red and yellow to white for the most expensive (a "hot"
/// colour map), so a picture reads without a legend.
pub(super) fn hot(t: f64) -> Rgb {
    let t = t.clamp(0.0, 1.0);
    let channel = |x: f64| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    [
        channel(3.0 * t),
        channel(3.0 * t - 1.0),
        channel(3.0 * t - 2.0),
    ]
}

impl Canvas {
    pub(super) fn new(width: usize, height: usize, background: Rgb) -> Canvas {
        Canvas {
            width,
            height,
            rgb: background.repeat(width * height),
        }
    }

    pub(super) fn put(&mut self, x: i64, y: i64, c: Rgb) {
        if (0..self.width as i64).contains(&x) && (0..self.height as i64).contains(&y) {
            let k = (y as usize * self.width + x as usize) * 3;
            self.rgb[k..k + 3].copy_from_slice(&c);
        }
    }

    /// Fills the pixels from `a` (inclusive) to `b` (exclusive).
    pub(super) fn fill(&mut self, a: DVec2, b: DVec2, c: Rgb) {
        for y in a.y.round() as i64..b.y.round() as i64 {
            for x in a.x.round() as i64..b.x.round() as i64 {
                self.put(x, y, c);
            }
        }
    }

    /// A rectangle's outline, `width` pixels thick, inside the corners `a` and `b`.
    pub(super) fn outline(&mut self, a: DVec2, b: DVec2, width: i64, c: Rgb) {
        let (x0, y0, x1, y1) = (
            a.x.round() as i64,
            a.y.round() as i64,
            b.x.round() as i64 - 1,
            b.y.round() as i64 - 1,
        );
        for t in 0..width {
            for x in x0..=x1 {
                self.put(x, y0 + t, c);
                self.put(x, y1 - t, c);
            }
            for y in y0..=y1 {
                self.put(x0 + t, y, c);
                self.put(x1 - t, y, c);
            }
        }
    }

    /// A disc of radius `r` pixels.
    pub(super) fn disc(&mut self, centre: DVec2, r: f64, c: Rgb) {
        let ri = r.ceil() as i64;
        for dy in -ri..=ri {
            for dx in -ri..=ri {
                if ((dx * dx + dy * dy) as f64) <= r * r {
                    self.put(
                        centre.x.round() as i64 + dx,
                        centre.y.round() as i64 + dy,
                        c,
                    );
                }
            }
        }
    }

    /// An arrow from `from`, `length` pixels long along the unit vector `dir`, with a
    /// head over its last 40 %.
    pub(super) fn arrow(&mut self, from: DVec2, dir: DVec2, length: f64, c: Rgb) {
        let side = dir.perp();
        let steps = (2.0 * length) as usize;
        for k in 0..=steps {
            let s = k as f64 / 2.0;
            let p = from + dir * s;
            let half = if s > 0.6 * length {
                (length - s).max(0.0) * 0.8
            } else {
                1.0
            };
            let mut w = -half;
            while w <= half {
                let q = p + side * w;
                self.put(q.x.round() as i64, q.y.round() as i64, c);
                w += 0.5;
            }
        }
    }

    pub(super) fn save(&self, file: &Path) -> anyhow::Result<()> {
        let out = std::fs::File::create(file)
            .with_context(|| format!("cannot create {}", file.display()))?;
        let mut encoder = png::Encoder::new(
            std::io::BufWriter::new(out),
            self.width as u32,
            self.height as u32,
        );
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder
            .write_header()
            .and_then(|mut w| w.write_image_data(&self.rgb))
            .with_context(|| format!("cannot write {}", file.display()))
    }
}
