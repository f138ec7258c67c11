//! Checking a replay by playing it again: the scenario, its seed and the bot log drive a
//! fresh world, and every frame it makes must equal the recorded one, byte for byte,
//! written in the protocol version the file recorded (a file of protocol 2 has frames
//! without the fields version 3 added).

use super::{Logged, Replay};
use crate::basketball::Capabilities;
use crate::protocol::FrameShape;
use crate::session::Session;
use crate::sim::World;
use serde_json::Value;
use std::fmt;
use std::sync::Arc;

/// A replay that played back identically.
#[derive(Debug, Clone, PartialEq)]
pub struct Verified {
    /// Frames compared.
    pub frames: usize,
    /// The tick the re-simulation reached (from tick 0).
    pub ticks: u64,
}

/// Why a replay did not verify.
#[derive(Debug, Clone, PartialEq)]
pub enum Mismatch {
    /// The world could not be rebuilt (its scenario, or the motion data, is wrong).
    Unplayable(String),
    /// The first frame that differs, and where in it.
    Frame {
        /// The frame's tick.
        tick: u64,
        /// The first field that differs, as a path into the frame (`agents[2].position`).
        field: String,
        /// Its value in the file.
        recorded: String,
        /// Its value re-simulated.
        replayed: String,
    },
    /// The replay has frames the re-simulation never made, or the other way round.
    Count {
        /// Frames in the file.
        recorded: usize,
        /// Frames the re-simulation made.
        replayed: usize,
    },
    /// A frame or the count differed, and the file was recorded by another version of
    /// the simulation, which is the likely reason.
    Simulation {
        /// The version in the file's header.
        recorded: u32,
        /// The difference found.
        first: Box<Mismatch>,
    },
    /// The footer's hash is not the hash of the frames.
    Hash {
        /// The footer's hash, hex.
        footer: String,
        /// The hash of the frames read, hex.
        frames: String,
    },
}

impl fmt::Display for Mismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Mismatch::Unplayable(why) => write!(f, "cannot re-simulate: {why}"),
            Mismatch::Frame {
                tick,
                field,
                recorded,
                replayed,
            } => write!(
                f,
                "tick {tick}: {field} differs: recorded {recorded}, re-simulated {replayed}"
            ),
            Mismatch::Count { recorded, replayed } => write!(
                f,
                "the file has {recorded} frames, the re-simulation made {replayed}"
            ),
            Mismatch::Simulation { recorded, first } => write!(
                f,
                "{first}; the replay was recorded by simulation version {recorded} and this \
                 build simulates version {}: only the simulation that recorded a replay can \
                 re-simulate it (its frames still play and export)",
                crate::sim::VERSION
            ),
            Mismatch::Hash { footer, frames } => {
                write!(
                    f,
                    "the footer's hash {footer} is not the frames' hash {frames}"
                )
            }
        }
    }
}

/// The first place two JSON values differ, as a path (`agents[1].position[0]`).
fn first_difference(a: &Value, b: &Value, path: &str) -> Option<(String, String, String)> {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let mut keys: Vec<&String> = x.keys().chain(y.keys()).collect();
            keys.dedup();
            keys.into_iter().find_map(|k| {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                first_difference(
                    x.get(k).unwrap_or(&Value::Null),
                    y.get(k).unwrap_or(&Value::Null),
                    &p,
                )
            })
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .find_map(|(i, (p, q))| first_difference(p, q, &format!("{path}[{i}]"))),
        _ if a == b => None,
        _ => Some((path.to_string(), a.to_string(), b.to_string())),
    }
}

/// Carries out one entry of the bot log, as the server did between two ticks.
fn apply(world: &mut World, ids: &[String], entry: &Logged) -> Result<(), Mismatch> {
    let agent = match entry {
        Logged::Control { agent, .. } | Logged::Command { agent, .. } => agent,
    };
    let k = ids.iter().position(|a| a == agent).ok_or_else(|| {
        Mismatch::Unplayable(format!(
            "the log names an agent \"{agent}\" the match does not have"
        ))
    })?;
    match entry {
        Logged::Control { bot, .. } => world.set_controlled(k, *bot),
        Logged::Command { action, tick, .. } => world
            .command(k, action)
            .map_err(|e| Mismatch::Unplayable(format!("tick {tick}: {e}")))?,
    }
    Ok(())
}

/// Re-simulates `replay` and compares every frame (from its first tick, for a later
/// segment of a rotated recording). Basketball needs the motion capabilities the match
/// was played with.
pub fn verify(replay: &Replay, caps: Option<Arc<Capabilities>>) -> Result<Verified, Mismatch> {
    let recorded = super::simulation(&replay.header);
    resimulate(replay, caps).map_err(|first| match first {
        Mismatch::Frame { .. } | Mismatch::Count { .. } if recorded != crate::sim::VERSION => {
            Mismatch::Simulation {
                recorded,
                first: Box::new(first),
            }
        }
        other => other,
    })
}

/// [`verify`] without the explanation of a version change.
fn resimulate(replay: &Replay, caps: Option<Arc<Capabilities>>) -> Result<Verified, Mismatch> {
    let s = &replay.scenario;
    let world = World::new(s, caps).map_err(|e| Mismatch::Unplayable(e.to_string()))?;
    // A file cut before its first frame was written (in format 2, before its first
    // chunk was) has nothing to compare: its scenario plays, which is all it says.
    if replay.frames.is_empty() && replay.footer.is_none() {
        return Ok(Verified {
            frames: 0,
            ticks: 0,
        });
    }
    let shape =
        FrameShape::of_version(super::protocol(&replay.header)).map_err(Mismatch::Unplayable)?;
    let mut session =
        Session::new(world, replay.match_id().to_string(), s.tick_hz, s.frame_hz).in_shape(shape);
    let ids = session.world.agent_ids();
    let end_tick = replay
        .footer
        .as_ref()
        .and_then(|f| f["tick"].as_u64())
        .or_else(|| replay.frames.last().map(|(t, _)| *t))
        .unwrap_or(0);
    let mut log = replay.log.iter().peekable();
    let mut made = 0usize;
    // A later segment of a rotated recording holds frames from its first tick on: the
    // world is played from tick 0 as always, and compared from there.
    let first_tick = replay.first_tick();
    let compare = |line: String, made: &mut usize| -> Result<(), Mismatch> {
        let made_at = || serde_json::from_str::<Value>(&line).ok()?["tick"].as_u64();
        if first_tick > 0 && made_at().is_some_and(|t| t < first_tick) {
            return Ok(());
        }
        let Some((tick, recorded)) = replay.frames.get(*made) else {
            *made += 1;
            return Ok(()); // counted below
        };
        *made += 1;
        if *recorded == line {
            return Ok(());
        }
        let (a, b): (Value, Value) = (
            serde_json::from_str(recorded).unwrap_or(Value::Null),
            serde_json::from_str(&line).unwrap_or(Value::Null),
        );
        let (field, recorded, replayed) = first_difference(&a, &b, "")
            .unwrap_or_else(|| ("(formatting)".into(), recorded.clone(), line.clone()));
        Err(Mismatch::Frame {
            tick: *tick,
            field,
            recorded,
            replayed,
        })
    };
    // The frame a match starts with, before any tick.
    compare(session.frame(), &mut made)?;
    loop {
        while let Some(entry) = log.next_if(|e| e.tick() <= session.world.tick()) {
            apply(&mut session.world, &ids, entry)?;
        }
        if session.world.tick() >= end_tick || session.world.finished() {
            break;
        }
        if let Some(frame) = session.step() {
            compare(frame, &mut made)?;
        }
    }
    if made < replay.frames.len() {
        if let Some(frame) = session.last_frame() {
            compare(frame, &mut made)?;
        }
    }
    if made != replay.frames.len() {
        return Err(Mismatch::Count {
            recorded: replay.frames.len(),
            replayed: made,
        });
    }
    // Every frame matched; the footer must vouch for exactly these frames.
    if let Some(footer) = &replay.footer {
        let frames = replay.frames_hash();
        let recorded = footer["hash"].as_str().unwrap_or_default();
        if recorded != frames {
            return Err(Mismatch::Hash {
                footer: recorded.to_string(),
                frames,
            });
        }
    }
    Ok(Verified {
        frames: replay.frames.len(),
        ticks: session.world.tick(),
    })
}
