//! `basketball-decide --png`: a decision drawn as three court panels from above, with
//! titles, a time scale and a legend, so the file explains itself.

use super::DecideArgs;
use crate::cli::canvas::{hot, text_width, Canvas, Rgb, INK, LINE_PX};
use crate::cli::heatmap::UNREACHABLE;
use fieldhouse::basketball::{Court, Decision, DecisionParams};
use fieldhouse::costmap::AgentPose;
use glam::DVec2;
use std::path::Path;

/// Pixels per court square.
const SCALE: f64 = 16.0;
const SHOOTER: Rgb = [40, 200, 60];
const DEFENDER: Rgb = [230, 40, 40];
const BASKET: Rgb = [255, 140, 0];
const FAILS: Rgb = [120, 120, 120];
const LINE: Rgb = [40, 90, 200];
const GAP: usize = 12;

/// Three court panels from above (x right, z down): the shooter's dribbling time C_d,
/// the defender's time C_o, and the rule (qualifying squares by success, dark = better;
/// the rest grey; the chosen square outlined in green).
pub(super) fn decision(
    court: &Court,
    decision: &Decision,
    params: &DecisionParams,
    args: &DecideArgs,
    file: &Path,
) -> anyhow::Result<()> {
    let (nx, nz) = court.squares_xz();
    let (w, h) = (nx as f64 * SCALE, nz as f64 * SCALE);
    let mut canvas = Canvas::new(3 * w as usize + 2 * GAP, h as usize, [255, 255, 255]);
    let horizon = decision
        .candidates
        .iter()
        .map(|c| c.c_o.max(c.c_d))
        .fold(0.1, f64::max);
    let best = decision
        .candidates
        .iter()
        .map(|c| c.success)
        .fold(1e-9, f64::max);
    let half_z = 0.5 * nz as f64 * court.square_m;
    let px = |panel: usize, p: DVec2| {
        DVec2::new(
            panel as f64 * (w + GAP as f64) + p.x / court.square_m * SCALE,
            (p.y + half_z) / court.square_m * SCALE,
        )
    };
    for panel in 0..3 {
        canvas.fill(
            px(panel, DVec2::new(0.0, -half_z)),
            px(panel, DVec2::new(court.length_m, half_z)),
            UNREACHABLE,
        );
    }
    let half = DVec2::splat(0.5 * court.square_m);
    for c in &decision.candidates {
        let centre = DVec2::from_array(c.cell);
        let colours = [
            hot(c.c_d / horizon),
            hot(c.c_o / horizon),
            if c.qualifies(params) {
                hot(1.0 - c.success / best)
            } else {
                FAILS
            },
        ];
        for (panel, colour) in colours.into_iter().enumerate() {
            canvas.fill(px(panel, centre - half), px(panel, centre + half), colour);
        }
    }
    for panel in 0..3 {
        // The three-point arc, where it lies on the court.
        for k in 0..=720 {
            let a = (f64::from(k) / 720.0 - 0.5) * std::f64::consts::PI;
            let p = court.basket + DVec2::from_angle(a) * court.three_point_m;
            if court.contains(p) {
                canvas.disc(px(panel, p), 1.0, LINE);
            }
        }
        canvas.disc(px(panel, court.basket), 0.45 * SCALE, BASKET);
        let pose = |p: &AgentPose, colour: Rgb, canvas: &mut Canvas| {
            canvas.disc(px(panel, p.position), 0.3 * SCALE, colour);
            canvas.arrow(
                px(panel, p.position),
                DVec2::from_angle(p.heading),
                2.0 * SCALE,
                colour,
            );
        };
        pose(&args.shooter, SHOOTER, &mut canvas);
        for d in &args.defender {
            pose(d, DEFENDER, &mut canvas);
        }
    }
    if let Some(c) = decision.chosen {
        let centre = DVec2::from_array(c.cell);
        canvas.outline(
            px(2, centre - half * 3.0),
            px(2, centre + half * 3.0),
            3,
            SHOOTER,
        );
    }
    annotate(canvas, (w, h), horizon, params).save(file)
}

/// The three panels (each `panel` wide and high, px) under their titles, over the time
/// scale (0 to `horizon_s`) and a legend: the file explains itself.
fn annotate(panels: Canvas, panel: (f64, f64), horizon_s: f64, params: &DecisionParams) -> Canvas {
    let (panel_w, panel_h) = panel;
    const PAD: f64 = 6.0;
    let top = LINE_PX + 2.0 * PAD;
    let mut canvas = panels.with_margins(top as usize, 70, 0, [255, 255, 255]);
    let titles = [
        "C_d: shooter's dribbling time",
        "C_o: defenders' time",
        "the rule: safe squares",
    ];
    for (k, title) in titles.into_iter().enumerate() {
        let left = k as f64 * (panel_w + GAP as f64);
        canvas.text(
            DVec2::new(left + 0.5 * (panel_w - text_width(title)).max(0.0), PAD),
            title,
            INK,
        );
    }
    let below = top + panel_h + PAD;
    let bar_w = (2.0 * panel_w + GAP as f64 - 2.0 * PAD).min(420.0);
    canvas.hot_bar(
        DVec2::new(PAD, below),
        DVec2::new(bar_w, 14.0),
        "0 s",
        &format!("{horizon_s:.1} s (C_d, C_o)"),
    );
    let rule = format!(
        "not safe: C_o <= C_d + {} s + {} s",
        params.shot_time_s, params.epsilon_s
    );
    canvas.legend(
        DVec2::new(PAD, below + 14.0 + LINE_PX + 2.0 * PAD),
        &[
            (FAILS, rule.as_str()),
            (hot(0.0), "safe, best shot (darker is better)"),
            (SHOOTER, "shooter; chosen square"),
            (UNREACHABLE, "beyond the map"),
            (DEFENDER, "defender"),
            (BASKET, "basket"),
        ],
    );
    canvas
}
