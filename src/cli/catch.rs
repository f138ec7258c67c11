//! `fieldhouse catch`: one fielder, one fly ball.

use super::args::{any_number, ground_point, non_negative, parse_str, positive, Setting};
use clap::Args;
use fieldhouse::fielding::{Observer, Outcome, StrategyKind, TraceEntry, Trial};
use fieldhouse::physics::{Flight, Launch};
use glam::DVec2;
use serde::Serialize;
use std::io::Write;

/// Longest flight simulated for a single catch.
const MAX_FLIGHT_S: f64 = 60.0;

#[derive(Args, Debug)]
#[command(
    allow_negative_numbers = true,
    args_override_self = true,
    about = "One fielder, one fly ball: did it catch it, and how did it run?",
    after_help = "The ball starts at (0, launch height, 0); azimuth is measured from +x toward +z, y is up.\n\
        Example: fieldhouse catch --strategy chapman --speed 40 --elevation 40 --azimuth 30 --fielder 70,55"
)]
pub(super) struct CatchArgs {
    /// chapman, chapman-1d, lot, lot-optical or predictive.
    #[arg(long, value_parser = parse_str::<StrategyKind>)]
    strategy: StrategyKind,
    /// Launch speed in m/s.
    #[arg(long = "speed", value_name = "M_PER_S", value_parser = positive)]
    speed: f64,
    /// Launch angle above the horizontal, in degrees.
    #[arg(long, value_name = "DEG", value_parser = elevation)]
    elevation: f64,
    /// Horizontal launch direction in degrees, from +x toward +z.
    #[arg(long, value_name = "DEG", value_parser = any_number)]
    azimuth: f64,
    /// Where the fielder starts, `X,Z` in metres (negative values are fine: -12.5,40).
    #[arg(long, value_name = "X,Z", value_parser = ground_point, allow_hyphen_values = true)]
    fielder: DVec2,
    /// Height the ball leaves the bat, in metres.
    #[arg(long, value_name = "M", default_value_t = 1.0, value_parser = non_negative)]
    launch_height: f64,
    /// Backspin in revolutions per minute.
    #[arg(long, value_name = "RPM", default_value_t = 2000.0, value_parser = non_negative)]
    spin: f64,
    /// Spin axis, as the tilt of the spin's lift about the velocity in degrees: 0 is pure
    /// backspin (lift up), 90 side spin curving toward increasing azimuth, -90 the other way.
    #[arg(long, value_name = "DEG", default_value_t = 0.0, value_parser = any_number)]
    spin_axis: f64,
    /// Who watches the ball: `ideal` (no delay or noise, 1 m reach) or `human` (0.2 s
    /// delay, 0.05° noise, 0.2 s smoothing, 0.9 m reach; docs/catching.md gives the
    /// sources). --delay, --noise-deg, --smoothing and --reach change single settings.
    #[arg(long, default_value = "ideal", value_parser = parse_str::<Observer>)]
    observer: Observer,
    /// Seed for perceptual noise (only matters with noise).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Print one JSON document with the outcome and a trace entry per tick.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    setting: Setting,
}

fn elevation(s: &str) -> Result<f64, String> {
    let x = any_number(s)?;
    if x > -90.0 && x < 90.0 {
        Ok(x)
    } else {
        Err(format!(
            "elevation {s} must lie strictly between -90 and 90 degrees"
        ))
    }
}

/// `fieldhouse catch --json`: exactly these fields, in this order.
#[derive(Serialize)]
struct CatchReport<'a> {
    outcome: Outcome,
    peak_accel: f64,
    peak_speed: f64,
    path_length_m: f64,
    trace: &'a [TraceEntry],
}

pub(super) fn run(args: CatchArgs, out: &mut impl Write) -> anyhow::Result<()> {
    let s = &args.setting;
    let launch = Launch {
        speed_m_s: args.speed,
        elevation_deg: args.elevation,
        azimuth_deg: args.azimuth,
        height_m: args.launch_height,
        spin_rpm: args.spin,
        spin_tilt_deg: args.spin_axis,
    };
    let air = launch.air(s.air, s.air_density, &s.ball);
    let flight = Flight::simulate(launch.initial_state(), &air, s.dt(), MAX_FLIGHT_S);
    let mut config = s.trial_config(args.seed, args.json);
    s.observer(args.observer).apply(&mut config);
    let result = Trial {
        flight: &flight,
        config: &config,
    }
    .run(args.strategy, args.fielder);
    if args.json {
        let report = CatchReport {
            outcome: result.outcome,
            peak_accel: result.peak_accel,
            peak_speed: result.peak_speed,
            path_length_m: result.path_length_m,
            trace: &result.trace,
        };
        writeln!(out, "{}", serde_json::to_string(&report)?)?;
        return Ok(());
    }
    let o = &result.outcome;
    let [lx, lz] = o.ball_landing;
    writeln!(
        out,
        "ball: {} m/s at {}°, azimuth {}°, {} rpm, {} air; lands at ({lx:.1}, {lz:.1}) after {:.2} s",
        args.speed,
        args.elevation,
        args.azimuth,
        args.spin,
        s.air.name(),
        flight.landing.t
    )?;
    let verdict = if o.caught { "CAUGHT" } else { "missed" };
    writeln!(
        out,
        "{} fielder from ({}, {}): {verdict} at {:.2} s, closest {:.2} m",
        args.strategy, args.fielder.x, args.fielder.y, o.time_s, o.miss_distance_m
    )?;
    writeln!(
        out,
        "ran {:.1} m; peak speed {:.2} m/s; peak acceleration {:.2} m/s²",
        result.path_length_m, result.peak_speed, result.peak_accel
    )?;
    Ok(())
}
