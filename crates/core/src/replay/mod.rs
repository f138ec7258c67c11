//! Replay files: what happened in a match, kept so it can be watched and checked later.
//!
//! **Encoding**: JSON lines (UTF-8, one record per line, `\n`-terminated), uncompressed:
//!
//! 1. a header: `{"record": "header", "format": 1, "fieldhouse": "0.1.0", "match": {...},
//!    "scenario": {...}, "seed": 1, "motion": "<fingerprint>", "started_unix_ms": ...}`;
//! 2. the `frame` messages of the wire protocol, byte for byte, in order, interleaved
//!    with the bot log: `{"record": "control", "tick": t, "agent": "cf", "bot": true}`
//!    when a bot takes or gives back an agent, and `{"record": "command", "tick": t,
//!    "agent": "cf", "action": {...}}` for every command the world accepted, applied
//!    after tick `t`;
//! 3. a footer: `{"record": "footer", "tick": t, "frames": n, "hash": "<sha256>",
//!    "reason": "finished", "result": {...}}`, the hash over every frame line and its
//!    newline. Wall-clock time appears only in the header and is not hashed. Besides
//!    the match's own end reasons (`finished`, `deleted`, `shutdown`), a footer may say
//!    `size_limit` (the server stopped recording at its per-match limit; the match went
//!    on, `result` is null) or `rotated` (see segments; `result` is null).
//!
//! **Segments.** A recording that may never end (the server's real-time matches
//! without bot slots) is rotated into files of bounded size. Every file is a complete
//! replay by itself; a later one's header adds `"segment": n` (1, 2, ...),
//! `"first_tick": t` (the tick of its first frame) and `"previous": "<replay id>"`
//! (the file before it). A file without these fields is segment 0 from tick 0, so files
//! written before segments existed read as they did (the format stays 1: fields were
//! added, none changed meaning). Checking a later segment re-simulates from tick 0 and
//! compares frames from its first tick on, which is exact for matches without bots
//! (the only ones rotated: a bot log would be split across files).
//!
//! Records are appended and flushed as they go (the server's writer flushes after each
//! batch it takes from its queue), so a process killed mid-match leaves complete
//! records behind and at most one torn line, which reading detects and ignores; a
//! finished file is flushed and synced before the match is reported ended.
//!
//! **Reading.** [`read`] and [`parse`] take a whole file, for tools; the server reads
//! through an [`Index`] and [`peek`], which bound every line they read.

mod index;
mod verify;

pub use index::{Index, MAX_LINE_BYTES};
pub use verify::{verify, Mismatch, Verified};

use crate::sim::{Action, Scenario};
use serde::Serialize;
use serde_json::{json, Value};
use sha2::{Digest, Sha256};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Bump when a reader of the old format could not read the new one.
pub const FORMAT: u32 = 1;

/// Where a recorder's bytes go: written, and made durable when the replay is finished.
/// A file syncs to disk; a test's sink may do anything (be slow, fail).
pub trait Durable: Write {
    /// Flushes and makes what was written durable (a file: `fsync`).
    fn sync(&mut self) -> io::Result<()>;
}

impl Durable for io::BufWriter<std::fs::File> {
    fn sync(&mut self) -> io::Result<()> {
        self.flush()?;
        self.get_ref().sync_all()
    }
}

/// Writes a replay as the match goes. Frames are buffered: [`Recorder::flush`] pushes
/// them to the file (the server flushes after each batch it takes from its queue).
pub struct Recorder<W: Durable = io::BufWriter<std::fs::File>> {
    out: W,
    hasher: Sha256,
    frames: u64,
    /// Bytes written so far, header included.
    bytes: u64,
}

/// The header record of a replay: what was played, with what, and when.
pub fn header(match_info: &impl Serialize, scenario: &Scenario, motion: &str) -> Value {
    let started = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64);
    json!({
        "record": "header",
        "format": FORMAT,
        "fieldhouse": env!("CARGO_PKG_VERSION"),
        "match": match_info,
        "scenario": scenario,
        "seed": scenario.seed,
        "motion": motion,
        "started_unix_ms": started,
    })
}

impl Recorder {
    /// Creates `path` (never overwriting a file) and writes the header.
    pub fn create(path: &Path, header: &Value) -> io::Result<Recorder> {
        let file = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(path)?;
        Recorder::new(io::BufWriter::new(file), header)
    }
}

impl<W: Durable> Recorder<W> {
    /// Writes the header to `out` and flushes it.
    pub fn new(out: W, header: &Value) -> io::Result<Recorder<W>> {
        let mut r = Recorder {
            out,
            hasher: Sha256::new(),
            frames: 0,
            bytes: 0,
        };
        r.line(&header.to_string())?;
        r.out.flush()?;
        Ok(r)
    }

    /// Bytes written so far.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// Frames written so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    fn line(&mut self, text: &str) -> io::Result<()> {
        self.bytes += text.len() as u64 + 1;
        self.out.write_all(text.as_bytes())?;
        self.out.write_all(b"\n")
    }

    /// Appends a frame (exactly the bytes sent on the wire).
    pub fn frame(&mut self, frame: &str) -> io::Result<()> {
        self.hasher.update(frame.as_bytes());
        self.hasher.update(b"\n");
        self.frames += 1;
        self.line(frame)
    }

    /// Appends a bot log record (`command` or `control`), already encoded.
    pub fn log(&mut self, record: &str) -> io::Result<()> {
        self.line(record)
    }

    /// Pushes what is buffered to the file, so a process killed after this leaves it.
    pub fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    /// Writes the footer, flushes and syncs: after this the file is complete on disk.
    pub fn finish(mut self, tick: u64, reason: &str, result: &Value) -> io::Result<()> {
        let hash = hex(&self.hasher.clone().finalize());
        let footer = json!({
            "record": "footer",
            "tick": tick,
            "frames": self.frames,
            "hash": hash,
            "reason": reason,
            "result": result,
        });
        self.line(&footer.to_string())?;
        self.out.sync()
    }
}

/// A bot's `command` record: `action`, accepted by the world, applied after `tick`.
pub fn command_record(tick: u64, agent: &str, action: &Action) -> String {
    json!({"record": "command", "tick": tick, "agent": agent, "action": action}).to_string()
}

/// A bot's `control` record: a bot took (`bot: true`) or gave back an agent at `tick`.
pub fn control_record(tick: u64, agent: &str, bot: bool) -> String {
    json!({"record": "control", "tick": tick, "agent": agent, "bot": bot}).to_string()
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

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
    /// The header record (see the module doc).
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
        hex(&hasher.finalize())
    }

    /// The id of the match recorded.
    pub fn match_id(&self) -> &str {
        self.header["match"]["id"].as_str().unwrap_or_default()
    }

    /// The tick this file starts at: 0, or where its segment of a rotated recording
    /// begins (see the module doc).
    pub fn first_tick(&self) -> u64 {
        first_tick(&self.header)
    }
}

/// The tick a file with this header starts at (0 unless it is a later segment).
pub fn first_tick(header: &Value) -> u64 {
    header["first_tick"].as_u64().unwrap_or(0)
}

/// Errors leave their source out of their message: it is the next link of the chain
/// (`{e:#}` shows it), and a message that also showed it would say it twice.
#[derive(Debug, Error)]
pub enum ReplayError {
    /// The file could not be read.
    #[error("cannot read {path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: io::Error,
    },
    /// The file has no readable replay header.
    #[error("{path}: not a fieldhouse replay: {reason}")]
    NotAReplay {
        /// The file.
        path: PathBuf,
        /// What is wrong with its first line.
        reason: String,
    },
}

/// Reads a replay file. Only a missing or unreadable header is an error: anything after
/// it that does not read is where the readable prefix ends. It reads the whole file
/// into memory: for tools run on a file of one's own, never for the server, which reads
/// through an [`Index`].
pub fn read(path: &Path) -> Result<Replay, ReplayError> {
    let bytes = std::fs::read(path).map_err(|source| ReplayError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&bytes).map_err(|reason| ReplayError::NotAReplay {
        path: path.to_path_buf(),
        reason,
    })
}

/// The longest header line read: a first line longer than this is no replay's header
/// (real ones are a few kilobytes), and reading one must not take a line without end.
pub const MAX_HEADER_BYTES: u64 = 1024 * 1024;

/// How much of a file's end is read to find its footer.
const TAIL_BYTES: u64 = 64 * 1024;

/// The header and (if the file is complete) the footer, without reading the frames
/// between them: for listing many large files. Reads at most [`MAX_HEADER_BYTES`] from
/// the start and 64 KiB from the end, whatever the file holds.
pub fn peek(mut file: &std::fs::File) -> Result<(Value, Option<Value>), String> {
    use std::io::{BufRead, Read, Seek, SeekFrom};
    use std::os::unix::fs::FileExt;
    file.seek(SeekFrom::Start(0)).map_err(|e| e.to_string())?;
    let mut first = Vec::new();
    io::BufReader::new(file.take(MAX_HEADER_BYTES))
        .read_until(b'\n', &mut first)
        .map_err(|e| e.to_string())?;
    let (header, _) = parse_header(&first)?;
    let len = file.metadata().map_err(|e| e.to_string())?.len();
    let start = len.saturating_sub(TAIL_BYTES);
    let mut tail = vec![0; (len - start) as usize];
    let mut filled = 0;
    while filled < tail.len() {
        match file.read_at(&mut tail[filled..], start + filled as u64) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) => return Err(e.to_string()),
        }
    }
    tail.truncate(filled);
    let footer = tail
        .strip_suffix(b"\n")
        .and_then(|t| t.rsplit(|&b| b == b'\n').next())
        .and_then(|last| serde_json::from_slice::<Value>(last).ok())
        .filter(|v| v["record"] == "footer");
    Ok((header, footer))
}

/// Reads a header line (with its newline): the record and the scenario it describes.
fn parse_header(first: &[u8]) -> Result<(Value, Scenario), String> {
    let header: Value = std::str::from_utf8(first)
        .ok()
        .filter(|l| l.ends_with('\n'))
        .and_then(|l| serde_json::from_str(l).ok())
        .ok_or("the first line is not a complete header record")?;
    if header["record"] != "header" {
        return Err("the first record is not a header".into());
    }
    if header["format"].as_u64() != Some(u64::from(FORMAT)) {
        return Err(format!(
            "format {} (this build reads {FORMAT})",
            header["format"]
        ));
    }
    let scenario = Scenario::from_value(header["scenario"].clone())
        .map_err(|e| format!("its scenario does not read: {e}"))?;
    Ok((header, scenario))
}

/// Reads a replay from its bytes (see [`read`]).
pub fn parse(bytes: &[u8]) -> Result<Replay, String> {
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
            break;
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
    Ok(replay)
}
