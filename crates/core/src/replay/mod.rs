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
//! **Reading.** [`parse`] takes a whole file's bytes, for tools; the server reads a
//! [`Source`] (its open file, at positions) through an [`Index`] (an entry per block of
//! the file, never per frame, so a file's index is bounded by its bytes) and [`peek`],
//! which bound every line and chunk they read.
//!
//! **Files.** `format.rs`: the format numbers, [`Encoding`], what a header says;
//! `writer.rs`: the [`Recorder`] and the records it writes (to a writer the edge
//! opens); `reader.rs`: [`parse`]; `peek.rs`: [`peek`] and the bounded header reads the
//! index starts from;
//! `index.rs`: the [`Index`]; [`chunks`]: format 2's chunks; `verify.rs`: [`verify`].

pub mod chunks;
mod format;
mod index;
mod peek;
mod reader;
mod verify;
mod writer;

pub use format::{first_tick, protocol, simulation, Encoding, FORMAT};
pub use index::{At, BlockCache, Frame, Index, MAX_LINE_BYTES};
pub(crate) use peek::{chunked_header, parse_header};
pub use peek::{peek, MAX_HEADER_BYTES};
pub use reader::{decode, parse, Logged, Replay};
pub use verify::{verify, Mismatch, Verified};
pub use writer::{command_record, control_record, header, Durable, Recorder};

use std::io;

/// A replay's bytes, read at positions: what the [`Index`] and [`peek`] read. The server
/// hands in a file it opened (which may grow while it is read); tests and fuzz targets,
/// bytes in memory. The core opens nothing.
pub trait Source {
    /// Reads into `buf` at `at`; how many bytes were read (0: nothing there).
    fn read_at(&self, buf: &mut [u8], at: u64) -> io::Result<usize>;
    /// How many bytes there are now.
    fn size(&self) -> io::Result<u64>;
}

impl Source for [u8] {
    fn read_at(&self, buf: &mut [u8], at: u64) -> io::Result<usize> {
        let start = usize::try_from(at).unwrap_or(usize::MAX).min(self.len());
        let n = buf.len().min(self.len() - start);
        buf[..n].copy_from_slice(&self[start..start + n]);
        Ok(n)
    }

    fn size(&self) -> io::Result<u64> {
        Ok(<[u8]>::len(self) as u64)
    }
}

/// Reads `buf.len()` bytes at `at`, or fewer if the source ends first; returns how many.
pub(crate) fn read_at<S: Source + ?Sized>(src: &S, buf: &mut [u8], at: u64) -> io::Result<usize> {
    let mut filled = 0;
    while filled < buf.len() {
        match src.read_at(&mut buf[filled..], at + filled as u64) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(filled)
}

/// Reads all of `buf` at `at`; an error if the source ends first.
pub(crate) fn read_exact_at<S: Source + ?Sized>(
    src: &S,
    buf: &mut [u8],
    at: u64,
) -> io::Result<()> {
    if read_at(src, buf, at)? < buf.len() {
        return Err(io::Error::new(
            io::ErrorKind::UnexpectedEof,
            "the replay ends here",
        ));
    }
    Ok(())
}

/// A source read on from a position, as [`io::Read`] (for buffered line and chunk reads).
pub(crate) struct ReadFrom<'a, S: ?Sized> {
    src: &'a S,
    at: u64,
}

impl<'a, S: Source + ?Sized> ReadFrom<'a, S> {
    pub(crate) fn new(src: &'a S, at: u64) -> ReadFrom<'a, S> {
        ReadFrom { src, at }
    }
}

impl<S: Source + ?Sized> io::Read for ReadFrom<'_, S> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.src.read_at(buf, self.at)?;
        self.at += n as u64;
        Ok(n)
    }
}
