//! `fieldhouse catch-sweep`: every strategy on the same launches.

use super::args::Setting;
use super::plots;
use anyhow::Context;
use clap::Args;
use fieldhouse::fielding::{
    LaunchDistribution, Observer, SpareBin, StrategyKind, StrategySummary, Sweep, SweepCase,
    SweepReport,
};
use fieldhouse::words::plural;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// How many launches `--svg` draws.
const PLOTTED_LAUNCHES: usize = 6;

#[derive(Args, Debug)]
#[command(
    allow_negative_numbers = true,
    args_override_self = true,
    about = "Many fly balls, every strategy on the same balls: catch rates, efforts, path shapes",
    after_help = "Launches: speed 25–45 m/s, elevation 25–65°, azimuth 0–90°, backspin 1000–3000 rpm, \
        from 1 m; the fielder starts 10–40 m from the landing point in a random direction (all uniform).\n\
        A ball is catchable when the `predictive` fielder (told where it comes down) catches it.\n\
        Example: fieldhouse catch-sweep --n 2000 --seed 7 --svg plots/"
)]
pub(super) struct SweepArgs {
    /// Comma-separated strategies to compare.
    #[arg(long, value_delimiter = ',', default_value = "chapman,lot-optical,predictive,lot,chapman-1d",
          value_parser = super::args::parse_str::<StrategyKind>)]
    strategies: Vec<StrategyKind>,
    /// Number of launches.
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
    n: u64,
    /// Comma-separated observers, each a full sweep over the same launches: `ideal` (no
    /// delay or noise, 1 m reach) and `human` (0.2 s delay, 0.05° noise, 0.2 s
    /// smoothing, 0.9 m reach; docs/catching.md gives the sources). --delay, --noise-deg,
    /// --smoothing and --reach change that setting for every observer.
    #[arg(long, value_delimiter = ',', default_value = "ideal,human",
          value_parser = super::args::parse_str::<Observer>)]
    observers: Vec<Observer>,
    /// Seed of the launch distribution (and of perceptual noise).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Print the reports as one JSON document: an array, a report per observer.
    #[arg(long)]
    json: bool,
    /// Draw the first launches' paths and optical trajectories as SVG files into a folder
    /// per observer in DIR (DIR/ideal, DIR/human).
    #[arg(long, value_name = "DIR")]
    svg: Option<PathBuf>,
    #[command(flatten)]
    setting: Setting,
}

pub(super) fn run(args: SweepArgs, out: &mut impl Write) -> anyhow::Result<()> {
    let s = &args.setting;
    let dist = LaunchDistribution::default();
    let started = Instant::now();
    let mut reports = Vec::with_capacity(args.observers.len());
    let mut cases = Vec::new();
    for &preset in &args.observers {
        let sweep = Sweep {
            ball: s.ball,
            air: s.air,
            air_density: s.air_density,
            dt: s.dt(),
            trial: s.trial_config(args.seed, false),
            observer: s.observer(preset),
        };
        if cases.is_empty() {
            // The launches are the observers' common ground: drawn and flown once.
            cases = sweep.cases(&dist, args.n as usize, args.seed);
        }
        let report = sweep.run(&cases, &args.strategies, &dist, args.seed);
        if let Some(dir) = &args.svg {
            draw(
                &dir.join(sweep.observer.name),
                &sweep,
                &cases,
                &args,
                &report,
            )?;
        }
        reports.push(report);
    }
    tracing::info!(
        launches = args.n,
        strategies = args.strategies.len(),
        observers = args.observers.len(),
        elapsed_s = started.elapsed().as_secs_f64(),
        "sweep finished"
    );
    if args.json {
        writeln!(out, "{}", serde_json::to_string_pretty(&reports)?)?;
    } else {
        for (k, report) in reports.iter().enumerate() {
            if k > 0 {
                writeln!(out)?;
            }
            print_table(report, out)?;
        }
    }
    Ok(())
}

/// The first launches' plots and the catch rates of one observer's sweep, into `dir`.
fn draw(
    dir: &Path,
    sweep: &Sweep,
    cases: &[SweepCase],
    args: &SweepArgs,
    report: &SweepReport,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    for (i, case) in cases.iter().take(PLOTTED_LAUNCHES).enumerate() {
        let results: Vec<_> = args
            .strategies
            .iter()
            .map(|&k| sweep.trial(i, case, k, true))
            .collect();
        plots::draw_launch(dir, i, case, &results, args.setting.eye_height)?;
    }
    plots::draw_rates(dir, report)?;
    tracing::info!(dir = %dir.display(), "plots written");
    Ok(())
}

fn print_table(report: &SweepReport, out: &mut impl Write) -> std::io::Result<()> {
    let catchable = report.strategies.first().map_or(0, |s| s.catchable);
    writeln!(out, "observer {}", report.observer)?;
    writeln!(
        out,
        "{} (seed {}), {} catchable by the predictive baseline",
        plural(report.n as u64, "launch"),
        report.seed,
        catchable
    )?;
    writeln!(
        out,
        "{:<12} {:>7} {:>10} {:>9} {:>9} {:>9} {:>9} {:>9} {:>7} {:>7} {:>7} {:>6} {:>8} {:>8} {:>7}",
        "strategy",
        "caught",
        "catchable",
        "a mean",
        "a peak",
        "a max",
        "v peak",
        "v max",
        "straight",
        "→home",
        "←home",
        "bulge",
        "ṙ drift",
        "img bend",
        "α sweep"
    )?;
    for s in &report.strategies {
        writeln!(out, "{}", row(s))?;
    }
    writeln!(out, "a mean: time-averaged |a| (m/s²); a peak / v peak: per-trial peaks averaged; a max / v max: largest over all trials")?;
    writeln!(out, "path shapes vs the chord from start to end: straight, bulging toward home (→home) or away from it (←home); bulge: median largest deviation / chord (+ toward home); ṙ drift: change of d(tan ψ)/dt over the flight / its mean (0: OAC's constant rate); img bend: scatter of the image across its best line / along it (0: LOT's straight image); medians")?;
    print_spare(report, out)?;
    print_finishing(report, out)
}

/// What the finishing phase decided: catches made only with it, and lost with it.
fn print_finishing(report: &SweepReport, out: &mut impl Write) -> std::io::Result<()> {
    if report.strategies.iter().all(|s| s.finishing.is_none()) {
        return Ok(());
    }
    writeln!(out)?;
    writeln!(
        out,
        "the finishing phase, against the same trials without it (no terminal run, no lunge)"
    )?;
    for s in &report.strategies {
        if let Some(f) = s.finishing {
            writeln!(
                out,
                "{:<12} decided {} of {} catches ({:.1}%), lost {}",
                s.strategy.name(),
                f.decided,
                s.caught,
                100.0 * f.decided as f64 / s.caught.max(1) as f64,
                f.lost
            )?;
        }
    }
    Ok(())
}

/// Catches of catchable balls by their time to spare: where each strategy fails.
fn print_spare(report: &SweepReport, out: &mut impl Write) -> std::io::Result<()> {
    let Some(first) = report.strategies.first() else {
        return Ok(());
    };
    writeln!(out)?;
    writeln!(out, "catchable balls caught, by time to spare (time to the catch band less the fastest sprint to within reach of it)")?;
    write!(out, "{:<12}", "")?;
    for bin in &first.by_time_to_spare {
        write!(out, " {:>16}", spare_label(bin))?;
    }
    writeln!(out)?;
    write!(out, "{:<12}", "balls")?;
    for bin in &first.by_time_to_spare {
        write!(out, " {:>16}", bin.catchable)?;
    }
    writeln!(out)?;
    for s in &report.strategies {
        write!(out, "{:<12}", s.strategy.name())?;
        for bin in &s.by_time_to_spare {
            let share = if bin.catchable == 0 {
                "–".to_string()
            } else {
                format!("{:.0}%", 100.0 * bin.caught as f64 / bin.catchable as f64)
            };
            write!(out, " {:>16}", format!("{} ({share})", bin.caught))?;
        }
        writeln!(out)?;
    }
    Ok(())
}

fn spare_label(bin: &SpareBin) -> String {
    match (bin.from_s, bin.to_s) {
        (None, Some(to)) => format!("< {to} s"),
        (Some(from), Some(to)) => format!("{from}–{to} s"),
        (Some(from), None) => format!("≥ {from} s"),
        (None, None) => "all".to_string(),
    }
}

fn row(s: &StrategySummary) -> String {
    format!(
        "{:<12} {:>6.1}% {:>9.1}% {:>9.2} {:>9.2} {:>9.1} {:>9.2} {:>9.1} {:>7.0}% {:>6.0}% {:>6.0}% {:>+6.2} {:>8.3} {:>8.3} {:>6.1}°",
        s.strategy.name(),
        100.0 * s.catch_rate,
        100.0 * s.catchable_rate,
        s.mean_accel,
        s.mean_peak_accel,
        s.max_peak_accel,
        s.mean_peak_speed,
        s.max_peak_speed,
        100.0 * s.share_straight,
        100.0 * s.share_bulging_toward_home,
        100.0 * s.share_bulging_away_from_home,
        s.median_bulge,
        s.median_rate_drift,
        s.median_image_bend,
        s.median_bearing_sweep_deg
    )
}
