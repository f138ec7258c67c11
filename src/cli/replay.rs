//! `fieldhouse replay info | verify | export | paths`: what a replay file holds, whether it
//! plays back identically, its positions for other tools, and its fielders' runs measured.

use super::basketball::CapabilityArgs;
use anyhow::Context;
use clap::{Args, Subcommand, ValueEnum};
use fieldhouse::replay::{self, Replay};
use fieldhouse::sim::Sport;
use fieldhouse::words::{figure, plural};
use serde_json::{json, Value};
use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub(super) struct ReplayArgs {
    #[command(subcommand)]
    command: ReplayCommand,
}

#[derive(Subcommand, Debug)]
enum ReplayCommand {
    /// The header, result, frames and duration, and whether the file is complete.
    Info {
        /// The replay file: JSON lines (format 1) or zstd chunks of them (format 2).
        file: PathBuf,
        /// Print one JSON document.
        #[arg(long)]
        json: bool,
    },
    /// Re-simulate from the scenario, seed and bot log; compare every frame. Exits
    /// non-zero, naming the first differing tick and field, if anything differs.
    #[command(after_help = "Exit codes:\n  \
        0  the whole file verified: every frame re-simulates identically, and it ends with its footer\n  \
        1  a frame differs, the file is damaged (a line or chunk that does not read where the file \
        goes on: it names the line, or the chunk and its byte), or it cannot be read or re-simulated\n  \
        2  bad arguments\n  \
        3  the file is cut at its end (a crash, or a match still recording): its readable part \
        re-simulates identically")]
    Verify {
        /// The replay file: JSON lines (format 1) or zstd chunks of them (format 2).
        file: PathBuf,
        #[command(flatten)]
        capability: CapabilityArgs,
    },
    /// Positions for other tools, on stdout: CSV by default, or the frames as JSON lines.
    #[command(after_help = "Formats (--format):\n  \
        csv    one row per frame for the ball and one for each agent, under the header \
        tick,time_s,agent,x,y,z,heading: the ball's row has agent \"ball\", its x, y (height) \
        and z, and no heading; an agent's row has its id, its ground position x and z, no y, \
        and its heading (radians from +x toward +z). Metres and seconds. --csv is the same.\n  \
        jsonl  the frame messages exactly as the WebSocket protocol sends them (PROTOCOL.md), \
        one a line, with every field: for jq and other JSON tools.\n\
        Example: fieldhouse replay export papers.jsonl.zst > papers.csv")]
    Export {
        /// The replay file: JSON lines (format 1) or zstd chunks of them (format 2).
        file: PathBuf,
        /// What to write: csv or jsonl (see below).
        #[arg(long, value_enum, default_value_t = ExportFormat::Csv)]
        format: ExportFormat,
        /// The same as --format csv (the default), kept for scripts that pass it.
        #[arg(long, conflicts_with = "format")]
        csv: bool,
    },
    /// Every fielder's run under every fly ball, measured as `catch-sweep` measures the
    /// built-in strategies: catches, path shape and bulge, ṙ drift, image bend and the
    /// bearing's sweep (docs/catching.md). For bots, whose brains the server cannot see.
    #[command(
        after_help = "Record every tick (\"frame_hz\" equal to \"tick_hz\") for the measures to \
        see every look; a file at 30 Hz gives them every other one.\n\
        Example: fieldhouse run balls.toml --out balls.jsonl && fieldhouse replay paths balls.jsonl"
    )]
    Paths {
        /// The replay file: JSON lines (format 1) or zstd chunks of them (format 2).
        file: PathBuf,
        /// Print one JSON document: a summary per fielder and every run.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ExportFormat {
    /// Positions, a row per ball or agent per frame.
    Csv,
    /// The frame messages, one a line.
    Jsonl,
}

/// Reads a whole replay file (for a file of one's own: the server reads through an
/// index). Only a missing or unreadable header is an error: anything after it that does
/// not read is where the readable prefix ends.
fn read(path: &Path) -> anyhow::Result<Replay> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    replay::parse(&bytes)
        .map_err(|reason| anyhow::anyhow!("{}: not a fieldhouse replay: {reason}", path.display()))
}

pub(super) fn run(args: ReplayArgs, out: &mut impl Write) -> anyhow::Result<()> {
    match args.command {
        ReplayCommand::Info { file, json } => info(&read(&file)?, json, out),
        ReplayCommand::Verify { file, capability } => {
            let replay = read(&file)?;
            if replay.damaged {
                anyhow::bail!(
                    "{} is damaged: {} ({} before it read)",
                    file.display(),
                    replay.problem.as_deref().unwrap_or("unreadable"),
                    plural(replay.frames.len() as u64, "frame")
                );
            }
            let caps = match replay.scenario.sport {
                Sport::Basketball => {
                    let caps = capability.load()?;
                    let recorded = replay.header["motion"].as_str().unwrap_or_default();
                    // A replay from another simulation could not re-simulate even with
                    // its motion: say so first, as for the other sports.
                    let simulation = replay.header["simulation"].as_u64().unwrap_or(1);
                    let version = if simulation == u64::from(fieldhouse::sim::VERSION) {
                        String::new()
                    } else {
                        format!(
                            "; it was also recorded by simulation version {simulation} and this build simulates version {}: only the simulation that recorded a replay can re-simulate it (its frames still play and export)",
                            fieldhouse::sim::VERSION
                        )
                    };
                    anyhow::ensure!(
                        recorded == caps.source.fingerprint(),
                        "{} was recorded with motion data {recorded}; this run has {} (pass the same --mocap){version}",
                        file.display(),
                        caps.source.fingerprint()
                    );
                    Some(caps)
                }
                _ => None,
            };
            let verified = replay::verify(&replay, caps)
                .map_err(|m| anyhow::anyhow!("{}: {m}", file.display()))?;
            writeln!(
                out,
                "{}: verified: {} over {} re-simulate identically{}",
                file.display(),
                plural(verified.frames as u64, "frame"),
                plural(verified.ticks, "tick"),
                if replay.complete() {
                    ""
                } else {
                    " (the file is incomplete; its readable part was checked)"
                }
            )?;
            if replay.complete() {
                return Ok(());
            }
            Err(super::Outcome {
                code: 3,
                message: format!(
                    "{} is cut at its end ({}): its readable part verifies",
                    file.display(),
                    replay.problem.as_deref().unwrap_or("no footer yet")
                ),
            }
            .into())
        }
        ReplayCommand::Export { file, format, .. } => {
            let replay = read(&file)?;
            match format {
                ExportFormat::Csv => export_csv(&replay, out),
                ExportFormat::Jsonl => export_frames(&replay, out),
            }
        }
        ReplayCommand::Paths { file, json } => super::paths::paths(&read(&file)?, json, out),
    }
}

fn info(replay: &Replay, as_json: bool, out: &mut impl Write) -> anyhow::Result<()> {
    let tick_hz = replay.scenario.tick_hz;
    let last_tick = replay.frames.last().map_or(0, |(t, _)| *t);
    let footer = replay.footer.clone().unwrap_or(Value::Null);
    let doc = json!({
        "format": replay.header["format"],
        "fieldhouse": replay.header["fieldhouse"],
        "simulation": fieldhouse::replay::simulation(&replay.header),
        "match": replay.match_id(),
        "sport": replay.scenario.sport.name(),
        "name": replay.scenario.name,
        "seed": replay.scenario.seed,
        "motion": replay.header["motion"],
        "segment": replay.header["segment"].as_u64().unwrap_or(0),
        "first_tick": replay.first_tick(),
        "previous": replay.header["previous"],
        "frames": replay.frames.len(),
        "commands": replay.log.len(),
        "ticks": last_tick,
        "duration_s": last_tick.saturating_sub(replay.first_tick()) as f64 / tick_hz,
        "complete": replay.complete(),
        "problem": replay.problem,
        "damaged": replay.damaged,
        "reason": footer["reason"],
        "result": footer["result"],
        "hash": footer["hash"],
        "hash_ok": replay.footer.as_ref().map(|f| f["hash"].as_str() == Some(replay.frames_hash().as_str())),
    });
    if as_json {
        writeln!(out, "{doc}")?;
        return Ok(());
    }
    writeln!(
        out,
        "{} replay of match {} ({}), seed {}, fieldhouse {}, simulation {}",
        doc["sport"].as_str().unwrap_or_default(),
        replay.match_id(),
        replay.scenario.name.as_deref().unwrap_or("unnamed"),
        replay.scenario.seed,
        doc["fieldhouse"].as_str().unwrap_or("?"),
        doc["simulation"]
    )?;
    writeln!(
        out,
        "  {}, {}, {} s of play ({} at {} Hz)",
        plural(replay.frames.len() as u64, "frame"),
        plural(replay.log.len() as u64, "bot log entry"),
        figure(doc["duration_s"].as_f64().unwrap_or(0.0), 2),
        plural(last_tick, "tick"),
        figure(tick_hz, 2)
    )?;
    if replay.first_tick() > 0 {
        writeln!(
            out,
            "  part {} of a rotated recording, from tick {} (the part before: {})",
            doc["segment"].as_u64().unwrap_or(0) + 1,
            replay.first_tick(),
            doc["previous"].as_str().unwrap_or("unknown")
        )?;
    }
    match (&replay.footer, &replay.problem) {
        (Some(f), None) => writeln!(
            out,
            "  complete: {}; {}",
            f["reason"].as_str().unwrap_or("ended"),
            super::run::summary(&f["result"])
        )?,
        (_, Some(problem)) if replay.damaged => writeln!(
            out,
            "  DAMAGED: {problem}; the records before it read back, what follows it is lost"
        )?,
        (_, Some(problem)) => writeln!(
            out,
            "  INCOMPLETE: {problem}; the records before it read back"
        )?,
        (None, None) => writeln!(
            out,
            "  INCOMPLETE: no footer (the match was still running or the process died)"
        )?,
    }
    Ok(())
}

/// The frames as recorded, which are the very messages spectators were sent.
fn export_frames(replay: &Replay, out: &mut impl Write) -> anyhow::Result<()> {
    for (_, line) in &replay.frames {
        writeln!(out, "{line}")?;
    }
    Ok(())
}

fn export_csv(replay: &Replay, out: &mut impl Write) -> anyhow::Result<()> {
    writeln!(out, "tick,time_s,agent,x,y,z,heading")?;
    for (_, line) in &replay.frames {
        let frame: Value = serde_json::from_str(line)?;
        let (tick, time) = (&frame["tick"], &frame["time_s"]);
        let b = &frame["ball"]["position"];
        writeln!(out, "{tick},{time},ball,{},{},{},", b[0], b[1], b[2])?;
        for a in frame["agents"].as_array().into_iter().flatten() {
            let p = &a["position"];
            writeln!(
                out,
                "{tick},{time},{},{},,{},{}",
                a["id"].as_str().unwrap_or_default(),
                p[0],
                p[1],
                a["heading"]
            )?;
        }
    }
    Ok(())
}
