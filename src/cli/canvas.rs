//! A small RGB raster for the PNG pictures (cost-map heat maps, basketball decisions):
//! filled rectangles, outlines, arrows and text (a built-in bitmap font, [`super::glyphs`],
//! so a picture carries its own title, scale and legend), written with the `png` crate.

use super::glyphs::{GLYPHS, GLYPH_H, GLYPH_W};
use anyhow::Context;
use glam::DVec2;
use std::path::Path;

pub(super) type Rgb = [u8; 3];

/// Text and frames.
pub(super) const INK: Rgb = [30, 30, 30];

/// The width of `text` in the built-in font, px.
pub(super) fn text_width(text: &str) -> f64 {
    (text.chars().count() * GLYPH_W) as f64
}

/// A line of text's height in the built-in font, px.
pub(super) const LINE_PX: f64 = GLYPH_H as f64;

pub(super) struct Canvas {
    width: usize,
    height: usize,
    rgb: Vec<u8>,
}

/// Dark for cheap, through red and yellow to white for the most expensive (a "hot"
/// colour map).
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

    /// The same picture with `top` and `bottom` margins of `background`, at least
    /// `min_width` wide (widened on the right): room for titles and legends around a
    /// drawing made at (0, 0).
    pub(super) fn with_margins(
        &self,
        top: usize,
        bottom: usize,
        min_width: usize,
        background: Rgb,
    ) -> Canvas {
        let width = self.width.max(min_width);
        let mut out = Canvas::new(width, self.height + top + bottom, background);
        for y in 0..self.height {
            let from = y * self.width * 3;
            let to = (y + top) * out.width * 3;
            out.rgb[to..to + self.width * 3]
                .copy_from_slice(&self.rgb[from..from + self.width * 3]);
        }
        out
    }

    /// `text` with its top-left corner at `at`, in the built-in font (printable ASCII;
    /// anything else is drawn as `?`).
    pub(super) fn text(&mut self, at: DVec2, text: &str, c: Rgb) {
        let (x0, y0) = (at.x.round() as i64, at.y.round() as i64);
        for (k, ch) in text.chars().enumerate() {
            let code = if (' '..='~').contains(&ch) { ch } else { '?' };
            let glyph = &GLYPHS[code as usize - ' ' as usize];
            for (dy, row) in glyph.iter().enumerate() {
                for dx in 0..GLYPH_W {
                    if row >> dx & 1 == 1 {
                        self.put(x0 + (k * GLYPH_W + dx) as i64, y0 + dy as i64, c);
                    }
                }
            }
        }
    }

    /// The "hot" scale as a bar `size` pixels at `at`, labelled `low` under its left end
    /// and `high` under its right: what a picture's colours mean.
    pub(super) fn hot_bar(&mut self, at: DVec2, size: DVec2, low: &str, high: &str) {
        for x in 0..size.x as i64 {
            let colour = hot(x as f64 / (size.x - 1.0).max(1.0));
            self.fill(
                at + DVec2::new(x as f64, 0.0),
                at + DVec2::new(x as f64 + 1.0, size.y),
                colour,
            );
        }
        self.outline(at, at + size, 1, INK);
        self.text(at + DVec2::new(0.0, size.y + 2.0), low, INK);
        self.text(
            at + DVec2::new(size.x - text_width(high), size.y + 2.0),
            high,
            INK,
        );
    }

    /// A legend: for each entry a square of its colour and its words, in a row from `at`
    /// (wrapping at the picture's right edge); returns the y below the last row.
    pub(super) fn legend(&mut self, at: DVec2, entries: &[(Rgb, &str)]) -> f64 {
        let line = GLYPH_H as f64 + 4.0;
        let mut p = at;
        for (colour, words) in entries {
            let wide = GLYPH_H as f64 + 4.0 + text_width(words) + 14.0;
            if p.x > at.x && p.x + wide > self.width as f64 {
                p = DVec2::new(at.x, p.y + line);
            }
            let square = DVec2::splat(GLYPH_H as f64 - 2.0);
            self.fill(
                p + DVec2::new(0.0, 1.0),
                p + DVec2::new(0.0, 1.0) + square,
                *colour,
            );
            self.outline(
                p + DVec2::new(0.0, 1.0),
                p + DVec2::new(0.0, 1.0) + square,
                1,
                INK,
            );
            self.text(p + DVec2::new(GLYPH_H as f64 + 2.0, 0.0), words, INK);
            p.x += wide;
        }
        p.y + line
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
