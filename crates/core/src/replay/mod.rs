//! Replay files: what happened in a match, kept so it can be watched and checked later.
//!
//! **Records**: JSON lines (UTF-8, one record per line, `\n`-terminated):
//!
//! 1. a header: `{"record": "header", "format": 2, "fieldhouse": "0.1.0", "match": {...},
//!    "scenario": {...}, "seed": 1, "motion": "<fingerprint>", "protocol": 3,
//!    "simulation": 2, "started_unix_ms": ...}`; `protocol` is the version the frames
//!    are written in (a file without it is protocol 2), which verification writes them
//!    in again; `simulation` is [`crate::sim::VERSION`] (a file without it is 1);
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
//! **Encodings** ([`Encoding`]), told apart by a file's first bytes, not its name:
//!
//! * **Format 2** (`.jsonl.zst`, what is written unless asked otherwise): the lines in
//!   chunks of whole lines, each chunk a zstd frame of its own, the header and the footer
//!   each in a chunk of their own, then a 20-byte trailer (a zstd skippable frame) giving
//!   the footer chunk's place: see [`chunks`] for the layout. 8–9× smaller than the
//!   lines; `zstdcat FILE` prints them (the header saying format 2). A file cut anywhere
//!   reads up to its last whole chunk; one without the trailer is incomplete.
//! * **Format 1** (`.jsonl`): the lines themselves, uncompressed, as files were written
//!   before format 2 (and still are on request: `fieldhouse run --out x.jsonl`). A file
//!   cut anywhere reads up to its last whole line.
//!
//! This build reads both, whatever number the header gives (1 or 2: the records are the
//! same, so a decompressed format 2 file reads as lines too); a build that knew only
//! format 1 refuses format 2 files by their header's number, and could not read their
//! chunks anyway.
//!
//! **Segments.** A recording that may never end (the server's real-time matches
//! without bot slots) is rotated into files of bounded size. Every file is a complete
//! replay by itself; a later one's header adds `"segment": n` (1, 2, ...),
//! `"first_tick": t` (the tick of its first frame) and `"previous": "<replay id>"`
//! (the file before it). A file without these fields is segment 0 from tick 0, so files
//! written before segments existed read as they did. Checking a later segment
//! re-simulates from tick 0 and compares frames from its first tick on, which is exact
//! for matches without bots (the only ones rotated: a bot log would be split across
//! files).
//!
//! **Writing.** Records are appended as they go. Format 1 writes each line as it comes;
//! format 2 writes a chunk when it is full (60 lines), or when its writer calls
//! [`Recorder::cut`] (the server does once a line has waited about 2 s, so a live viewer
//! sees frames that late at most and a crash loses at most that much; this core keeps
//! no clock). [`Recorder::flush`] pushes what was written to the file, so a process
//! killed mid-match leaves whole chunks (or lines) behind and at most one torn, which
//! reading detects and ignores; a finished file is flushed and synced before the match
//! is reported ended.
//!
//! **Reading.** [`read`] and [`parse`] take a whole file, for tools; the server reads
//! through an [`Index`] (an entry per block of the file, never per frame, so a file's
//! index is bounded by its bytes) and [`peek`], which bound every line and chunk they
//! read.

pub mod chunks;
mod index;
mod verify;

pub use index::{At, BlockCache, Frame, Index, MAX_LINE_BYTES};
pub use verify::{verify, Mismatch, Verified};

use crate::sim::{Action, Scenario};
use chunks::Packer;
use serde::Serialize;
use serde_json::Value;
use sha2::{Digest, Sha256};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The format written by default (chunked zstd, see the module doc). Bump when a reader
/// of the old format could not read the new one.
pub const FORMAT: u32 = 2;

/// How a replay file is stored (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// Format 1: JSON lines, uncompressed.
    Plain,
    /// Format 2: the lines in chunks, each a zstd frame.
    Zstd,
}

impl Encoding {
    /// The encoding of a file that starts with `start` (its first 4 bytes suffice): a
    /// zstd frame's magic number, or the `{` of a header record.
    pub fn of(start: &[u8]) -> Result<Encoding, String> {
        if start.starts_with(&chunks::MAGIC) {
            Ok(Encoding::Zstd)
        } else if start.first() == Some(&b'{') {
            Ok(Encoding::Plain)
        } else if start.is_empty() {
            Err("the file is empty".into())
        } else {
            Err("neither JSON lines (format 1) nor chunked zstd (format 2)".into())
        }
    }

    /// The encoding of an opened file, from its first bytes.
    pub fn of_file(file: &std::fs::File) -> Result<Encoding, String> {
        let mut start = [0; 4];
        let got = read_at(file, &mut start, 0).map_err(|e| e.to_string())?;
        Encoding::of(&start[..got])
    }

    /// The encoding a file named `path` should be written in: format 1 for a name ending
    /// in `.jsonl` (plain text asked for by name), else format 2.
    pub fn for_path(path: &Path) -> Encoding {
        match path.extension() {
            Some(e) if e == "jsonl" => Encoding::Plain,
            _ => Encoding::Zstd,
        }
    }

    /// The `format` number its header gives.
    pub fn format(self) -> u32 {
        match self {
            Encoding::Plain => 1,
            Encoding::Zstd => FORMAT,
        }
    }

    /// The file name extension, without its first dot: `jsonl` or `jsonl.zst`.
    pub fn extension(self) -> &'static str {
        match self {
            Encoding::Plain => "jsonl",
            Encoding::Zstd => "jsonl.zst",
        }
    }

    /// The media type of a file in this encoding.
    pub fn media_type(self) -> &'static str {
        match self {
            Encoding::Plain => "application/x-ndjson",
            Encoding::Zstd => "application/zstd",
        }
    }
}

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

/// Writes a replay as the match goes. Records are buffered: [`Recorder::flush`] pushes
/// what was written to the file (the server flushes after each batch it takes from its
/// queue). In format 2 a record is written with its chunk: when the chunk is full, or
/// [`Recorder::cut`]. Dropping a recorder loses the chunk being filled: cut and flush
/// first.
pub struct Recorder<W: Durable = io::BufWriter<std::fs::File>> {
    out: W,
    /// Format 2's compressor and the chunk being filled; None for format 1.
    chunked: Option<Chunked>,
    hasher: Sha256,
    frames: u64,
    /// Bytes written to `out`, header included.
    written: u64,
}

/// A format 2 recorder's state.
struct Chunked {
    packer: Packer,
    /// The lines of the chunk being filled.
    text: Vec<u8>,
    lines: usize,
    /// Chunks written.
    count: u64,
    /// The last chunk written: its offset and length.
    last: (u64, u32),
}

/// The records of a replay file besides its frames, as written. Keys are in alphabetical
/// order, as format 1 wrote them; a record is read back as a JSON value, since a file
/// from an older release may hold shapes this one would not write.
mod records {
    use crate::protocol::Action;
    use crate::sim::Scenario;
    use crate::tags;
    use serde::Serialize;

    /// The first line: what was played, with what, and when.
    #[derive(Serialize)]
    pub(super) struct Header<'a, M: Serialize> {
        pub(super) fieldhouse: &'static str,
        pub(super) format: u32,
        #[serde(rename = "match")]
        pub(super) match_info: &'a M,
        pub(super) motion: &'a str,
        /// The protocol version the frames are written in: verifying writes them so.
        pub(super) protocol: u32,
        pub(super) record: tags::Header,
        pub(super) scenario: &'a Scenario,
        pub(super) seed: u64,
        /// The simulation's version: only it re-simulates the frames exactly.
        pub(super) simulation: u32,
        pub(super) started_unix_ms: u64,
    }

    /// The last line: how the match ended, and a hash over every frame line.
    #[derive(Serialize)]
    pub(super) struct Footer<'a, R: Serialize> {
        pub(super) frames: u64,
        pub(super) hash: &'a str,
        pub(super) reason: &'a str,
        pub(super) record: tags::Footer,
        pub(super) result: &'a R,
        pub(super) tick: u64,
    }

    /// A command a bot's agent was given, applied after `tick`.
    #[derive(Serialize)]
    pub(super) struct Command<'a> {
        pub(super) action: &'a Action,
        pub(super) agent: &'a str,
        pub(super) record: tags::Command,
        pub(super) tick: u64,
    }

    /// A bot took (`bot: true`) or gave back an agent at `tick`.
    #[derive(Serialize)]
    pub(super) struct Control<'a> {
        pub(super) agent: &'a str,
        pub(super) bot: bool,
        pub(super) record: tags::Control,
        pub(super) tick: u64,
    }
}

/// The header record of a replay: what was played, with what, and when (`started`,
/// since the Unix epoch: the caller reads the clock). A value, since a recording of
/// several files adds its segment's fields to it.
pub fn header(
    match_info: &impl Serialize,
    scenario: &Scenario,
    motion: &str,
    started: std::time::Duration,
) -> Value {
    let started_unix_ms = started.as_millis() as u64;
    serde_json::to_value(records::Header {
        fieldhouse: env!("CARGO_PKG_VERSION"),
        format: FORMAT,
        match_info,
        motion,
        protocol: crate::protocol::VERSION,
        record: crate::tags::Header,
        scenario,
        seed: scenario.seed,
        simulation: crate::sim::VERSION,
        started_unix_ms,
    })
    .expect("headers serialise")
}

impl Recorder {
    /// Creates `path` (never overwriting a file) and writes the header.
    #[allow(
        clippy::disallowed_methods,
        reason = "a named writer: a new replay file, given its path"
    )]
    pub fn create(path: &Path, header: &Value, encoding: Encoding) -> io::Result<Recorder> {
        let file = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(path)?;
        Recorder::new(io::BufWriter::new(file), header, encoding)
    }
}

impl<W: Durable> Recorder<W> {
    /// Writes the header to `out` (its `format` set to the encoding's) and flushes it.
    pub fn new(out: W, header: &Value, encoding: Encoding) -> io::Result<Recorder<W>> {
        let chunked = match encoding {
            Encoding::Plain => None,
            Encoding::Zstd => Some(Chunked {
                packer: Packer::new(chunks::LEVEL)?,
                text: Vec::with_capacity(chunks::CHUNK_BYTES + 4096),
                lines: 0,
                count: 0,
                last: (0, 0),
            }),
        };
        let mut r = Recorder {
            out,
            chunked,
            hasher: Sha256::new(),
            frames: 0,
            written: 0,
        };
        let mut header = header.clone();
        header["format"] = encoding.format().into();
        r.line(&header.to_string())?;
        // The header has a chunk of its own, so it reads without the frames.
        r.cut()?;
        r.out.flush()?;
        Ok(r)
    }

    /// About the bytes the file will hold once what it was given is written: the bytes
    /// written, and those of the chunk being filled uncompressed (at most what it will
    /// take compressed, but for a few bytes of framing).
    pub fn bytes(&self) -> u64 {
        self.written + self.chunked.as_ref().map_or(0, |c| c.text.len() as u64)
    }

    /// Frames written so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Format 2: how many lines wait in the chunk being filled (0 in format 1, where
    /// each line is written as it comes).
    pub fn buffered(&self) -> usize {
        self.chunked.as_ref().map_or(0, |c| c.lines)
    }

    /// Format 2: chunks written so far (0 in format 1).
    pub fn chunks(&self) -> u64 {
        self.chunked.as_ref().map_or(0, |c| c.count)
    }

    fn line(&mut self, text: &str) -> io::Result<()> {
        let Some(c) = &mut self.chunked else {
            self.written += text.len() as u64 + 1;
            self.out.write_all(text.as_bytes())?;
            return self.out.write_all(b"\n");
        };
        c.text.extend_from_slice(text.as_bytes());
        c.text.push(b'\n');
        c.lines += 1;
        if c.lines >= chunks::CHUNK_LINES || c.text.len() >= chunks::CHUNK_BYTES {
            self.cut()?;
        }
        Ok(())
    }

    /// Format 2: ends the chunk being filled now, however few lines it has, and writes
    /// it (then [`Recorder::flush`] pushes it to the file). Nothing to do in format 1 or
    /// with no line waiting.
    pub fn cut(&mut self) -> io::Result<()> {
        let Some(c) = &mut self.chunked else {
            return Ok(());
        };
        if c.lines == 0 {
            return Ok(());
        }
        let packed = c.packer.pack(&c.text)?;
        self.out.write_all(packed)?;
        c.last = (self.written, packed.len() as u32);
        self.written += packed.len() as u64;
        c.text.clear();
        c.lines = 0;
        c.count += 1;
        Ok(())
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

    /// Pushes what was written to the file, so a process killed after this leaves it:
    /// every line in format 1, every whole chunk in format 2 (see [`Recorder::cut`]).
    pub fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    /// Writes the footer (in format 2 in a chunk of its own, then the trailer), flushes
    /// and syncs: after this the file is complete on disk.
    pub fn finish(mut self, tick: u64, reason: &str, result: &impl Serialize) -> io::Result<()> {
        let hash = hex::encode(self.hasher.clone().finalize());
        let footer = crate::protocol::encode(&records::Footer {
            frames: self.frames,
            hash: &hash,
            reason,
            record: crate::tags::Footer,
            result,
            tick,
        });
        self.cut()?;
        self.line(&footer)?;
        self.cut()?;
        if let Some(c) = &self.chunked {
            let (at, len) = c.last;
            self.out.write_all(&chunks::trailer(at, len))?;
            self.written += chunks::TRAILER_BYTES as u64;
        }
        self.out.sync()
    }
}

/// A bot's `command` record: `action`, accepted by the world, applied after `tick`.
pub fn command_record(tick: u64, agent: &str, action: &Action) -> String {
    crate::protocol::encode(&records::Command {
        action,
        agent,
        record: crate::tags::Command,
        tick,
    })
}

/// A bot's `control` record: a bot took (`bot: true`) or gave back an agent at `tick`.
pub fn control_record(tick: u64, agent: &str, bot: bool) -> String {
    crate::protocol::encode(&records::Control {
        agent,
        bot,
        record: crate::tags::Control,
        tick,
    })
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
    /// begins (see the module doc).
    pub fn first_tick(&self) -> u64 {
        first_tick(&self.header)
    }
}

/// The tick a file with this header starts at (0 unless it is a later segment).
pub fn first_tick(header: &Value) -> u64 {
    header["first_tick"].as_u64().unwrap_or(0)
}

/// The protocol version a file with this header wrote its frames in: its `protocol`,
/// or 2 for a file written before headers said (protocol 2 was the last version without
/// it).
pub fn protocol(header: &Value) -> u32 {
    version(header, "protocol", 2)
}

/// The simulation version that recorded a file with this header: its `simulation`, or 1
/// for a file written before headers said.
pub fn simulation(header: &Value) -> u32 {
    version(header, "simulation", 1)
}

/// A version number in a header, or `before` for a file written before headers gave it.
/// A number too large for a `u32` reads as `u32::MAX`: no build knows it either way.
fn version(header: &Value, key: &str, before: u32) -> u32 {
    header[key]
        .as_u64()
        .map_or(before, |v| u32::try_from(v).unwrap_or(u32::MAX))
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
#[allow(
    clippy::disallowed_methods,
    reason = "a named reader: a replay file, given its path"
)]
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
/// the start and 64 KiB from the end, whatever the file holds (in format 2: the header
/// chunk, the trailer and the footer chunk it names).
pub fn peek(file: &std::fs::File) -> Result<(Value, Option<Value>), String> {
    match Encoding::of_file(file)? {
        Encoding::Plain => peek_plain(file),
        Encoding::Zstd => {
            let (header, _) = chunked_header(file)?;
            Ok((header, chunked_footer(file)?))
        }
    }
}

/// Reads `buf.len()` bytes at `at`, or fewer if the file ends first; returns how many.
pub(crate) fn read_at(file: &std::fs::File, buf: &mut [u8], at: u64) -> io::Result<usize> {
    use std::os::unix::fs::FileExt;
    let mut filled = 0;
    while filled < buf.len() {
        match file.read_at(&mut buf[filled..], at + filled as u64) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(filled)
}

fn peek_plain(mut file: &std::fs::File) -> Result<(Value, Option<Value>), String> {
    use std::io::{BufRead, Read, Seek, SeekFrom};
    file.seek(SeekFrom::Start(0)).map_err(|e| e.to_string())?;
    let mut first = Vec::new();
    io::BufReader::new(file.take(MAX_HEADER_BYTES))
        .read_until(b'\n', &mut first)
        .map_err(|e| e.to_string())?;
    let (header, _) = parse_header(&first)?;
    let len = file.metadata().map_err(|e| e.to_string())?.len();
    let start = len.saturating_sub(TAIL_BYTES);
    let mut tail = vec![0; (len - start) as usize];
    let filled = read_at(file, &mut tail, start).map_err(|e| e.to_string())?;
    tail.truncate(filled);
    let footer = tail
        .strip_suffix(b"\n")
        .and_then(|t| t.rsplit(|&b| b == b'\n').next())
        .and_then(|last| serde_json::from_slice::<Value>(last).ok())
        .filter(|v| v["record"] == "footer");
    Ok((header, footer))
}

/// The header of a format 2 file, from its first chunk (read with bounds).
pub(crate) fn chunked_header(mut file: &std::fs::File) -> Result<(Value, Scenario), String> {
    use std::io::{Read, Seek, SeekFrom};
    file.seek(SeekFrom::Start(0)).map_err(|e| e.to_string())?;
    let mut input = io::BufReader::new(file.take(MAX_HEADER_BYTES));
    let mut unpacker = chunks::Unpacker::new(0).map_err(|e| e.to_string())?;
    let mut text = Vec::new();
    let piece = unpacker
        .next(&mut input, &mut text)
        .map_err(|e| e.to_string())?;
    match piece {
        chunks::Piece::Chunk { .. } => {}
        chunks::Piece::Torn { .. } => {
            return Err("its first chunk is torn (cut, or longer than 1 MiB)".into())
        }
        chunks::Piece::Bad { why, .. } => return Err(format!("its first chunk: {why}")),
        chunks::Piece::End | chunks::Piece::Trailer { .. } => {
            return Err("it has no header chunk".into())
        }
    }
    let first = text
        .split_inclusive(|&b| b == b'\n')
        .next()
        .unwrap_or_default();
    parse_header(first)
}

/// The footer of a format 2 file, found through its trailer; None if the file has no
/// trailer (it is incomplete) or the trailer does not lead to a footer.
fn chunked_footer(file: &std::fs::File) -> Result<Option<Value>, String> {
    let len = file.metadata().map_err(|e| e.to_string())?.len();
    let trailer_at = len.saturating_sub(chunks::TRAILER_BYTES as u64);
    let mut trailer = [0; chunks::TRAILER_BYTES];
    if read_at(file, &mut trailer, trailer_at).map_err(|e| e.to_string())? < trailer.len() {
        return Ok(None);
    }
    let Some((at, chunk_len)) = chunks::read_trailer(&trailer) else {
        return Ok(None);
    };
    if at.checked_add(chunk_len) != Some(trailer_at) || chunk_len > TAIL_BYTES {
        return Ok(None);
    }
    let mut chunk = vec![0; chunk_len as usize];
    if read_at(file, &mut chunk, at).map_err(|e| e.to_string())? < chunk.len() {
        return Ok(None);
    }
    let mut unpacker = chunks::Unpacker::new(at).map_err(|e| e.to_string())?;
    let mut text = Vec::new();
    let piece = unpacker
        .next(&mut &chunk[..], &mut text)
        .map_err(|e| e.to_string())?;
    if !matches!(piece, chunks::Piece::Chunk { .. }) {
        return Ok(None);
    }
    Ok(text
        .strip_suffix(b"\n")
        .and_then(|line| serde_json::from_slice::<Value>(line).ok())
        .filter(|v| v["record"] == "footer"))
}

/// Reads a header line (with its newline): the record and the scenario it describes.
pub(crate) fn parse_header(first: &[u8]) -> Result<(Value, Scenario), String> {
    let header: Value = std::str::from_utf8(first)
        .ok()
        .filter(|l| l.ends_with('\n') && l.len() as u64 <= MAX_HEADER_BYTES)
        .and_then(|l| serde_json::from_str(l).ok())
        .ok_or("the first line is not a complete header record")?;
    if header["record"] != "header" {
        return Err("the first record is not a header".into());
    }
    // Format 2's records are format 1's: either number reads in either encoding.
    if !matches!(header["format"].as_u64(), Some(1..=2)) {
        return Err(format!(
            "format {} (this build reads 1 and {FORMAT})",
            header["format"]
        ));
    }
    let scenario = Scenario::from_value(header["scenario"].clone())
        .map_err(|e| format!("its scenario does not read: {e}"))?;
    Ok((header, scenario))
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

/// Reads a replay from its bytes, in either encoding (see [`read`]).
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
