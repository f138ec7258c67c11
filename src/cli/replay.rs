//! `fieldhouse replay info | verify | export`: what a replay file holds, whether it plays
//! back identically, and its positions as CSV.

use super::basketball::CapabilityArgs;
use clap::{Args, Subcommand};
use fieldhouse::replay::{self, Replay};
use fieldhouse::sim::Sport;
use serde_json::{json, Value};
use std::io::Write;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ReplayArgs {
    #[command(subcommand)]
    command: ReplayCommand,
}

#[derive(Subcommand, Debug)]
enum ReplayCommand {
    /// The header, result, frames and duration, and whether the file is complete.
    Info {
        file: PathBuf,
        /// Print one JSON document.
        #[arg(long)]
        json: bool,
    },
    /// Re-simulate from the scenario, seed and bot log; compare every frame. Exits
    /// non-zero, naming the first differing tick and field, if anything differs.
    Verify {
        file: PathBuf,
        #[command(flatten)]
        capability: CapabilityArgs,
    },
    /// Positions for other tools: one CSV row per agent (and one for the ball) per frame.
    Export {
        file: PathBuf,
        /// Write CSV (the only format).
        #[arg(long, required = true)]
        csv: bool,
    },
}

pub fn run(args: ReplayArgs, out: &mut impl Write) -> anyhow::Result<()> {
    match args.command {
        ReplayCommand::Info { file, json } => info(&replay::read(&file)?, json, out),
        ReplayCommand::Verify { file, capability } => {
            let replay = replay::read(&file)?;
            let caps = match replay.scenario.sport {
                Sport::Basketball => {
                    let caps = capability.load()?;
                    let recorded = replay.header["motion"].as_str().unwrap_or_default();
                    anyhow::ensure!(
                        recorded == caps.source.fingerprint(),
                        "{} was recorded with motion data {recorded}; this run has {} (pass the same --mocap)",
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
                "{}: verified: {} frames over {} ticks re-simulate identically{}",
                file.display(),
                verified.frames,
                verified.ticks,
                if replay.complete() {
                    ""
                } else {
                    " (the file is incomplete; its readable part was checked)"
                }
            )?;
            Ok(())
        }
        ReplayCommand::Export { file, .. } => export(&replay::read(&file)?, out),
    }
}

fn info(replay: &Replay, as_json: bool, out: &mut impl Write) -> anyhow::Result<()> {
    let tick_hz = replay.scenario.tick_hz;
    let last_tick = replay.frames.last().map_or(0, |(t, _)| *t);
    let footer = replay.footer.clone().unwrap_or(Value::Null);
    let doc = json!({
        "format": replay.header["format"],
        "fieldhouse": replay.header["fieldhouse"],
        "match": replay.match_id(),
        "sport": replay.scenario.sport.name(),
        "name": replay.scenario.name,
        "seed": replay.scenario.seed,
        "motion": replay.header["motion"],
        "frames": replay.frames.len(),
        "commands": replay.log.len(),
        "ticks": last_tick,
        "duration_s": last_tick as f64 / tick_hz,
        "complete": replay.complete(),
        "problem": replay.problem,
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
        "{} replay of match {} ({}), seed {}, fieldhouse {}",
        doc["sport"].as_str().unwrap_or_default(),
        replay.match_id(),
        replay.scenario.name.as_deref().unwrap_or("unnamed"),
        replay.scenario.seed,
        doc["fieldhouse"].as_str().unwrap_or("?")
    )?;
    writeln!(
        out,
        "  {} frames, {} bot log entries, {:.1} s of play ({} ticks at {} Hz)",
        replay.frames.len(),
        replay.log.len(),
        doc["duration_s"].as_f64().unwrap_or(0.0),
        last_tick,
        tick_hz
    )?;
    match (&replay.footer, &replay.problem) {
        (Some(f), None) => writeln!(out, "  complete: {} with {}", f["reason"], f["result"])?,
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

fn export(replay: &Replay, out: &mut impl Write) -> anyhow::Result<()> {
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
