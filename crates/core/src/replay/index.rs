//! Where the frames of a replay file are, at a cost bounded by the file's bytes and not
//! by its frames: the index keeps an entry per *block* of the file, never one per frame,
//! and learns what a block holds when it is first read.
//!
//! * A block of a format 2 file is a run of whole chunks: closed before it would take
//!   more than [`BLOCK_BYTES`] of the file or decompress to more than 2 MiB. Opening a
//!   file walks its chunks' zstd headers (each says how long it is and what it holds)
//!   and decompresses none of them but the header's and the footer's.
//! * A block of a format 1 file is a run of whole lines of at most [`BLOCK_BYTES`] (or
//!   one longer line, up to [`MAX_LINE_BYTES`]): opening it looks for newlines and
//!   parses nothing.
//!
//! So a file costs some 50 bytes of index per block and one read of its bytes to open,
//! however many frames it packs: a file of millions of tiny frames per megabyte costs
//! what any file of its size does (indexing every frame took 8.8 GB per MB of such a
//! file). A format 2 file whose chunks decompress to more than [`MAX_EXPANSION`] times
//! its size is not one this server writes (replays compress about 9×, the most seen in
//! a chunk 44×) and is read no further than that: it could not otherwise be bounded.
//!
//! A block is *decoded* (read, decompressed, its lines parsed) when a viewer reads frames
//! from it or a seek looks into it. The viewer's [`BlockCache`] keeps the last block it
//! decoded for the frames after it; the shared index keeps what was learned of each
//! block (how many frames, their first and last tick), so a seek is a binary search
//! over the blocks that decodes each at most once per index. A line that is not a
//! record is found when its block is decoded: the readable part of the file ends there.
//!
//! A file being written is indexed up to its last whole line or chunk, and
//! [`Index::grown`] walks on from there.

use super::chunks::{self, Measured, Piece, Unpacker, MAX_CHUNK_BYTES, TRAILER_BYTES};
use super::{
    chunked_header, parse_header, read_at, read_exact_at, Encoding, ReadFrom, Source,
    MAX_HEADER_BYTES,
};
use crate::sim::Scenario;
use serde::Deserialize;
use serde_json::Value;
use std::io::{self, BufRead, BufReader, Read};
use std::sync::OnceLock;

/// The longest record read after the header: frames are kilobytes (the longest line of
/// a basketball replay with cost maps was 1.4 kB), so a longer line is not one, and the
/// readable prefix ends there rather than memory running out.
pub const MAX_LINE_BYTES: usize = 1024 * 1024;

/// A block is closed before it would take more of the file than this: small enough that
/// decoding one is quick, large enough that the index of a 1 GiB file is some thousands
/// of entries.
pub(crate) const BLOCK_BYTES: u64 = 64 * 1024;

/// A format 2 block is closed before its chunks would decompress to more than this, so
/// a decoded block holds at most twice it (the last chunk may be 2 MiB itself).
const BLOCK_TEXT_BYTES: u64 = MAX_CHUNK_BYTES as u64;

/// How many times its size a format 2 file's chunks may decompress to, on average, past
/// [`EXPANSION_SLACK`]: replays compress about 9× (the most seen in one chunk, of frames
/// where nothing moves, 44×). It bounds the blocks of a file, and so its index, by the
/// file's size: chunks that each expand to 2 MiB from a few dozen bytes would make a
/// block each.
pub(crate) const MAX_EXPANSION: u64 = 256;

/// What a small file may decompress to whatever its size.
const EXPANSION_SLACK: u64 = 64 << 20;

/// What the walk over a format 2 file reads at a time.
const WALK_READ: usize = 1 << 20;

/// A block's place in its file.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Block {
    offset: u64,
    len: u32,
}

/// What decoding a block found in it.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Learned {
    frames: u32,
    /// The ticks of its first and last frame (0 without frames).
    first_tick: u64,
    last_tick: u64,
}

/// A frame's place: its block and its number among the block's frames. A place past a
/// block's last frame stands for the next frame after it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Default)]
pub struct At {
    block: u32,
    frame: u32,
}

impl At {
    /// The start of the file: its first frame.
    pub const START: At = At { block: 0, frame: 0 };

    fn next_block(self) -> At {
        At {
            block: self.block + 1,
            frame: 0,
        }
    }
}

/// A frame read back: its tick and its line, as recorded.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// The frame's tick.
    pub tick: u64,
    /// Its line, without the newline (invalid UTF-8, which no writer writes, replaced).
    pub text: String,
}

/// A replay file's header, footer and blocks: everything but the frames.
#[derive(Debug, Clone)]
pub struct Index {
    /// The header record (see the module doc of [`super`]).
    pub header: Value,
    /// The scenario the header records, parsed.
    pub scenario: Scenario,
    /// How the file is stored.
    pub encoding: Encoding,
    /// The footer record, if the file has one.
    pub footer: Option<Value>,
    /// Why the walk stopped before the file's end, as [`super::Replay::problem`].
    pub problem: Option<String>,
    blocks: Vec<Block>,
    /// What each block holds, once it has been decoded.
    learned: Vec<OnceLock<Learned>>,
    walk: Walk,
}

/// Where the walk over a file stopped, and what it needs to go on from there.
#[derive(Debug, Clone)]
struct Walk {
    /// After the last whole line or chunk walked.
    offset: u64,
    /// The number of the line (format 1) or chunk (format 2, 1 first) at `offset`.
    number: usize,
    /// The last whole line (without its newline) or chunk walked: the footer is the
    /// last line of a format 1 file, and the chunk a format 2 file's trailer names.
    last: Option<Block>,
    /// What the chunks walked say they decompress to.
    content: u64,
    /// Whether the walk stopped at the file's end (maybe in a line or chunk being
    /// written) rather than at something that does not read: a file that has grown
    /// since can be walked on (see [`Index::grown`]).
    at_end: bool,
}

/// What a line says it is; the rest of it is skipped, not kept.
#[derive(Deserialize)]
struct Kind {
    #[serde(rename = "type")]
    kind: Option<String>,
    record: Option<String>,
    tick: Option<u64>,
}

/// One line of a file, read with a bound on its length.
enum Line {
    /// A whole line, newline stripped.
    Whole,
    /// The file ends without a newline.
    Torn,
    /// Longer than the bound: what was read is dropped.
    TooLong,
    End,
}

/// Reads the next line into `buf` (cleared first), never more than `max` bytes of it.
fn next_line(reader: &mut impl BufRead, buf: &mut Vec<u8>, max: usize) -> io::Result<Line> {
    buf.clear();
    loop {
        let available = reader.fill_buf()?;
        if available.is_empty() {
            return Ok(if buf.is_empty() {
                Line::End
            } else {
                Line::Torn
            });
        }
        let (taken, done) = match available.iter().position(|&b| b == b'\n') {
            Some(k) => (k, true),
            None => (available.len(), false),
        };
        if buf.len() + taken > max {
            buf.clear();
            return Ok(Line::TooLong);
        }
        buf.extend_from_slice(&available[..taken]);
        reader.consume(taken + usize::from(done));
        if done {
            return Ok(Line::Whole);
        }
    }
}

impl Index {
    /// Walks `file` from its start, in either encoding (told by its first bytes). Only a
    /// missing or unreadable header is an error (the same cases as [`super::parse`]);
    /// anything later that does not read ends the walk, with the reason in `problem`.
    /// Memory: the index and one read buffer; no frame is parsed.
    pub fn build<S: Source + ?Sized>(file: &S) -> Result<Index, String> {
        let encoding = Encoding::of_file(file)?;
        let (header, scenario, offset, number) = match encoding {
            Encoding::Plain => {
                let mut first = Vec::new();
                BufReader::new(ReadFrom::new(file, 0).take(MAX_HEADER_BYTES))
                    .read_until(b'\n', &mut first)
                    .map_err(|e| e.to_string())?;
                let (header, scenario) = parse_header(&first)?;
                (header, scenario, first.len() as u64, 2)
            }
            // The header's chunk is block 0's first (its line is skipped there).
            Encoding::Zstd => {
                let (header, scenario) = chunked_header(file)?;
                (header, scenario, 0, 1)
            }
        };
        let mut index = Index {
            header,
            scenario,
            encoding,
            footer: None,
            problem: None,
            blocks: Vec::new(),
            learned: Vec::new(),
            walk: Walk {
                offset,
                number,
                last: None,
                content: 0,
                at_end: false,
            },
        };
        index.walk_on(file)?;
        Ok(index)
    }

    /// The index of `file`, the file this index is of, grown since it was walked (a
    /// replay being written): the blocks already found are kept, with what was learned
    /// of them, and only the bytes after them are read. None if there is nothing to
    /// read on from (the file is complete, or the walk ended at something that does
    /// not read).
    pub fn grown<S: Source + ?Sized>(&self, file: &S) -> Option<Result<Index, String>> {
        if !self.walk.at_end || self.complete() {
            return None;
        }
        let mut index = self.clone();
        index.problem = None;
        index.walk.at_end = false;
        Some(index.walk_on(file).map(|()| index))
    }

    /// How many bytes of the file the index covers.
    pub fn walked(&self) -> u64 {
        self.walk.offset
    }

    fn walk_on<S: Source + ?Sized>(&mut self, file: &S) -> Result<(), String> {
        match self.encoding {
            Encoding::Plain => self.walk_lines(file),
            Encoding::Zstd => self.walk_chunks(file),
        }
    }

    /// Files the piece at `at`, `len` bytes long, in the last block if `join`, else in
    /// a block of its own.
    fn file_piece(&mut self, at: u64, len: u64, join: bool) {
        match self.blocks.last_mut() {
            Some(block) if join => block.len += len as u32,
            _ => {
                self.blocks.push(Block {
                    offset: at,
                    len: len as u32,
                });
                self.learned.push(OnceLock::new());
            }
        }
    }

    /// Takes the last `len` bytes (the footer's line or chunk) out of the last block.
    fn take_off_the_end(&mut self, len: u32) {
        if let Some(block) = self.blocks.last_mut() {
            block.len -= len.min(block.len);
            if block.len == 0 {
                self.blocks.pop();
                self.learned.pop();
            }
        }
    }

    /// Walks whole lines from where the walk stopped, to the end or the first that does
    /// not read; a last line that is a footer is the footer.
    fn walk_lines<S: Source + ?Sized>(&mut self, file: &S) -> Result<(), String> {
        let mut reader = BufReader::with_capacity(64 * 1024, ReadFrom::new(file, self.walk.offset));
        let mut line = Vec::new();
        // A walk starts a block of its own, so no block learned before it changes.
        let mut first = true;
        let problem = loop {
            let number = self.walk.number;
            let read = next_line(&mut reader, &mut line, MAX_LINE_BYTES)
                .map_err(|e| format!("line {number} cannot be read: {e}"));
            match read {
                Ok(Line::Whole) => {
                    let (at, len) = (self.walk.offset, line.len() as u64 + 1);
                    let join = !first
                        && self
                            .blocks
                            .last()
                            .is_some_and(|b| u64::from(b.len) + len <= BLOCK_BYTES);
                    self.file_piece(at, len, join);
                    first = false;
                    self.walk.last = Some(Block {
                        offset: at,
                        len: line.len() as u32,
                    });
                    self.walk.offset += len;
                    self.walk.number += 1;
                }
                Ok(Line::End) => {
                    self.walk.at_end = true;
                    break None;
                }
                Ok(Line::Torn) => {
                    self.walk.at_end = true;
                    break Some(format!(
                        "line {number} is torn (the file was cut mid-record)"
                    ));
                }
                Ok(Line::TooLong) => {
                    break Some(format!(
                        "line {number} is longer than {} MiB: not a record",
                        MAX_LINE_BYTES >> 20
                    ))
                }
                Err(e) => break Some(e),
            }
        };
        self.problem = problem;
        if self.walk.at_end && self.problem.is_none() {
            if let Some(last) = self.walk.last {
                let mut text = vec![0; last.len as usize];
                read_exact_at(file, &mut text, last.offset).map_err(|e| e.to_string())?;
                if let Some(footer) = footer_of(&text) {
                    self.footer = Some(footer);
                    self.take_off_the_end(last.len + 1);
                }
            }
        }
        Ok(())
    }

    /// Walks whole chunks from where the walk stopped, by their headers, to the end or
    /// the first piece that does not read; the chunk the trailer names is the footer.
    fn walk_chunks<S: Source + ?Sized>(&mut self, file: &S) -> Result<(), String> {
        // The bytes from `walk.offset` on that have been read, from `pos` in `buf`.
        let (mut buf, mut pos, mut ended) = (Vec::new(), 0usize, false);
        let (mut first, mut block_text) = (true, 0u64);
        let mut trailer = false;
        let problem = loop {
            let at = self.walk.offset;
            let chunk = self.walk.number;
            match chunks::measure(&buf[pos..]) {
                Measured::Short if !ended => {
                    buf.drain(..pos);
                    pos = 0;
                    let had = buf.len();
                    buf.resize(had + WALK_READ, 0);
                    let got = read_at(file, &mut buf[had..], at + had as u64)
                        .map_err(|e| e.to_string())?;
                    buf.truncate(had + got);
                    ended = got == 0;
                }
                Measured::Short if pos == buf.len() => {
                    self.walk.at_end = true;
                    break None;
                }
                Measured::Short if trailer => break Some("something follows the trailer".into()),
                Measured::Short => {
                    self.walk.at_end = true;
                    break Some(chunks::torn(chunk - 1, at));
                }
                Measured::Chunk { .. } if trailer => {
                    break Some("something follows the trailer".into())
                }
                Measured::Chunk { len, content } => {
                    self.walk.content += content;
                    if self.walk.content > MAX_EXPANSION * (at + len) + EXPANSION_SLACK {
                        break Some(format!(
                            "chunk {chunk} (byte {at}): the chunks up to it decompress to more \
                             than {MAX_EXPANSION}× their size (not a replay this server writes)"
                        ));
                    }
                    let join = !first
                        && block_text + content <= BLOCK_TEXT_BYTES
                        && self
                            .blocks
                            .last()
                            .is_some_and(|b| u64::from(b.len) + len <= BLOCK_BYTES);
                    block_text = if join { block_text + content } else { content };
                    self.file_piece(at, len, join);
                    first = false;
                    self.walk.last = Some(Block {
                        offset: at,
                        len: len as u32,
                    });
                    self.walk.offset += len;
                    self.walk.number += 1;
                    pos += len as usize;
                }
                Measured::Trailer { .. } if trailer => break Some("a second trailer".into()),
                Measured::Trailer { footer_at } => {
                    trailer = true;
                    self.walk.offset += TRAILER_BYTES as u64;
                    pos += TRAILER_BYTES;
                    if let Some(problem) = self.take_chunked_footer(file, footer_at) {
                        break Some(problem);
                    }
                }
                Measured::Bad(why) => break Some(format!("chunk {chunk} (byte {at}): {why}")),
            }
        };
        self.problem = problem;
        Ok(())
    }

    /// Reads the footer from the chunk the trailer names, which must be the last one
    /// walked, and takes it out of the last block; or says why not.
    fn take_chunked_footer<S: Source + ?Sized>(
        &mut self,
        file: &S,
        footer_at: u64,
    ) -> Option<String> {
        let last = self.walk.last.filter(|last| last.offset == footer_at);
        let Some(last) = last else {
            return chunks::trailer_problem(footer_at, self.walk.last.map(|l| l.offset));
        };
        let not_a_footer = || Some("the trailer names a chunk that is not a footer".into());
        let mut packed = vec![0; last.len as usize];
        if read_exact_at(file, &mut packed, last.offset).is_err() {
            return not_a_footer();
        }
        let mut text = Vec::new();
        let unpacked =
            Unpacker::new(last.offset).and_then(|mut u| u.next(&mut &packed[..], &mut text));
        let footer = match unpacked {
            Ok(Piece::Chunk { .. }) => text.strip_suffix(b"\n").and_then(footer_of),
            _ => None,
        };
        let Some(footer) = footer else {
            return not_a_footer();
        };
        self.footer = Some(footer);
        self.take_off_the_end(last.len);
        None
    }

    /// Whether the file ends with its footer (and in format 2 its trailer) and its walk
    /// found nothing wrong. (A line inside that is not a record is found when it is
    /// read.)
    pub fn complete(&self) -> bool {
        self.footer.is_some() && self.problem.is_none()
    }

    /// How many frames the file holds, as its footer says: known without reading them
    /// only for a complete file.
    pub fn frames(&self) -> Option<u64> {
        let footer = self.footer.as_ref().filter(|_| self.complete())?;
        footer["frames"].as_u64()
    }

    /// Decodes block `k` into `cache` (unless it holds it already), learning what it
    /// holds.
    fn decode<'c, S: Source + ?Sized>(
        &self,
        file: &S,
        cache: &'c mut BlockCache,
        k: u32,
    ) -> io::Result<&'c Decoded> {
        if cache.held.as_ref().is_some_and(|d| d.block == k) {
            return Ok(cache.held.as_ref().expect("held"));
        }
        let block = self.blocks[k as usize];
        let mut decoded = cache.held.take().unwrap_or_default();
        decoded.block = k;
        decoded.text.clear();
        decoded.frames.clear();
        cache.raw.resize(block.len as usize, 0);
        read_exact_at(file, &mut cache.raw, block.offset)?;
        let damaged = |why: &str| {
            io::Error::new(
                io::ErrorKind::InvalidData,
                format!("the block at byte {}: {why}", block.offset),
            )
        };
        match self.encoding {
            Encoding::Plain => decoded.text.extend_from_slice(&cache.raw),
            Encoding::Zstd => {
                let unpacker = match &mut cache.unpacker {
                    Some(u) => u,
                    None => cache.unpacker.insert(Unpacker::new(block.offset)?),
                };
                let mut input = &cache.raw[..];
                while !input.is_empty() {
                    match unpacker.next(&mut input, &mut cache.chunk)? {
                        Piece::Chunk { .. } if cache.chunk.ends_with(b"\n") => {}
                        Piece::Chunk { .. } => {
                            return Err(damaged("a chunk does not end with a whole line"))
                        }
                        Piece::Bad { why, .. } => return Err(damaged(&why)),
                        _ => return Err(damaged("a chunk does not read as when it was indexed")),
                    }
                    decoded.text.extend_from_slice(&cache.chunk);
                }
                // What a chunk of 2 MiB left is not kept for the next block.
                if cache.chunk.capacity() > BLOCK_BYTES as usize {
                    cache.chunk = Vec::new();
                }
            }
        }
        // The header's line opens a format 2 file's first chunk.
        let mut start = match (self.encoding, k) {
            (Encoding::Zstd, 0) => decoded
                .text
                .iter()
                .position(|&b| b == b'\n')
                .map_or(0, |n| n + 1),
            _ => 0,
        };
        let mut lines = decoded.text[start..]
            .split_inclusive(|&b| b == b'\n')
            .peekable();
        while let Some(line) = lines.next() {
            let body = line.strip_suffix(b"\n").unwrap_or(line);
            if body.len() > MAX_LINE_BYTES {
                return Err(damaged("a line longer than 1 MiB: not a record"));
            }
            let kind: Kind = serde_json::from_slice(body)
                .map_err(|e| damaged(&format!("a line that is not a record: {e}")))?;
            match (kind.kind.as_deref(), kind.record.as_deref(), kind.tick) {
                (Some("frame"), _, Some(tick)) => decoded.frames.push(Placed {
                    tick,
                    start: start as u32,
                    len: body.len() as u32,
                }),
                // The bot log matters for checking a replay, not for watching one.
                (_, Some("command" | "control"), Some(_)) => {}
                // The footer of a file cut before its trailer: nothing follows it.
                (_, Some("footer"), _) if lines.peek().is_none() => {}
                (_, Some("footer"), _) => return Err(damaged("a line follows the footer")),
                _ => {
                    return Err(damaged(
                        "a line that is not a frame, command, control or footer record",
                    ))
                }
            }
            start += line.len();
        }
        let frames = &decoded.frames;
        self.learned[k as usize].get_or_init(|| Learned {
            frames: frames.len() as u32,
            first_tick: frames.first().map_or(0, |f| f.tick),
            last_tick: frames.last().map_or(0, |f| f.tick),
        });
        Ok(cache.held.insert(decoded))
    }

    /// What block `k` holds, decoding it if nobody has yet.
    fn learn<S: Source + ?Sized>(
        &self,
        file: &S,
        cache: &mut BlockCache,
        k: u32,
    ) -> io::Result<Learned> {
        if let Some(learned) = self.learned[k as usize].get() {
            return Ok(*learned);
        }
        self.decode(file, cache, k)?;
        Ok(*self.learned[k as usize].get().expect("decoding learns"))
    }

    fn block_count(&self) -> u32 {
        self.blocks.len() as u32
    }

    /// Whether `at` is past the last frame of the file as indexed.
    pub fn is_end(&self, at: At) -> bool {
        at.block >= self.block_count()
    }

    /// The ticks of the file's first and last frames (None without frames), looked for
    /// in at most 64 blocks from each end.
    pub fn ends<S: Source + ?Sized>(
        &self,
        file: &S,
        cache: &mut BlockCache,
    ) -> io::Result<(Option<u64>, Option<u64>)> {
        let n = self.block_count();
        let mut first = None;
        for k in (0..n).take(ENDS_LOOKED_AT) {
            let learned = self.learn(file, cache, k)?;
            if learned.frames > 0 {
                first = Some(learned.first_tick);
                break;
            }
        }
        let mut last = None;
        for k in (0..n).rev().take(ENDS_LOOKED_AT) {
            let learned = self.learn(file, cache, k)?;
            if learned.frames > 0 {
                last = Some(learned.last_tick);
                break;
            }
        }
        Ok((first, last))
    }

    /// The first frame at or after `tick` (a file's ticks never go back): a binary
    /// search over the blocks, then over the frames of one. None if every frame is
    /// before it.
    pub fn seek<S: Source + ?Sized>(
        &self,
        file: &S,
        cache: &mut BlockCache,
        tick: u64,
    ) -> io::Result<Option<At>> {
        // The first block with a frame at or after `tick` is in lo..=hi (hi: none).
        let (mut lo, mut hi) = (0, self.block_count());
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            // The first block from `mid` on (before `hi`) with frames.
            let mut found = None;
            for k in mid..hi {
                let learned = self.learn(file, cache, k)?;
                if learned.frames > 0 {
                    found = Some((k, learned));
                    break;
                }
            }
            match found {
                None => hi = mid,
                Some((k, learned)) if learned.last_tick < tick => lo = k + 1,
                Some((k, _)) => hi = k,
            }
        }
        // Blocks from `hi` on to the first with frames have none: that one is it.
        for k in hi..self.block_count() {
            if self.learn(file, cache, k)?.frames > 0 {
                let decoded = self.decode(file, cache, k)?;
                let frame = decoded.frames.partition_point(|f| f.tick < tick) as u32;
                return Ok(Some(At { block: k, frame }));
            }
        }
        Ok(None)
    }

    /// Where the frames up to `most` before `at` start, but not before `floor` (both
    /// places of frames, `floor` not after `at`), and how many frames that is: where a
    /// seek's lead-in starts.
    pub fn back<S: Source + ?Sized>(
        &self,
        file: &S,
        cache: &mut BlockCache,
        at: At,
        floor: At,
        most: u64,
    ) -> io::Result<(At, u64)> {
        let (mut place, mut left) = (at, most);
        loop {
            let available = if place.block == floor.block {
                place.frame.saturating_sub(floor.frame)
            } else {
                place.frame
            };
            let taken = u64::from(available).min(left);
            place.frame -= taken as u32;
            left -= taken;
            if left == 0 || place.block <= floor.block {
                return Ok((place, most - left));
            }
            let k = place.block - 1;
            place = At {
                block: k,
                frame: self.learn(file, cache, k)?.frames,
            };
        }
    }

    /// Reads frames from `from` on (the first frame at or after it): at least one if
    /// there is one, then more, up to `most` of them, while their text is at most
    /// `budget` bytes; and where the next read goes on. Empty at the end of the file.
    pub fn read<S: Source + ?Sized>(
        &self,
        file: &S,
        cache: &mut BlockCache,
        from: At,
        most: usize,
        budget: usize,
    ) -> io::Result<(Vec<Frame>, At)> {
        let (mut frames, mut at, mut spent) = (Vec::new(), from, 0);
        while frames.len() < most && !self.is_end(at) {
            // A block known to have nothing more is not decoded again.
            if self.learned[at.block as usize]
                .get()
                .is_some_and(|l| at.frame >= l.frames)
            {
                at = at.next_block();
                continue;
            }
            let decoded = self.decode(file, cache, at.block)?;
            let Some(placed) = decoded.frames.get(at.frame as usize) else {
                at = at.next_block();
                continue;
            };
            let len = placed.len as usize;
            if !frames.is_empty() && spent + len > budget {
                break;
            }
            let line = &decoded.text[placed.start as usize..][..len];
            frames.push(Frame {
                tick: placed.tick,
                text: String::from_utf8_lossy(line).into_owned(),
            });
            spent += len;
            at.frame += 1;
        }
        Ok((frames, at))
    }
}

/// How many blocks from each end [`Index::ends`] looks at for a frame: a file this
/// writes has frames in its first and last; one with thousands of blocks of none is
/// not worth decoding whole to open.
const ENDS_LOOKED_AT: usize = 64;

/// `line` as a footer record, if it is one.
fn footer_of(line: &[u8]) -> Option<Value> {
    serde_json::from_slice::<Value>(line)
        .ok()
        .filter(|v| v["record"] == "footer")
}

/// A frame's place in its decoded block.
#[derive(Debug, Clone, Copy)]
struct Placed {
    tick: u64,
    start: u32,
    len: u32,
}

/// A block read and parsed.
#[derive(Debug, Default)]
struct Decoded {
    block: u32,
    text: Vec<u8>,
    frames: Vec<Placed>,
}

/// One reader's last decoded block, for the frames after it, and the buffers decoding
/// reuses. It holds at most a block: 4 MiB of text and its frames' places.
#[derive(Default)]
pub struct BlockCache {
    held: Option<Decoded>,
    raw: Vec<u8>,
    chunk: Vec<u8>,
    unpacker: Option<Unpacker>,
}

#[cfg(test)]
mod tests {
    use super::{next_line, At, BlockCache, Frame, Index, Line, BLOCK_BYTES, MAX_EXPANSION};
    use crate::replay::chunks::{Packer, LEVEL, MAGIC};
    use crate::replay::{Encoding, Recorder};
    use std::io::Write;

    const HEADER: &str = r#"{"record":"header","format":1,"match":{"id":"m"},"scenario":{"sport":"baseball"},"seed":1}"#;

    /// These tests keep replays in files (one grows while it is read), read as the
    /// server reads its own.
    impl crate::replay::Source for std::fs::File {
        fn read_at(&self, buf: &mut [u8], at: u64) -> std::io::Result<usize> {
            std::os::unix::fs::FileExt::read_at(self, buf, at)
        }

        fn size(&self) -> std::io::Result<u64> {
            Ok(self.metadata()?.len())
        }
    }

    fn tempfile() -> std::fs::File {
        tempfile::tempfile().unwrap()
    }

    fn file_of(bytes: &[u8]) -> std::fs::File {
        let mut file = tempfile();
        file.write_all(bytes).unwrap();
        file
    }

    /// A small deterministic generator, so that the files are the same on every run.
    struct Lcg(u64);

    impl Lcg {
        fn next(&mut self) -> u64 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            self.0 >> 33
        }

        fn hex(&mut self, n: usize) -> String {
            (0..n).map(|_| format!("{:x}", self.next() % 16)).collect()
        }
    }

    /// A replay of `frames` frames, in `encoding`, finished if `finish`: its bytes and
    /// its frames in order (the oracle the index is checked against). Ticks go up by 0
    /// to 3, and now and then a long run of control records makes blocks without
    /// frames.
    fn sample(encoding: Encoding, frames: usize, seed: u64, finish: bool) -> (Vec<u8>, Vec<Frame>) {
        let mut rng = Lcg(seed);
        let file = tempfile();
        let header: serde_json::Value = serde_json::from_str(HEADER).unwrap();
        let out = std::io::BufWriter::new(file.try_clone().unwrap());
        let mut r = Recorder::new(out, &header, encoding).unwrap();
        let mut truth = Vec::new();
        let mut tick = rng.next() % 5;
        for k in 0..frames {
            let text = format!(r#"{{"type":"frame","tick":{tick},"x":"{}"}}"#, rng.hex(150));
            r.frame(&text).unwrap();
            truth.push(Frame { tick, text });
            if k % 700 == 350 {
                for _ in 0..1500 {
                    let c = format!(
                        r#"{{"record":"control","tick":{tick},"agent":"cf","bot":true,"x":"{}"}}"#,
                        rng.hex(160)
                    );
                    r.log(&c).unwrap();
                }
            }
            tick += rng.next() % 4;
        }
        if finish {
            let result = serde_json::json!({});
            r.finish(tick, "finished", &result).unwrap();
        } else {
            r.cut().unwrap();
            r.flush().unwrap();
        }
        let mut bytes = Vec::new();
        std::io::Seek::rewind(&mut &file).unwrap();
        std::io::Read::read_to_end(&mut &file, &mut bytes).unwrap();
        (bytes, truth)
    }

    #[test]
    fn bytes_in_memory_read_as_the_file_they_were_written_to() {
        for encoding in [Encoding::Plain, Encoding::Zstd] {
            let (bytes, truth) = sample(encoding, 2000, 7, true);
            let index = Index::build(&bytes[..]).unwrap();
            assert!(index.complete());
            let mut cache = BlockCache::default();
            assert_eq!(read_all(&index, &bytes[..], &mut cache).unwrap(), truth);
            let on_disk = file_of(&bytes);
            assert_eq!(
                crate::replay::peek(&bytes[..]).unwrap(),
                crate::replay::peek(&on_disk).unwrap()
            );
            // Cut anywhere, bytes and file stop at the same frame.
            for cut in [0, 10, bytes.len() / 3, bytes.len() - 1] {
                let (mem, disk) = (
                    Index::build(&bytes[..cut]),
                    Index::build(&file_of(&bytes[..cut])),
                );
                assert_eq!(
                    mem.map(|i| i.frames()),
                    disk.map(|i| i.frames()),
                    "cut at {cut}"
                );
            }
        }
    }

    /// Every frame, read from the start a batch at a time.
    fn read_all<S: crate::replay::Source + ?Sized>(
        index: &Index,
        file: &S,
        cache: &mut BlockCache,
    ) -> std::io::Result<Vec<Frame>> {
        let (mut all, mut at) = (Vec::new(), At::START);
        loop {
            let (batch, next) = index.read(file, cache, at, 64, 16 * 1024)?;
            if batch.is_empty() {
                assert!(index.is_end(next));
                return Ok(all);
            }
            all.extend(batch);
            at = next;
        }
    }

    const ENCODINGS: [Encoding; 2] = [Encoding::Plain, Encoding::Zstd];

    #[test]
    fn every_frame_reads_back_byte_for_byte_and_seeks_agree_with_a_linear_search() {
        for encoding in ENCODINGS {
            let (bytes, truth) = sample(encoding, 3000, 7, true);
            let file = file_of(&bytes);
            let index = Index::build(&file).unwrap();
            assert!(index.complete(), "{encoding:?}: {:?}", index.problem);
            assert_eq!(index.frames(), Some(3000));
            assert!(
                index.blocks.len() > 4,
                "{encoding:?}: {} blocks",
                index.blocks.len()
            );
            // Nothing is decoded to open a file.
            assert!(index.learned.iter().all(|l| l.get().is_none()));
            let mut cache = BlockCache::default();
            assert_eq!(read_all(&index, &file, &mut cache).unwrap(), truth);
            let ends = index.ends(&file, &mut cache).unwrap();
            assert_eq!(ends, (Some(truth[0].tick), Some(truth[2999].tick)));
            // Some blocks hold only control records.
            assert!(index.learned.iter().any(|l| l.get().unwrap().frames == 0));
            let last = truth[2999].tick;
            for tick in (0..=last + 2).step_by(7).chain([0, 1, last, last + 1]) {
                let mut fresh = BlockCache::default();
                let expected = truth.iter().position(|f| f.tick >= tick);
                let found = index.seek(&file, &mut fresh, tick).unwrap();
                match (expected, found) {
                    (None, None) => {}
                    (Some(k), Some(at)) => {
                        let (got, _) = index.read(&file, &mut fresh, at, 1, 1).unwrap();
                        assert_eq!(got[0], truth[k], "{encoding:?}: seek {tick}");
                        // The lead-in: up to `most` frames back, never before the floor.
                        let floor_tick = tick.saturating_sub(40);
                        let floor_k = truth.iter().position(|f| f.tick >= floor_tick).unwrap();
                        let floor = index.seek(&file, &mut fresh, floor_tick).unwrap().unwrap();
                        for most in [0, 1, 5, 30, 1000] {
                            let (start, n) =
                                index.back(&file, &mut fresh, at, floor, most).unwrap();
                            let first = k - (k - floor_k).min(most as usize);
                            assert_eq!(n as usize, k - first, "{encoding:?}: back {most} from {k}");
                            let (got, _) = index.read(&file, &mut fresh, start, 1, 1).unwrap();
                            assert_eq!(got[0], truth[first], "{encoding:?}: back {most} from {k}");
                        }
                    }
                    other => panic!("{encoding:?}: seek {tick}: {other:?}"),
                }
            }
        }
    }

    #[test]
    fn a_file_cut_anywhere_reads_a_prefix_and_grows_to_the_whole() {
        for encoding in ENCODINGS {
            let (whole, truth) = sample(encoding, 800, 11, true);
            let step = whole.len() / 37;
            for cut in (200..whole.len())
                .step_by(step)
                .chain(whole.len() - 25..whole.len())
            {
                let file = file_of(&whole[..cut]);
                let before = match Index::build(&file) {
                    Ok(index) => index,
                    // Cut inside the header.
                    Err(_) => continue,
                };
                assert!(!before.complete(), "{encoding:?}: cut at {cut}");
                if let Some(problem) = &before.problem {
                    assert!(problem.contains("torn"), "{encoding:?}: {problem}");
                }
                let read = read_all(&before, &file, &mut BlockCache::default()).unwrap();
                assert_eq!(read[..], truth[..read.len()], "{encoding:?}: cut at {cut}");
                // Where the writer goes on: the file's end, whatever reading moved.
                std::os::unix::fs::FileExt::write_all_at(&file, &whole[cut..], cut as u64).unwrap();
                let grown = before.grown(&file).unwrap().unwrap();
                assert!(
                    grown.complete(),
                    "{encoding:?}: cut at {cut}: {:?}",
                    grown.problem
                );
                assert_eq!(
                    read_all(&grown, &file, &mut BlockCache::default()).unwrap(),
                    truth
                );
                assert_eq!(grown.frames(), Some(800));
            }
            // A file whose writer cut its last chunk reads to its last frame, incomplete.
            let (unfinished, truth) = sample(encoding, 130, 3, false);
            let file = file_of(&unfinished);
            let index = Index::build(&file).unwrap();
            assert_eq!(index.problem, None);
            assert!(!index.complete());
            assert_eq!(index.frames(), None);
            assert_eq!(
                read_all(&index, &file, &mut BlockCache::default()).unwrap(),
                truth
            );
        }
    }

    #[test]
    fn damage_inside_a_block_ends_the_readable_part_there_and_nothing_else_is_misread() {
        for encoding in ENCODINGS {
            let (mut bytes, truth) = sample(encoding, 2000, 5, true);
            // In the middle of frame 1000: a quote in a format 1 line, any byte of a
            // format 2 chunk (its checksum fails).
            match encoding {
                Encoding::Plain => {
                    let text = truth[1000].text.as_bytes();
                    let k = bytes.windows(text.len()).position(|w| w == text).unwrap();
                    bytes[k + text.len() / 2] = b'"';
                }
                Encoding::Zstd => {
                    let clean_file = file_of(&bytes);
                    let clean = Index::build(&clean_file).unwrap();
                    let mut cache = BlockCache::default();
                    let at = clean
                        .seek(&clean_file, &mut cache, truth[1000].tick)
                        .unwrap()
                        .unwrap();
                    let block = clean.blocks[at.block as usize];
                    let k = block.offset as usize + block.len as usize / 2;
                    bytes[k] ^= 0x5a;
                }
            }
            let file = file_of(&bytes);
            let index = Index::build(&file).unwrap();
            let mut cache = BlockCache::default();
            let (mut read, mut at) = (Vec::new(), At::START);
            let error = loop {
                match index.read(&file, &mut cache, at, 64, 1 << 20) {
                    Ok((batch, _)) if batch.is_empty() => break None,
                    Ok((batch, next)) => {
                        read.extend(batch);
                        at = next;
                    }
                    Err(e) => break Some(e.to_string()),
                }
            };
            assert_eq!(read[..], truth[..read.len()], "{encoding:?}");
            assert!(
                read.len() <= 1000,
                "{encoding:?}: {} frames read",
                read.len()
            );
            // The blocks before the damaged one are read (a block holds a few hundred
            // of these frames).
            assert!(
                read.len() >= 250,
                "{encoding:?}: {} frames read",
                read.len()
            );
            let error = error
                .or(index.problem.clone())
                .expect("the damage is found");
            assert!(error.contains("byte"), "{encoding:?}: {error}");
        }
    }

    #[test]
    fn a_torn_line_ends_the_readable_part_and_an_endless_one_is_not_read_for_ever() {
        let torn = file_of(
            format!("{HEADER}\n{{\"type\":\"frame\",\"tick\":0}}\n{{\"type\":\"fra").as_bytes(),
        );
        let index = Index::build(&torn).unwrap();
        assert!(index.problem.as_ref().unwrap().contains("torn"));
        assert_eq!(
            read_all(&index, &torn, &mut BlockCache::default())
                .unwrap()
                .len(),
            1
        );
        // A header with no end is not read for ever.
        assert!(Index::build(&file_of(&vec![b'x'; 2 << 20])).is_err());
        // Nor a line after it.
        let mut long = format!("{HEADER}\n").into_bytes();
        long.resize(long.len() + (1 << 20) + 10, b'x');
        let index = Index::build(&file_of(&long)).unwrap();
        assert!(index.problem.unwrap().contains("longer than 1 MiB"));
    }

    /// Chunks of tiny frames, each 2 MiB decompressed from a few hundred bytes: what
    /// made the old index hold 8.8 GB per MB of file.
    fn dense(chunks: usize) -> Vec<u8> {
        let mut packer = Packer::new(LEVEL).unwrap();
        let mut bytes = packer
            .pack(format!("{HEADER}\n").as_bytes())
            .unwrap()
            .to_vec();
        for c in 0..chunks {
            let mut text = Vec::new();
            let mut k = 0;
            while text.len() < (2 << 20) - 64 {
                writeln!(
                    text,
                    r#"{{"type":"frame","tick":{}}}"#,
                    c * 1_000_000 + k / 1000
                )
                .unwrap();
                k += 1;
            }
            bytes.extend_from_slice(packer.pack(&text).unwrap());
        }
        bytes
    }

    #[test]
    fn frame_dense_files_cost_an_index_entry_per_block_not_per_frame() {
        let bytes = dense(20);
        assert_eq!(&bytes[..4], &MAGIC);
        let file = file_of(&bytes);
        let index = Index::build(&file).unwrap();
        // 1.6 million frames in 20 chunks: 21 blocks at most, none decoded yet.
        assert!(index.blocks.len() <= 21, "{}", index.blocks.len());
        assert_eq!(index.problem, None);
        assert!(index.learned.iter().all(|l| l.get().is_none()));
        // Seeks find their frame by decoding a handful of blocks.
        let mut cache = BlockCache::default();
        let at = index.seek(&file, &mut cache, 7_000_050).unwrap().unwrap();
        let (got, _) = index.read(&file, &mut cache, at, 1, 1).unwrap();
        assert_eq!(got[0].text, r#"{"type":"frame","tick":7000050}"#);
        let decoded = index.learned.iter().filter(|l| l.get().is_some()).count();
        assert!(decoded <= 6, "{decoded} blocks decoded for one seek");
        // Past what any replay expands to, the file is read no further.
        let bytes = dense(40);
        let index = Index::build(&file_of(&bytes)).unwrap();
        let problem = index.problem.unwrap();
        assert!(
            problem.contains(&format!("more than {MAX_EXPANSION}×")),
            "{problem}"
        );
        let most = (super::EXPANSION_SLACK + MAX_EXPANSION * bytes.len() as u64) >> 21;
        assert!(
            index.blocks.len() as u64 <= most + 1,
            "{} blocks",
            index.blocks.len()
        );
    }

    #[test]
    fn blocks_stay_within_their_bound() {
        for encoding in ENCODINGS {
            let (bytes, _) = sample(encoding, 3000, 9, true);
            let index = Index::build(&file_of(&bytes)).unwrap();
            for pair in index.blocks.windows(2) {
                assert_eq!(pair[0].offset + u64::from(pair[0].len), pair[1].offset);
                assert!(u64::from(pair[0].len) <= BLOCK_BYTES);
                // A block was closed only because the next piece did not fit.
                assert!(u64::from(pair[0].len + pair[1].len) > BLOCK_BYTES / 2);
            }
        }
    }

    #[test]
    fn lines_are_read_up_to_their_bound() {
        let mut reader = std::io::BufReader::with_capacity(4, &b"abcdefgh\nxy\nlast"[..]);
        let mut buf = Vec::new();
        assert!(matches!(
            next_line(&mut reader, &mut buf, 5).unwrap(),
            Line::TooLong
        ));
        let mut reader = std::io::BufReader::with_capacity(4, &b"abcdefgh\nxy\nlast"[..]);
        assert!(matches!(
            next_line(&mut reader, &mut buf, 100).unwrap(),
            Line::Whole
        ));
        assert_eq!(buf, b"abcdefgh");
        assert!(matches!(
            next_line(&mut reader, &mut buf, 100).unwrap(),
            Line::Whole
        ));
        assert_eq!(buf, b"xy");
        assert!(matches!(
            next_line(&mut reader, &mut buf, 100).unwrap(),
            Line::Torn
        ));
        assert!(matches!(
            next_line(&mut reader, &mut buf, 100).unwrap(),
            Line::End
        ));
    }
}
