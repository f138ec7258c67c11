//! Reading a whole replay file back, up to its first torn or unreadable record: for
//! tools, and for verifying a match (the server reads through an [`super::Index`]).

use super::chunks;
use super::format::{first_tick, Encoding};
use super::peek::parse_header;
use crate::sim::{Action, Scenario};
use serde_json::Value;
use sha2::{Digest, Sha256};

/// A bot's log entry, as read back.
#[derive(Debug, Clone, PartialEq)]
pub enum Logged {
    /// A bot took or gave back an agent.
    Control {
        /// The tick it happened after.
        tick: u64,
        /// The agent's id.
        agent: String,
        /// `true`: a bot took it; `false`: its built-in brain has it back.
        bot: bool,
    },
    /// A command the world accepted.
    Command {
        /// The tick it was applied after.
        tick: u64,
        /// The agent's id.
        agent: String,
        /// What the agent was told.
        action: Action,
    },
}

impl Logged {
    /// The tick the entry takes effect after.
    pub fn tick(&self) -> u64 {
        match self {
            Logged::Control { tick, .. } | Logged::Command { tick, .. } => *tick,
        }
    }
}

/// A replay read back: everything up to the first torn or unreadable record.
#[derive(Debug, Clone)]
pub struct Replay {
    /// The header record (see [the replay module](super)).
    pub header: Value,
    /// The scenario the header records, parsed.
    pub scenario: Scenario,
    /// Frame lines, exactly as written, with their ticks.
    pub frames: Vec<(u64, String)>,
    /// The bot log, in file order.
    pub log: Vec<Logged>,
    /// The footer record, if the file has one.
    pub footer: Option<Value>,
    /// Why reading stopped early (a torn last record, or the line that did not parse).
    pub problem: Option<String>,
    /// Whether `problem` is damage (bytes that do not read where the file goes on: a
    /// whole line that is not a record, a chunk that does not decompress) rather than a
    /// cut end (a torn last record, a file cut mid-chunk or before its trailer). A cut
    /// file's readable part is all it has; a damaged file has lost what came after.
    pub damaged: bool,
}

impl Replay {
    /// Whether the file ends with its footer and nothing is missing.
    pub fn complete(&self) -> bool {
        self.footer.is_some() && self.problem.is_none()
    }

    /// The hash of the frames read, as the footer computes it.
    pub fn frames_hash(&self) -> String {
        let mut hasher = Sha256::new();
        for (_, line) in &self.frames {
            hasher.update(line.as_bytes());
            hasher.update(b"\n");
        }
        hex::encode(hasher.finalize())
    }

    /// The id of the match recorded.
    pub fn match_id(&self) -> &str {
        self.header["match"]["id"].as_str().unwrap_or_default()
    }

    /// The tick this file starts at: 0, or where its segment of a rotated recording
    /// begins (see [the replay module](super)).
    pub fn first_tick(&self) -> u64 {
        first_tick(&self.header)
    }
}

/// The JSON lines a replay file's bytes hold, and why they end before the file does, if
/// they do: format 1's bytes as they are; format 2's whole chunks decompressed (what
/// `zstdcat` prints) up to the first that does not read.
pub fn decode(bytes: &[u8]) -> Result<(Vec<u8>, Option<String>), String> {
    match Encoding::of(bytes)? {
        Encoding::Plain => Ok((bytes.to_vec(), None)),
        Encoding::Zstd => {
            let unpacked = chunks::unpack(bytes);
            Ok((unpacked.text, unpacked.problem))
        }
    }
}

/// Reads a replay from its bytes, in either encoding. Only a missing or unreadable
/// header is an error: anything after it that does not read is where the readable
/// prefix ends. It takes the whole file: for tools run on a file of one's own (the CLI
/// reads it), never for the server, which reads through an [`Index`](super::Index).
pub fn parse(bytes: &[u8]) -> Result<Replay, String> {
    match Encoding::of(bytes)? {
        Encoding::Plain => parse_lines(bytes),
        Encoding::Zstd => {
            let unpacked = chunks::unpack(bytes);
            if unpacked.text.is_empty() {
                let why = unpacked.problem.unwrap_or_else(|| "no chunk".into());
                return Err(format!("its first chunk does not read: {why}"));
            }
            let mut replay = parse_lines(&unpacked.text)?;
            if replay.problem.is_none() {
                (replay.problem, replay.damaged) = match unpacked.problem {
                    Some(problem) => (Some(problem), unpacked.damaged),
                    None => match (&replay.footer, unpacked.trailer) {
                        (Some(_), false) => (Some(NO_TRAILER.into()), false),
                        (None, true) => (Some("the file has a trailer but no footer".into()), true),
                        _ => (None, false),
                    },
                };
            }
            Ok(replay)
        }
    }
}

/// The problem of a format 2 file whose footer is not followed by its trailer.
const NO_TRAILER: &str =
    "the footer is not followed by the trailer (the file was cut as it was finished)";

/// Reads format 1's lines (or format 2's, decompressed).
fn parse_lines(bytes: &[u8]) -> Result<Replay, String> {
    let mut lines = bytes.split_inclusive(|&b| b == b'\n');
    let first = lines.next().ok_or("the file is empty")?;
    let (header, scenario) = parse_header(first)?;
    let mut replay = Replay {
        header,
        scenario,
        frames: Vec::new(),
        log: Vec::new(),
        footer: None,
        problem: None,
        damaged: false,
    };
    for (k, raw) in lines.enumerate() {
        let number = k + 2;
        let Some(line) = std::str::from_utf8(raw)
            .ok()
            .and_then(|l| l.strip_suffix('\n'))
        else {
            replay.problem = Some(format!(
                "line {number} is torn (the file was cut mid-record)"
            ));
            return Ok(replay);
        };
        let record: Value = match serde_json::from_str(line) {
            Ok(v) => v,
            Err(e) => {
                replay.problem = Some(format!("line {number} is not a record: {e}"));
                break;
            }
        };
        if replay.footer.is_some() {
            replay.problem = Some(format!("line {number} follows the footer"));
            break;
        }
        let tick = record["tick"].as_u64();
        let agent = record["agent"].as_str().map(str::to_string);
        match (record["type"].as_str(), record["record"].as_str(), tick) {
            (Some("frame"), _, Some(t)) => replay.frames.push((t, line.to_string())),
            (_, Some("command"), Some(tick)) => {
                let action = serde_json::from_value(record["action"].clone());
                match (agent, action) {
                    (Some(agent), Ok(action)) => replay.log.push(Logged::Command {
                        tick,
                        agent,
                        action,
                    }),
                    _ => {
                        replay.problem = Some(format!(
                            "line {number}: a command record without agent or action"
                        ));
                        break;
                    }
                }
            }
            (_, Some("control"), Some(tick)) => match (agent, record["bot"].as_bool()) {
                (Some(agent), Some(bot)) => replay.log.push(Logged::Control { tick, agent, bot }),
                _ => {
                    replay.problem = Some(format!(
                        "line {number}: a control record without agent or bot"
                    ));
                    break;
                }
            },
            (_, Some("footer"), _) => replay.footer = Some(record),
            _ => {
                replay.problem = Some(format!(
                    "line {number} is not a frame, command, control or footer record"
                ));
                break;
            }
        }
    }
    // Reading stops early only at a torn last line (returned above) or at a whole line
    // that does not read: damage.
    replay.damaged = replay.problem.is_some();
    Ok(replay)
}
