//! Where each frame of a replay file is, so a file of any size can be played, sought and
//! shared without holding its frames: the server scans a file once (a line at a time,
//! every line bounded), keeps each frame's tick, offset and length, and reads frames
//! back from the file when a viewer needs them.

use super::{parse_header, MAX_HEADER_BYTES};
use crate::sim::Scenario;
use serde::Deserialize;
use serde_json::Value;
use std::fs::File;
use std::io::{self, BufRead, BufReader, Read, Seek, SeekFrom};
use std::os::unix::fs::FileExt;

/// The longest record read after the header: frames are kilobytes (the longest line of
/// a basketball replay with cost maps was 1.4 kB), so a longer line is not one, and the
/// readable prefix ends there rather than memory running out. It also bounds what one
/// viewer holds of a file at a time.
pub const MAX_LINE_BYTES: usize = 1024 * 1024;

/// A frame's place in its file.
#[derive(Debug, Clone, Copy, PartialEq)]
struct FrameAt {
    tick: u64,
    offset: u64,
    /// Without the newline.
    len: u32,
}

/// A replay file's header, footer and frame positions: everything but the frames.
#[derive(Debug, Clone)]
pub struct Index {
    /// The header record (see the module doc of [`super`]).
    pub header: Value,
    /// The scenario the header records, parsed.
    pub scenario: Scenario,
    frames: Vec<FrameAt>,
    /// The footer record, if the file has one.
    pub footer: Option<Value>,
    /// Why the readable prefix ends early, as [`super::Replay::problem`].
    pub problem: Option<String>,
    /// Where the scan stopped: after the last whole line read, and that line's number
    /// plus one.
    scanned: (u64, usize),
    /// Whether the scan stopped at the file's end (maybe in a line being written) rather
    /// than at a record that does not read: a file that has grown since can be scanned
    /// on from `scanned` (see [`Index::grown`]).
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
    /// Scans `file` from its start. Only a missing or unreadable header is an error
    /// (the same cases as [`super::parse`]); anything later that does not read ends the
    /// readable prefix, with the reason in `problem`. Memory: one line at a time.
    pub fn build(mut file: &File) -> Result<Index, String> {
        file.seek(SeekFrom::Start(0)).map_err(|e| e.to_string())?;
        let mut first = Vec::new();
        BufReader::new(file.take(MAX_HEADER_BYTES))
            .read_until(b'\n', &mut first)
            .map_err(|e| e.to_string())?;
        let (header, scenario) = parse_header(&first)?;
        let mut index = Index {
            header,
            scenario,
            frames: Vec::new(),
            footer: None,
            problem: None,
            scanned: (first.len() as u64, 2),
            at_end: false,
        };
        index.scan(file)?;
        Ok(index)
    }

    /// The index of `file`, the file this index is of, grown since it was scanned (a
    /// replay being written): the frames already found are kept and only the bytes
    /// after them are read. None if there is nothing to read on from (the scan ended at
    /// the footer or at a record that does not read).
    pub fn grown(&self, file: &File) -> Option<Result<Index, String>> {
        if !self.at_end || self.footer.is_some() {
            return None;
        }
        let mut index = Index {
            problem: None,
            at_end: false,
            ..self.clone()
        };
        Some(index.scan(file).map(|()| index))
    }

    /// Reads whole lines from `scanned` on, to the end or the first that does not read.
    fn scan(&mut self, mut file: &File) -> Result<(), String> {
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
                Ok(Line::Whole) => self.take(&line, offset, number).err(),
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

    /// Files one whole line, found at `offset`.
    fn take(&mut self, line: &[u8], offset: u64, number: usize) -> Result<(), String> {
        if self.footer.is_some() {
            return Err(format!("line {number} follows the footer"));
        }
        let kind: Kind = serde_json::from_slice(line)
            .map_err(|e| format!("line {number} is not a record: {e}"))?;
        match (kind.kind.as_deref(), kind.record.as_deref(), kind.tick) {
            (Some("frame"), _, Some(tick)) => self.frames.push(FrameAt {
                tick,
                offset,
                len: line.len() as u32,
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

    /// Whether the file ends with its footer and nothing is missing.
    pub fn complete(&self) -> bool {
        self.footer.is_some() && self.problem.is_none()
    }

    /// Reads frames `from..` back from `file` (the file indexed), in one read: at least
    /// one if there is one, then more, up to `most` of them, while they span at most
    /// `budget` bytes.
    pub fn read(
        &self,
        file: &File,
        from: usize,
        most: usize,
        budget: usize,
    ) -> io::Result<Vec<String>> {
        let Some(first) = self.frames.get(from) else {
            return Ok(Vec::new());
        };
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
}

#[cfg(test)]
mod tests {
    use super::{next_line, Index, Line};
    use std::io::Write;

    const HEADER: &str = r#"{"record":"header","format":1,"match":{"id":"m"},"scenario":{"sport":"baseball"},"seed":1}"#;

    fn file_of(text: &str) -> std::fs::File {
        let mut file = tempfile();
        file.write_all(text.as_bytes()).unwrap();
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
        let batch = index.read(&file, 251, 64, 200).unwrap();
        assert!(!batch.is_empty() && batch.len() < 10, "{}", batch.len());
        assert_eq!(batch[0], frame(502));
        assert_eq!(batch[1], frame(504));
        assert_eq!(index.read(&file, 0, 3, 1 << 20).unwrap().len(), 3);
        assert_eq!(index.read(&file, 499, 64, 1).unwrap(), vec![frame(998)]);
        assert!(index.read(&file, 500, 64, 1000).unwrap().is_empty());
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
            grown.read(&file, 99, 2, 1 << 20).unwrap(),
            vec![frame(99), frame(100)]
        );
        let whole = Index::build(&file).unwrap();
        assert_eq!(grown.frames, whole.frames);
        assert_eq!(grown.scanned, whole.scanned);
        // A file that ended at a record that does not read is not scanned on.
        let bad = file_of(&format!("{HEADER}\n{}\nnot json\n", frame(0)));
        assert!(Index::build(&bad).unwrap().grown(&bad).is_none());
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
