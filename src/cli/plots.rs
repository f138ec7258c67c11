//! SVG plots of a sweep: what the fielders did and what they saw. People would rather look
//! at these than read them.

use anyhow::{anyhow, Result};
use fieldhouse::fielding::{SweepCase, SweepReport, TrialResult};
use fieldhouse::words::plural;
use glam::DVec2;
use plotters::prelude::*;
use std::path::Path;

const SIZE: (u32, u32) = (860, 540);
/// Width of the legend panel to the right of a line chart.
const LEGEND_WIDTH: u32 = 170;
const COLOURS: [RGBColor; 5] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
];

fn colour(i: usize) -> RGBColor {
    COLOURS[i % COLOURS.len()]
}

fn plot_err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("drawing failed: {e:?}")
}

/// Smallest range that holds `xs`, padded by 5 %.
fn span(xs: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
        (lo.min(x), hi.max(x))
    });
    if !lo.is_finite() || !hi.is_finite() {
        return 0.0..1.0;
    }
    let pad = ((hi - lo) * 0.05).max(0.5);
    (lo - pad)..(hi + pad)
}

/// A line drawn on a chart: a name for the legend, points, and whether it is a
/// reference (drawn thin and grey, like the ball's ground track) or a strategy's.
struct Line {
    name: String,
    points: Vec<(f64, f64)>,
    reference: bool,
}

/// A titled chart with a line per strategy and the legend in a panel of its own on the
/// right, so it never hides data; drawn into `file`.
fn line_chart(
    file: &Path,
    title: &str,
    (x_desc, y_desc): (&str, &str),
    lines: &[Line],
    marks: &[(String, (f64, f64))],
    equal_axes: bool,
) -> Result<()> {
    let root = SVGBackend::new(file, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(plot_err)?;
    let root = root.titled(title, ("sans-serif", 18)).map_err(plot_err)?;
    let (plot, legend) = root.split_horizontally(SIZE.0 - LEGEND_WIDTH);
    let all = || {
        lines
            .iter()
            .flat_map(|l| l.points.iter())
            .chain(marks.iter().map(|(_, p)| p))
    };
    let (mut xr, mut yr) = (span(all().map(|p| p.0)), span(all().map(|p| p.1)));
    if equal_axes {
        // Keep metres square so a path's curvature is not distorted.
        let (w_px, h_px) = plot.dim_in_pixel();
        let aspect = f64::from(w_px - 60) / f64::from(h_px - 50);
        let (w, h) = (xr.end - xr.start, yr.end - yr.start);
        if w / h < aspect {
            let grow = (h * aspect - w) / 2.0;
            xr = (xr.start - grow)..(xr.end + grow);
        } else {
            let grow = (w / aspect - h) / 2.0;
            yr = (yr.start - grow)..(yr.end + grow);
        }
    }
    let mut chart = ChartBuilder::on(&plot)
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(48)
        .build_cartesian_2d(xr, yr)
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .draw()
        .map_err(plot_err)?;
    let styles: Vec<ShapeStyle> = lines
        .iter()
        .scan(0, |strategy, l| {
            Some(if l.reference {
                RGBColor(150, 150, 150).stroke_width(1)
            } else {
                *strategy += 1;
                colour(*strategy - 1).stroke_width(2)
            })
        })
        .collect();
    for (l, style) in lines.iter().zip(&styles) {
        chart
            .draw_series(LineSeries::new(l.points.iter().copied(), *style))
            .map_err(plot_err)?;
    }
    for (label, p) in marks {
        chart
            .draw_series(std::iter::once(Cross::new(*p, 5, BLACK.stroke_width(2))))
            .map_err(plot_err)?;
        chart
            .draw_series(std::iter::once(Text::new(
                label.clone(),
                *p,
                ("sans-serif", 13),
            )))
            .map_err(plot_err)?;
    }
    for (i, (l, style)) in lines.iter().zip(&styles).enumerate() {
        let y = 40 + 22 * i as i32;
        legend
            .draw(&PathElement::new(vec![(4, y), (26, y)], *style))
            .map_err(plot_err)?;
        legend
            .draw(&Text::new(l.name.clone(), (32, y - 7), ("sans-serif", 13)))
            .map_err(plot_err)?;
    }
    root.present().map_err(plot_err)?;
    Ok(())
}

fn label(r: &TrialResult) -> String {
    format!(
        "{} ({})",
        r.strategy,
        if r.outcome.caught { "caught" } else { "missed" }
    )
}

/// Three plots of one launch: the fielders' paths seen from above, tan ψ against time,
/// and the ball's image on a plane facing home plate.
pub(super) fn draw_launch(
    dir: &Path,
    index: usize,
    case: &SweepCase,
    results: &[TrialResult],
    eye: f64,
) -> Result<()> {
    let l = &case.launch;
    let about = format!(
        "launch {index}: {:.0} m/s at {:.0}°, azimuth {:.0}°",
        l.speed_m_s, l.elevation_deg, l.azimuth_deg
    );
    let landing = case.flight.landing.pos;
    let mut paths: Vec<Line> = results
        .iter()
        .map(|r| Line {
            name: label(r),
            points: r.path.iter().map(|p| (p.x, p.y)).collect(),
            reference: false,
        })
        .collect();
    // Show the ball's ground track only near the fielders, so their paths stay legible.
    let excursion = results
        .iter()
        .flat_map(|r| r.path.iter())
        .chain(std::iter::once(&DVec2::new(landing.x, landing.z)))
        .map(|p| (*p - case.start).length())
        .fold(15.0, f64::max);
    paths.push(Line {
        name: "ball (ground track)".into(),
        points: case
            .flight
            .samples
            .iter()
            .map(|s| DVec2::new(s.pos.x, s.pos.z))
            .filter(|p| (*p - case.start).length() < 1.5 * excursion)
            .map(|p| (p.x, p.y))
            .collect(),
        reference: true,
    });
    line_chart(
        &dir.join(format!("launch-{index}-paths.svg")),
        &format!("Fielders' paths from above — {about}"),
        ("x (m)", "z (m)"),
        &paths,
        &[
            ("start".into(), (case.start.x, case.start.y)),
            ("lands".into(), (landing.x, landing.z)),
        ],
        true,
    )?;

    // tan ψ runs off to infinity as a missed ball passes overhead: plot the part a
    // fielder could still use.
    let tan_psi: Vec<Line> = results
        .iter()
        .map(|r| Line {
            name: label(r),
            points: r
                .trace
                .iter()
                .filter(|e| e.tan_psi > 0.0 && e.tan_psi < 4.0)
                .map(|e| (e.t, e.tan_psi))
                .collect(),
            reference: false,
        })
        .collect();
    line_chart(
        &dir.join(format!("launch-{index}-tan-psi.svg")),
        &format!("Optical elevation tan ψ — {about}"),
        ("time (s)", "tan ψ"),
        &tan_psi,
        &[],
        false,
    )?;

    let home = DVec2::new(case.flight.samples[0].pos.x, case.flight.samples[0].pos.z);
    let image: Vec<Line> = results
        .iter()
        .map(|r| {
            let pts = r
                .trace
                .iter()
                .filter_map(|e| {
                    let f = DVec2::from_array(e.fielder);
                    let forward = (home - f).normalize_or(DVec2::X);
                    let rel = DVec2::new(e.ball[0], e.ball[2]) - f;
                    let depth = rel.dot(forward);
                    let (u, v) = (
                        rel.dot(DVec2::new(-forward.y, forward.x)) / depth,
                        (e.ball[1] - eye) / depth,
                    );
                    (depth > 2.0 && v.abs() < 1.5 && u.abs() < 1.5).then_some((u, v))
                })
                .collect();
            Line {
                name: label(r),
                points: pts,
                reference: false,
            }
        })
        .collect();
    line_chart(
        &dir.join(format!("launch-{index}-image.svg")),
        &format!("The ball's image on a plane facing home — {about}"),
        ("lateral tan (u = L/D)", "vertical tan (v = Y/D)"),
        &image,
        &[],
        false,
    )
}

/// A bar chart of each strategy's catch rate on catchable balls.
pub(super) fn draw_rates(dir: &Path, report: &SweepReport) -> Result<()> {
    let file = dir.join("catch-rates.svg");
    let root = SVGBackend::new(&file, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(plot_err)?;
    let n = report.strategies.len() as u32;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "Catch rate on catchable balls ({}, seed {})",
                plural(report.n as u64, "launch"),
                report.seed
            ),
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(48)
        .build_cartesian_2d((0..n - 1).into_segmented(), 0.0..100.0)
        .map_err(plot_err)?;
    let names: Vec<String> = report
        .strategies
        .iter()
        .map(|s| s.strategy.to_string())
        .collect();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_label_formatter(&|x| match x {
            SegmentValue::CenterOf(i) => names.get(*i as usize).cloned().unwrap_or_default(),
            _ => String::new(),
        })
        .y_desc("% of catchable balls caught")
        .draw()
        .map_err(plot_err)?;
    chart
        .draw_series(
            Histogram::vertical(&chart)
                .margin(24)
                .style_func(|x, _| match x {
                    SegmentValue::Exact(i) | SegmentValue::CenterOf(i) => {
                        colour(*i as usize).filled()
                    }
                    SegmentValue::Last => BLACK.filled(),
                })
                .data(
                    report
                        .strategies
                        .iter()
                        .zip(0..)
                        .map(|(s, i)| (i, 100.0 * s.catchable_rate)),
                ),
        )
        .map_err(plot_err)?;
    root.present().map_err(plot_err)?;
    Ok(())
}
