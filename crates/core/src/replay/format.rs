//! What a replay file is: its format numbers, how it is stored ([`Encoding`]), and what
//! its header says about how it was made.

use super::{chunks, read_at, Source};
use serde_json::Value;
use std::path::Path;

/// The format written by default (chunked zstd, see [the replay module](super)). Bump
/// when a reader of the old format could not read the new one.
pub const FORMAT: u32 = 2;

/// How a replay file is stored (see [the replay module](super)).
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

    /// The encoding of a replay's bytes (an opened file's, say), from its first bytes.
    pub fn of_file<S: Source + ?Sized>(file: &S) -> Result<Encoding, String> {
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
