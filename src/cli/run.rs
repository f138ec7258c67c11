//! `fieldhouse run`: a scenario played headless, as fast as the machine allows, into a
//! replay file.

use super::basketball::CapabilityArgs;
use super::writer::Background;
use anyhow::Context;
use clap::Args;
use fieldhouse::protocol::Score;
use fieldhouse::replay::{self, Encoding, Recorder};
use fieldhouse::session::Session;
use fieldhouse::sim::{Mode, Scenario, Sport, World};
use fieldhouse::words::{figure, plural};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::{json, Value};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Args, Debug)]
#[command(
    after_help = "Example: fieldhouse run scenarios/baseball-papers.toml --out papers.jsonl.zst\n\
    A scenario written for the server (no end): fieldhouse run scenarios/basketball.toml --possessions 100\n\
    Then: fieldhouse replay info papers.jsonl.zst; fieldhouse replay verify papers.jsonl.zst"
)]
pub(super) struct RunArgs {
    /// A scenario file (TOML; the structure of the POST /api/matches body).
    scenario: PathBuf,
    /// The replay file to write (default: the scenario's name with .jsonl.zst, here).
    /// Its name picks the format: a name ending in .jsonl gets plain JSON lines (format
    /// 1, 8-9x larger); any other name, zstd-compressed chunks of them (format 2, which
    /// `zstdcat FILE` prints as JSON lines). `fieldhouse replay` reads both.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// `builtin`: play bot-controlled agents with their built-in brains.
    #[arg(long, value_name = "builtin")]
    bots: Option<String>,
    /// Play this many simulated seconds (the scenario's `duration_s`, which this
    /// replaces): how a scenario written for the server, which plays until deleted,
    /// gets an end.
    #[arg(long, value_name = "S")]
    duration_s: Option<f64>,
    /// Basketball: play this many possessions (the scenario's `options.possessions`,
    /// which this replaces).
    #[arg(long, value_name = "N")]
    possessions: Option<u64>,
    /// Print one JSON document.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    capability: CapabilityArgs,
}

/// A scenario file as the JSON the scenario is read from.
fn scenario_value(path: &Path) -> anyhow::Result<Value> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let value: toml::Value =
        toml::from_str(&text).with_context(|| format!("{} is not TOML", path.display()))?;
    Ok(serde_json::to_value(value)?)
}

/// The scenario of `args`, with the end its flags give in place of the file's: checked
/// as a whole, so a flag's value is held to the field's own rules.
fn scenario_of(args: &RunArgs) -> anyhow::Result<Scenario> {
    let mut value = scenario_value(&args.scenario)?;
    if let Value::Object(doc) = &mut value {
        if let Some(d) = args.duration_s {
            doc.insert("duration_s".into(), json!(d));
        }
        if let Some(p) = args.possessions {
            let options = doc.entry("options").or_insert_with(|| json!({}));
            if let Value::Object(options) = options {
                options.insert("possessions".into(), json!(p));
            }
        }
    }
    let given = match (args.duration_s, args.possessions) {
        (None, None) => "",
        _ => " (with --duration-s or --possessions)",
    };
    Scenario::from_value(value)
        .map_err(|e| anyhow::anyhow!("{}{given}: {e}", args.scenario.display()))
}

pub(super) fn run(args: RunArgs, out: &mut impl Write) -> anyhow::Result<()> {
    let mut scenario = scenario_of(&args).map_err(super::bad_input)?;
    match args.bots.as_deref() {
        None => {
            if let Some(i) = scenario.agents.iter().position(|a| a.bot) {
                return Err(super::bad_input(anyhow::anyhow!(
                    "{}: agents[{i}].bot: a headless run has no bots; pass --bots builtin to play them with their built-in brains",
                    args.scenario.display()
                )));
            }
        }
        Some("builtin") => {}
        Some(other) => {
            return Err(super::bad_input(anyhow::anyhow!(
                "--bots {other}: the only choice is builtin"
            )))
        }
    }
    // Headless: as fast as possible, whatever mode the scenario is for.
    scenario.mode = fieldhouse::sim::Mode::Fast;
    for a in &mut scenario.agents {
        a.bot = false;
    }
    let o = &scenario.options;
    if scenario.duration_s.is_none() && o.possessions.is_none() && o.launches.is_none() {
        return Err(super::bad_input(anyhow::anyhow!(
            "{}: a headless run needs an end: pass --duration-s S (or --possessions N for basketball), \
             or give the scenario duration_s, options.possessions (basketball) or options.launches (fly balls)",
            args.scenario.display()
        )));
    }
    let caps = match scenario.sport {
        Sport::Basketball => Some(args.capability.load()?),
        _ => None,
    };
    let motion = caps
        .as_ref()
        .map_or("none".to_string(), |c| c.source.fingerprint().to_string());
    // Spectators read where the motion came from in words; the header keeps the
    // fingerprint a verification needs.
    let source = caps
        .as_ref()
        .map_or(String::new(), |c| c.source.to_string());
    // What the world refuses is the scenario's (an unknown strategy, a bad launch).
    let world = World::new(&scenario, caps)
        .map_err(|e| super::bad_input(anyhow::anyhow!("{}: {e}", args.scenario.display())))?;
    let stem = args
        .scenario
        .file_stem()
        .map_or("match".to_string(), |s| s.to_string_lossy().into_owned());
    // The match is named after its file; the scenario's name stays in the header.
    let id = stem.clone();
    let info = world.match_info(id.clone(), &scenario, Mode::Fast, source);
    let path = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("{stem}.jsonl.zst")));
    let header = replay::header(
        &info,
        &scenario,
        &motion,
        fieldhouse_server::wall::since_epoch(),
    );
    let encoding = Encoding::for_path(&path);
    let recorder = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&path)
        .and_then(|file| Recorder::new(std::io::BufWriter::new(file), &header, encoding))
        .with_context(|| {
            format!(
                "cannot create {} (an existing file is never overwritten)",
                path.display()
            )
        })?;
    let write_error = |e: std::io::Error| anyhow::anyhow!("writing {}: {e}", path.display());
    let mut recorder = Background::start(recorder).map_err(write_error)?;
    let mut session = Session::new(world, id, scenario.tick_hz, scenario.frame_hz);
    recorder
        .frame(|out| {
            session.frame_into(out);
            true
        })
        .map_err(write_error)?;
    let end_tick = scenario
        .duration_s
        .map(|d| (d * scenario.tick_hz).round() as u64);
    // Long runs show progress on stderr: by ticks when the scenario has a duration (an
    // hour of play or more), else by possessions (500 or more).
    let possessions = scenario.options.possessions;
    let (total, unit) = match (end_tick, possessions) {
        (Some(t), _) => (Some(t).filter(|&t| t >= 60 * 60 * 60), "ticks"),
        (None, Some(p)) => (Some(p).filter(|&p| p >= 500), "possessions"),
        (None, None) => (None, ""),
    };
    let bar = total.map(|t| {
        let template = format!("[{{bar:30}}] {{pos}}/{{len}} {unit} ({{eta}})");
        ProgressBar::new(t)
            .with_style(ProgressStyle::with_template(&template).expect("template is valid"))
    });
    let progress = |world: &World| match unit {
        "ticks" => world.tick(),
        _ => match world.result() {
            Score::Hoops(score) => score.possession,
            Score::Fly(_) => 0,
        },
    };
    let started = Instant::now();
    let mut frames = 1u64;
    while !session.world.finished() {
        if recorder
            .frame(|out| session.step_into(out))
            .map_err(write_error)?
        {
            frames += 1;
        }
        if let Some(b) = &bar {
            if session.world.tick().is_multiple_of(600) {
                b.set_position(progress(&session.world));
            }
        }
    }
    if session.last_frame_due() {
        recorder
            .frame(|out| {
                session.frame_into(out);
                true
            })
            .map_err(write_error)?;
        frames += 1;
    }
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    // The run's time includes writing every frame (the writer catching up), not the
    // footer and the sync to disk.
    let recorder = recorder.done().map_err(write_error)?;
    let elapsed_s = started.elapsed().as_secs_f64();
    let tick = session.world.tick();
    let result = serde_json::to_value(session.world.result()).expect("scores serialise");
    recorder
        .finish(tick, "finished", &result)
        .map_err(write_error)?;
    let simulated_s = session.world.time_s();
    let summary = summary(&result);
    if args.json {
        let doc = json!({
            "file": path,
            "sport": scenario.sport.name(),
            "frames": frames,
            "ticks": tick,
            "simulated_s": simulated_s,
            "elapsed_s": elapsed_s,
            "simulated_s_per_s": simulated_s / elapsed_s.max(1e-9),
            "result": result,
            "summary": summary,
        });
        writeln!(out, "{doc}")?;
        return Ok(());
    }
    writeln!(
        out,
        "{}: {} simulated s in {} s ({}× real time); {} to {}",
        scenario.sport.name(),
        figure(simulated_s, 2),
        figure(elapsed_s, 2),
        figure(simulated_s / elapsed_s.max(1e-9), 0),
        plural(frames, "frame"),
        path.display()
    )?;
    writeln!(out, "{summary}")?;
    Ok(())
}

/// A match's result (or score so far) in words: points per possession for basketball,
/// catches for fly balls; what a replay's footer and a bot's progress say too.
pub(super) fn summary(result: &Value) -> String {
    let count = |key: &str| result[key].as_u64().unwrap_or(0);
    if result.get("points").is_some() {
        let (points, possessions) = (count("points"), count("possession"));
        format!(
            "{} in {} ({:.3} per possession)",
            plural(points, "point"),
            plural(possessions, "possession"),
            points as f64 / possessions.max(1) as f64
        )
    } else {
        format!(
            "{}: {} caught, {} landed",
            plural(count("balls"), "ball"),
            count("caught"),
            count("dropped")
        )
    }
}
