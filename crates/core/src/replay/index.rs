//! Where each frame of a replay file is, so a file of any size can be played, sought and
//! shared without holding its frames: the server scans a file once (a line or a chunk at
//! a time, every one bounded), keeps each frame's tick and place, and reads frames back
//! from the file when a viewer needs them.
//!
//! In format 1 a frame's place is its offset and length in the file. In format 2 it is
//! its chunk (the index keeps each chunk's offset and length) and its offset and length
//! in the chunk decompressed: reading a frame decompresses its chunk, which the viewer's
//! [`ChunkCache`] keeps for the frames after it. A file being written is indexed up to
//! its last whole line or chunk, and [`Index::grown`] reads on from there.

use super::chunks::{self, Piece, Unpacker};
use super::{chunked_header, parse_header, Encoding, MAX_HEADER_BYTES, NO_TRAILER};
use crate::sim::Scenario;
use serde::Deserialize;
use serde_json::Value;
use std::collections::VecDeque;
use std::fs::File;
use std::io::{self, BufRead, BufReader, Read, Seek, SeekFrom};
use std::os::unix::fs::FileExt;

/// The longest record read after the header: frames are kilobytes (the longest line of
/// a basketball replay with cost maps was 1.4 kB), so a longer line is not one, and the
/// readable prefix ends there rather than memory running out. It also bounds what one
/// viewer holds of a file at a time.
pub const MAX_LINE_BYTES: usize = 1024 * 1024;

/// A format 1 frame's `chunk`: its place is in the file itself.
const IN_FILE: u32 = u32::MAX;

/// A frame's place: in its file (format 1), or in its chunk decompressed (format 2).
#[derive(Debug, Clone, Copy, PartialEq)]
struct FrameAt {
    tick: u64,
    /// [`IN_FILE`], or the index of its chunk.
    chunk: u32,
    /// Without the newline.
    len: u32,
    offset: u64,
}

/// A format 2 chunk's place in its file.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ChunkAt {
    offset: u64,
    len: u32,
}

/// A replay file's header, footer and frame positions: everything but the frames.
#[derive(Debug, Clone)]
pub struct Index {
    /// The header record (see the module doc of [`super`]).
    pub header: Value,
    /// The scenario the header records, parsed.
    pub scenario: Scenario,
    /// How the file is stored.
    pub encoding: Encoding,
    frames: Vec<FrameAt>,
    /// Format 2: every whole chunk read.
    chunks: Vec<ChunkAt>,
    /// The footer record, if the file has one.
    pub footer: Option<Value>,
    /// Why the readable prefix ends early, as [`super::Replay::problem`].
    pub problem: Option<String>,
    /// Where the scan stopped: after the last whole line (format 1) or chunk (format 2)
    /// read, and the number of the line after it.
    scanned: (u64, usize),
    /// Whether the scan stopped at the file's end (maybe in a line or chunk being
    /// written) rather than at something that does not read: a file that has grown
    /// since can be scanned on from `scanned` (see [`Index::grown`]).
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
    /// Scans `file` from its start, in either encoding (told by its first bytes). Only a
    /// missing or unreadable header is an error (the same cases as [`super::parse`]);
    /// anything later that does not read ends the readable prefix, with the reason in
    /// `problem`. Memory: one line or chunk at a time.
    pub fn build(mut file: &File) -> Result<Index, String> {
        let encoding = Encoding::of_file(file)?;
        let (header, scenario, scanned) = match encoding {
            Encoding::Plain => {
                file.seek(SeekFrom::Start(0)).map_err(|e| e.to_string())?;
                let mut first = Vec::new();
                BufReader::new(file.take(MAX_HEADER_BYTES))
                    .read_until(b'\n', &mut first)
                    .map_err(|e| e.to_string())?;
                let (header, scenario) = parse_header(&first)?;
                (header, scenario, (first.len() as u64, 2))
            }
            // The header's chunk is scanned with the rest (line 1 is skipped there).
            Encoding::Zstd => {
                let (header, scenario) = chunked_header(file)?;
                (header, scenario, (0, 1))
            }
        };
        let mut index = Index {
            header,
            scenario,
            encoding,
            frames: Vec::new(),
            chunks: Vec::new(),
            footer: None,
            problem: None,
            scanned,
            at_end: false,
        };
        index.scan(file)?;
        Ok(index)
    }

    /// The index of `file`, the file this index is of, grown since it was scanned (a
    /// replay being written): the frames already found are kept and only the bytes
    /// after them are read. None if there is nothing to read on from (the file is
    /// complete, or the scan ended at something that does not read).
    pub fn grown(&self, file: &File) -> Option<Result<Index, String>> {
        if !self.at_end || self.complete() {
            return None;
        }
        let mut index = Index {
            problem: None,
            at_end: false,
            ..self.clone()
        };
        Some(index.scan(file).map(|()| index))
    }

    fn scan(&mut self, file: &File) -> Result<(), String> {
        match self.encoding {
            Encoding::Plain => self.scan_lines(file),
            Encoding::Zstd => self.scan_chunks(file),
        }
    }

    /// Reads whole lines from `scanned` on, to the end or the first that does not read.
    fn scan_lines(&mut self, mut file: &File) -> Result<(), String> {
        let (mut offset, first_number) = self.scanned;
        file.seek(SeekFrom::Start(offset))
            .map_err(|e| e.to_string())?;
        let mut reader = BufReader::with_capacity(64 * 1024, file);
        let mut line = Vec::new();
        for number in first_number.. {
            let read = next_line(&mut reader, &mut line, MAX_LINE_BYTES)
                .map_err(|e| format!("line {number} cannot be read: {e}"));
            let problem = match read {
                Ok(Line::End) => {
                    self.at_end = true;
                    None
                }
                Ok(Line::Whole) => self.take(&line, IN_FILE, offset, number).err(),
                Ok(Line::Torn) => {
                    self.at_end = true;
                    Some(format!(
                        "line {number} is torn (the file was cut mid-record)"
                    ))
                }
                Ok(Line::TooLong) => Some(format!(
                    "line {number} is longer than {} MiB: not a record",
                    MAX_LINE_BYTES >> 20
                )),
                Err(e) => Some(e),
            };
            if problem.is_some() || self.at_end {
                self.problem = problem;
                self.scanned = (offset, number);
                return Ok(());
            }
            offset += line.len() as u64 + 1;
        }
        unreachable!("the lines of a file are fewer than usize::MAX")
    }

    /// Reads whole chunks from `scanned` on, to the end or the first that does not read.
    fn scan_chunks(&mut self, mut file: &File) -> Result<(), String> {
        let (offset, mut number) = self.scanned;
        file.seek(SeekFrom::Start(offset))
            .map_err(|e| e.to_string())?;
        let mut reader = BufReader::with_capacity(64 * 1024, file);
        let mut unpacker = Unpacker::new(offset).map_err(|e| e.to_string())?;
        let mut text = Vec::new();
        loop {
            let (at, count) = (unpacker.at(), self.chunks.len());
            let problem = match unpacker.next(&mut reader, &mut text) {
                Err(e) => Some(format!(
                    "chunk {} (byte {at}) cannot be read: {e}",
                    count + 1
                )),
                Ok(Piece::End) => {
                    self.at_end = true;
                    self.footer.as_ref().map(|_| NO_TRAILER.to_string())
                }
                Ok(Piece::Torn { at }) => {
                    self.at_end = true;
                    Some(chunks::torn(count, at))
                }
                Ok(Piece::Bad { at, why }) => {
                    Some(format!("chunk {} (byte {at}): {why}", count + 1))
                }
                Ok(Piece::Trailer { footer_at }) => {
                    let last = self.chunks.last().map(|c| c.offset);
                    match chunks::trailer_problem(footer_at, last) {
                        Some(p) => Some(p),
                        None if self.footer.is_none() => {
                            Some("the file has a trailer but no footer".into())
                        }
                        // Complete: nothing may follow.
                        None => match unpacker.next(&mut reader, &mut text) {
                            Ok(Piece::End) => None,
                            _ => Some("something follows the trailer".into()),
                        },
                    }
                }
                Ok(Piece::Chunk { at, len }) => {
                    match self.take_chunk(&text, at, len, &mut number) {
                        Ok(()) => {
                            self.scanned = (at + len, number);
                            continue;
                        }
                        Err(p) => Some(p),
                    }
                }
            };
            self.problem = problem;
            return Ok(());
        }
    }

    /// Files the lines of a whole chunk, found at `at`, `len` bytes long; the first line
    /// is number `number`, which is moved on past them.
    fn take_chunk(
        &mut self,
        text: &[u8],
        at: u64,
        len: u64,
        number: &mut usize,
    ) -> Result<(), String> {
        if let Some(p) = chunks::chunk_problem(text, self.chunks.len(), at) {
            return Err(p);
        }
        let k = self.chunks.len() as u32;
        self.chunks.push(ChunkAt {
            offset: at,
            len: len as u32,
        });
        let mut within = 0u64;
        for line in text.split_inclusive(|&b| b == b'\n') {
            let line = &line[..line.len() - 1];
            let n = *number;
            *number += 1;
            // The header, read already.
            if n > 1 {
                if line.len() > MAX_LINE_BYTES {
                    return Err(format!(
                        "line {n} is longer than {} MiB: not a record",
                        MAX_LINE_BYTES >> 20
                    ));
                }
                self.take(line, k, within, n)?;
            }
            within += line.len() as u64 + 1;
        }
        Ok(())
    }

    /// Files one whole line, found at `offset` (of the file, or of chunk `chunk`).
    fn take(&mut self, line: &[u8], chunk: u32, offset: u64, number: usize) -> Result<(), String> {
        if self.footer.is_some() {
            return Err(format!("line {number} follows the footer"));
        }
        let kind: Kind = serde_json::from_slice(line)
            .map_err(|e| format!("line {number} is not a record: {e}"))?;
        match (kind.kind.as_deref(), kind.record.as_deref(), kind.tick) {
            (Some("frame"), _, Some(tick)) => self.frames.push(FrameAt {
                tick,
                chunk,
                len: line.len() as u32,
                offset,
            }),
            // The bot log matters for checking a replay, not for watching one.
            (_, Some("command" | "control"), Some(_)) => {}
            (_, Some("footer"), _) => {
                self.footer = Some(serde_json::from_slice(line).map_err(|e| e.to_string())?)
            }
            _ => {
                return Err(format!(
                    "line {number} is not a frame, command, control or footer record"
                ))
            }
        }
        Ok(())
    }

    /// Frames indexed.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether no frame is indexed.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The tick of frame `k`.
    pub fn tick(&self, k: usize) -> Option<u64> {
        self.frames.get(k).map(|f| f.tick)
    }

    /// The first frame at or after `tick`: a binary search, whatever the file's size.
    pub fn seek(&self, tick: u64) -> Option<usize> {
        let k = self.frames.partition_point(|f| f.tick < tick);
        (k < self.frames.len()).then_some(k)
    }

    /// Whether the file ends with its footer (and in format 2 its trailer) and nothing
    /// is missing.
    pub fn complete(&self) -> bool {
        self.footer.is_some() && self.problem.is_none()
    }

    /// Reads frames `from..` back from `file` (the file indexed): at least one if there
    /// is one, then more, up to `most` of them, while they span at most `budget` bytes
    /// (of the file in format 1, in one read; of frames in format 2, from the chunks
    /// `cache` holds or decompresses).
    pub fn read(
        &self,
        file: &File,
        cache: &mut ChunkCache,
        from: usize,
        most: usize,
        budget: usize,
    ) -> io::Result<Vec<String>> {
        let Some(first) = self.frames.get(from) else {
            return Ok(Vec::new());
        };
        if first.chunk != IN_FILE {
            return self.read_chunked(file, cache, from, most, budget);
        }
        let end_of = |f: &FrameAt| f.offset + u64::from(f.len);
        let last = self.frames[from..]
            .iter()
            .take(most)
            .take_while(|f| end_of(f) - first.offset <= budget as u64)
            .count()
            .max(1);
        let batch = &self.frames[from..from + last];
        let mut bytes = vec![0; (end_of(&batch[last - 1]) - first.offset) as usize];
        file.read_exact_at(&mut bytes, first.offset)?;
        Ok(batch
            .iter()
            .map(|f| {
                let at = (f.offset - first.offset) as usize;
                String::from_utf8_lossy(&bytes[at..at + f.len as usize]).into_owned()
            })
            .collect())
    }

    fn read_chunked(
        &self,
        file: &File,
        cache: &mut ChunkCache,
        from: usize,
        most: usize,
        budget: usize,
    ) -> io::Result<Vec<String>> {
        let mut frames = Vec::new();
        let mut spent = 0;
        for f in self.frames[from..].iter().take(most) {
            let len = f.len as usize;
            if !frames.is_empty() && spent + len > budget {
                break;
            }
            let text = cache.chunk(file, f.chunk, self.chunks[f.chunk as usize])?;
            let at = f.offset as usize;
            let line = text.get(at..at + len).ok_or_else(|| changed(f.chunk))?;
            frames.push(String::from_utf8_lossy(line).into_owned());
            spent += len;
        }
        Ok(frames)
    }
}

/// The error of a chunk that no longer reads as it did when it was indexed.
fn changed(chunk: u32) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidData,
        format!(
            "chunk {} no longer reads as when it was indexed (the file changed)",
            chunk + 1
        ),
    )
}

/// One reader's decompressed chunks of a format 2 file: the two it read last, so that
/// playing on through a chunk, or a batch that spans two, decompresses each once.
#[derive(Default)]
pub struct ChunkCache {
    held: VecDeque<(u32, Vec<u8>)>,
    unpacker: Option<Unpacker>,
}

impl ChunkCache {
    /// Chunks held at most.
    const HELD: usize = 2;

    /// Chunk `k`, at `at` in `file`, decompressed.
    fn chunk(&mut self, file: &File, k: u32, at: ChunkAt) -> io::Result<&[u8]> {
        if let Some(i) = self.held.iter().position(|(j, _)| *j == k) {
            return Ok(&self.held[i].1);
        }
        let mut packed = vec![0; at.len as usize];
        file.read_exact_at(&mut packed, at.offset)?;
        let unpacker = match &mut self.unpacker {
            Some(u) => u,
            None => self.unpacker.insert(Unpacker::new(at.offset)?),
        };
        let mut text = match self.held.len() {
            n if n >= Self::HELD => self.held.pop_front().expect("held").1,
            _ => Vec::new(),
        };
        match unpacker.next(&mut &packed[..], &mut text)? {
            Piece::Chunk { len, .. } if len == u64::from(at.len) => {}
            _ => return Err(changed(k)),
        }
        self.held.push_back((k, text));
        Ok(&self.held.back().expect("just pushed").1)
    }
}

#[cfg(test)]
mod tests {
    use super::{next_line, ChunkCache, Index, Line};
    use crate::replay::{Encoding, Recorder};
    use std::io::Write;

    const HEADER: &str = r#"{"record":"header","format":1,"match":{"id":"m"},"scenario":{"sport":"baseball"},"seed":1}"#;

    fn file_of(text: &str) -> std::fs::File {
        let mut file = tempfile();
        file.write_all(text.as_bytes()).unwrap();
        file
    }

    fn file_of_bytes(bytes: &[u8]) -> std::fs::File {
        let mut file = tempfile();
        file.write_all(bytes).unwrap();
        file
    }

    fn tempfile() -> std::fs::File {
        let path = std::env::temp_dir().join(format!(
            "fieldhouse-index-{}-{:?}",
            std::process::id(),
            std::thread::current().id()
        ));
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(&path)
            .unwrap();
        std::fs::remove_file(&path).unwrap();
        file
    }

    fn frame(tick: u64) -> String {
        format!(
            r#"{{"type":"frame","tick":{tick},"x":"{}"}}"#,
            "y".repeat(tick as usize % 7)
        )
    }

    #[test]
    fn frames_are_found_by_tick_and_read_back_byte_for_byte() {
        let mut text = format!("{HEADER}\n");
        for t in (0..1000).step_by(2) {
            text += &frame(t);
            text += "\n";
            if t % 10 == 0 {
                text += &format!(r#"{{"record":"control","tick":{t},"agent":"cf","bot":true}}"#);
                text += "\n";
            }
        }
        text += r#"{"record":"footer","tick":998,"frames":500,"hash":"h","reason":"finished","result":{}}"#;
        text += "\n";
        let file = file_of(&text);
        let index = Index::build(&file).unwrap();
        assert_eq!(index.len(), 500);
        assert!(index.complete(), "{:?}", index.problem);
        // Seeking is a binary search: the first frame at or after the tick.
        assert_eq!(index.seek(0), Some(0));
        assert_eq!(index.seek(501), Some(251));
        assert_eq!(index.tick(251), Some(502));
        assert_eq!(index.seek(999), None);
        // A batch is what fits the budget, and always at least one frame.
        let batch = index
            .read(&file, &mut ChunkCache::default(), 251, 64, 200)
            .unwrap();
        assert!(!batch.is_empty() && batch.len() < 10, "{}", batch.len());
        assert_eq!(batch[0], frame(502));
        assert_eq!(batch[1], frame(504));
        assert_eq!(
            index
                .read(&file, &mut ChunkCache::default(), 0, 3, 1 << 20)
                .unwrap()
                .len(),
            3
        );
        assert_eq!(
            index
                .read(&file, &mut ChunkCache::default(), 499, 64, 1)
                .unwrap(),
            vec![frame(998)]
        );
        assert!(index
            .read(&file, &mut ChunkCache::default(), 500, 64, 1000)
            .unwrap()
            .is_empty());
    }

    #[test]
    fn a_torn_or_endless_line_ends_the_readable_prefix() {
        let torn = file_of(&format!("{HEADER}\n{}\n{{\"type\":\"fra", frame(0)));
        let index = Index::build(&torn).unwrap();
        assert_eq!(index.len(), 1);
        assert!(index.problem.unwrap().contains("torn"));
        // A header with no end is not read for ever.
        let endless = file_of(&"x".repeat(2 * 1024 * 1024));
        assert!(Index::build(&endless).is_err());
    }

    #[test]
    fn a_grown_file_is_scanned_on_from_where_its_index_stopped() {
        let mut text = format!("{HEADER}\n");
        for t in 0..100 {
            text += &frame(t);
            text += "\n";
        }
        // Cut in the middle of a frame being written.
        let cut = text.len() - 10;
        let mut file = file_of(&text[..cut]);
        let before = Index::build(&file).unwrap();
        assert_eq!(before.len(), 99);
        assert!(before.problem.as_ref().unwrap().contains("torn"));
        file.write_all(&text.as_bytes()[cut..]).unwrap();
        file.write_all(format!("{}\n", frame(100)).as_bytes())
            .unwrap();
        let grown = before.grown(&file).unwrap().unwrap();
        assert_eq!(grown.len(), 101);
        assert_eq!(grown.problem, None);
        assert_eq!(
            grown
                .read(&file, &mut ChunkCache::default(), 99, 2, 1 << 20)
                .unwrap(),
            vec![frame(99), frame(100)]
        );
        let whole = Index::build(&file).unwrap();
        assert_eq!(grown.frames, whole.frames);
        assert_eq!(grown.scanned, whole.scanned);
        // A file that ended at a record that does not read is not scanned on.
        let bad = file_of(&format!("{HEADER}\n{}\nnot json\n", frame(0)));
        assert!(Index::build(&bad).unwrap().grown(&bad).is_none());
    }

    /// A format 2 file of `frames` frames (ticks 0, 2, ...), with a control record every
    /// tenth, finished if `finish`: its bytes.
    fn chunked(frames: u64, finish: bool) -> Vec<u8> {
        let file = tempfile();
        let header: serde_json::Value = serde_json::from_str(HEADER).unwrap();
        let mut r = Recorder::new(
            std::io::BufWriter::new(file.try_clone().unwrap()),
            &header,
            Encoding::Zstd,
        )
        .unwrap();
        for k in 0..frames {
            r.frame(&frame(2 * k)).unwrap();
            if k % 10 == 0 {
                r.log(&format!(
                    r#"{{"record":"control","tick":{k},"agent":"cf","bot":true}}"#
                ))
                .unwrap();
            }
        }
        if finish {
            r.finish(2 * frames, "finished", &serde_json::json!({}))
                .unwrap();
        } else {
            r.cut().unwrap();
            r.flush().unwrap();
        }
        let mut bytes = Vec::new();
        std::io::Seek::rewind(&mut &file).unwrap();
        std::io::Read::read_to_end(&mut &file, &mut bytes).unwrap();
        bytes
    }

    #[test]
    fn a_chunked_file_is_indexed_by_chunk_and_read_back_through_a_cache() {
        let bytes = chunked(1000, true);
        assert_eq!(&bytes[..4], &crate::replay::chunks::MAGIC);
        let file = file_of_bytes(&bytes);
        let index = Index::build(&file).unwrap();
        assert_eq!(index.encoding, Encoding::Zstd);
        assert_eq!(index.header["format"], 2);
        assert!(index.complete(), "{:?}", index.problem);
        assert_eq!(index.len(), 1000);
        // Chunks of 60 lines: the header's, 1100 lines in 19, the footer's.
        assert_eq!(index.chunks.len(), 1 + 19 + 1);
        assert_eq!(index.seek(501), Some(251));
        let mut cache = ChunkCache::default();
        // Played through: every frame, byte for byte, each chunk decompressed once.
        let mut k = 0;
        while k < index.len() {
            let batch = index.read(&file, &mut cache, k, 64, 64 * 1024).unwrap();
            for (j, f) in batch.iter().enumerate() {
                assert_eq!(*f, frame(2 * (k + j) as u64));
            }
            k += batch.len();
        }
        assert!(cache.held.len() <= 2);
        // A budget smaller than a frame still gives one.
        assert_eq!(
            index.read(&file, &mut cache, 999, 64, 1).unwrap(),
            vec![frame(1998)]
        );
    }

    #[test]
    fn a_chunked_file_being_written_is_indexed_by_whole_chunks_and_grows() {
        let whole = chunked(300, true);
        let complete = Index::build(&file_of_bytes(&whole)).unwrap();
        // Cut at many places, mid-chunk and mid-trailer included: the index holds the
        // frames of the whole chunks before the cut, and grows to the complete one.
        let after_header = complete.chunks[1].offset as usize;
        for cut in (after_header..whole.len())
            .step_by(97)
            .chain(whole.len() - 15..whole.len())
        {
            let mut file = file_of_bytes(&whole[..cut]);
            let before = Index::build(&file).unwrap();
            assert!(!before.complete(), "cut at {cut}");
            let shown = before.len();
            assert!(shown <= 300);
            assert_eq!(before.frames[..], complete.frames[..shown], "cut at {cut}");
            if let Some(problem) = &before.problem {
                assert!(
                    problem.contains("torn") || problem.contains("trailer"),
                    "{problem}"
                );
            }
            file.write_all(&whole[cut..]).unwrap();
            let grown = before.grown(&file).unwrap().unwrap();
            assert!(grown.complete(), "cut at {cut}: {:?}", grown.problem);
            assert_eq!(grown.frames, complete.frames);
            assert_eq!(grown.chunks, complete.chunks);
        }
        // A file whose writer cut its last chunk reads to its last frame, incomplete.
        let unfinished = Index::build(&file_of_bytes(&chunked(130, false))).unwrap();
        assert_eq!(unfinished.len(), 130);
        assert_eq!(unfinished.problem, None);
        assert!(!unfinished.complete());
    }

    #[test]
    fn a_corrupt_chunk_ends_the_readable_prefix_and_is_not_scanned_on() {
        let mut bytes = chunked(300, true);
        let complete = Index::build(&file_of_bytes(&bytes)).unwrap();
        let third = complete.chunks[3];
        bytes[third.offset as usize + third.len as usize / 2] ^= 0xff;
        let file = file_of_bytes(&bytes);
        let index = Index::build(&file).unwrap();
        let problem = index.problem.clone().unwrap();
        assert!(problem.starts_with("chunk 4 (byte"), "{problem}");
        assert_eq!(index.frames[..], complete.frames[..index.len()]);
        assert!(index.len() < complete.len());
        assert!(index.grown(&file).is_none());
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
