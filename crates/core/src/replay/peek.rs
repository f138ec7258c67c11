//! A replay's header and footer without its frames, read with bounds: for listing many
//! large files, and for the index to start from.

use super::chunks;
use super::format::{Encoding, FORMAT};
use super::{read_at, ReadFrom, Source};
use crate::sim::Scenario;
use serde_json::Value;
use std::io;

/// The longest header line read: a first line longer than this is no replay's header
/// (real ones are a few kilobytes), and reading one must not take a line without end.
pub const MAX_HEADER_BYTES: u64 = 1024 * 1024;

/// How much of a file's end is read to find its footer.
const TAIL_BYTES: u64 = 64 * 1024;

/// The header and (if the file is complete) the footer, without reading the frames
/// between them: for listing many large files. Reads at most [`MAX_HEADER_BYTES`] from
/// the start and 64 KiB from the end, whatever the file holds (in format 2: the header
/// chunk, the trailer and the footer chunk it names).
pub fn peek<S: Source + ?Sized>(file: &S) -> Result<(Value, Option<Value>), String> {
    match Encoding::of_file(file)? {
        Encoding::Plain => peek_plain(file),
        Encoding::Zstd => {
            let (header, _) = chunked_header(file)?;
            Ok((header, chunked_footer(file)?))
        }
    }
}

fn peek_plain<S: Source + ?Sized>(file: &S) -> Result<(Value, Option<Value>), String> {
    use std::io::{BufRead, Read};
    let mut first = Vec::new();
    io::BufReader::new(ReadFrom::new(file, 0).take(MAX_HEADER_BYTES))
        .read_until(b'\n', &mut first)
        .map_err(|e| e.to_string())?;
    let (header, _) = parse_header(&first)?;
    let len = file.size().map_err(|e| e.to_string())?;
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
pub(crate) fn chunked_header<S: Source + ?Sized>(file: &S) -> Result<(Value, Scenario), String> {
    use std::io::Read;
    let mut input = io::BufReader::new(ReadFrom::new(file, 0).take(MAX_HEADER_BYTES));
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
fn chunked_footer<S: Source + ?Sized>(file: &S) -> Result<Option<Value>, String> {
    let len = file.size().map_err(|e| e.to_string())?;
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
