//! Writing a replay as the match goes: the [`Recorder`], and the records it writes
//! besides the frames.

use super::chunks::{self, Packer};
use super::format::{Encoding, FORMAT};
use crate::sim::{Action, Scenario};
use serde::Serialize;
use serde_json::Value;
use sha2::{Digest, Sha256};
use std::io::{self, Write};

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
