//! Chunked zstd, the encoding of format 2 replay files: the JSON lines of format 1, cut
//! into chunks of whole lines, each chunk compressed as a zstd frame of its own.
//!
//! ```text
//! [header chunk] [chunk] [chunk] ... [chunk] [footer chunk] [trailer]
//! ```
//!
//! * The **header chunk** holds the header line alone, so listing a file decompresses
//!   a few hundred bytes.
//! * A **chunk** holds whole lines: [`CHUNK_LINES`] of them, or fewer if it reached
//!   [`CHUNK_BYTES`] first or its writer cut it early (the server does when a line has
//!   waited about 2 s, so a live viewer and a crash lose at most that much).
//! * The **footer chunk** holds the footer line alone.
//! * The **trailer** is a zstd *skippable frame* (which zstd's tools skip): the magic
//!   number `0x184D2A5F` and the length 12 (each `u32`, little-endian), then the footer
//!   chunk's offset in the file (`u64`) and its length (`u32`), little-endian: 20 bytes
//!   in all, so the footer is found from the file's last 20 bytes. A file without it was
//!   cut before it was finished.
//!
//! Every chunk frame records its content size and a checksum (XXH64), so a corrupt chunk
//! is found, not read as other lines. Frames are independent: one can be decompressed
//! without the ones before it, and a file cut anywhere reads up to its last whole chunk.
//! Concatenated zstd frames decompress to the concatenation of their contents, so
//! `zstdcat FILE` prints the JSON lines (format 1's encoding).
//!
//! Reading bounds what a file can make it do: a chunk is at most [`MAX_CHUNK_BYTES`],
//! compressed and decompressed, and its window at most 4 MiB.

use std::io::{self, BufRead};
use zstd::stream::raw::{DParameter, Decoder, InBuffer, Operation, OutBuffer};

/// The first bytes of a zstd frame (its magic number, little-endian): how a chunked
/// file is told from JSON lines.
pub const MAGIC: [u8; 4] = [0x28, 0xB5, 0x2F, 0xFD];

/// Lines a chunk holds when it is not cut early: about 60 kB of frames, which compress
/// about as well as the whole file does (a chunk costs some 20 bytes of framing and
/// starts its dictionary afresh).
pub const CHUNK_LINES: usize = 60;

/// A chunk is cut once it holds this many bytes, whatever its lines, so that a chunk of
/// wide lines stays small to read back.
pub const CHUNK_BYTES: usize = 64 * 1024;

/// The most a chunk may hold or take in the file: [`CHUNK_BYTES`] and one line of the
/// longest a reader takes (1 MiB), with room. A larger one is not a chunk this writes.
pub const MAX_CHUNK_BYTES: usize = 2 * 1024 * 1024;

/// The zstd level chunks are written with. On replays' chunks level 1 is both faster
/// and smaller than zstd's default 3 (`zstd -b1 -B48K` on a 600 s baseball replay:
/// 8.9× at 460 MB/s; `-b3`: 8.5× at 310–380 MB/s; cricket 8.7× and 8.4×).
pub const LEVEL: i32 = 1;

/// The trailer's skippable-frame magic number (any of `0x184D2A50..=0x184D2A5F` is one).
const TRAILER_MAGIC: u32 = 0x184D_2A5F;

/// What a trailer carries after its magic and length: the footer chunk's offset (8
/// bytes) and length (4).
const TRAILER_CONTENT: u32 = 12;

/// The trailer's size.
pub const TRAILER_BYTES: usize = 8 + TRAILER_CONTENT as usize;

/// Compresses chunks, reusing its context and buffer from one to the next.
pub(crate) struct Packer {
    compressor: zstd::bulk::Compressor<'static>,
    packed: Vec<u8>,
}

impl Packer {
    pub(crate) fn new(level: i32) -> io::Result<Packer> {
        let mut compressor = zstd::bulk::Compressor::new(level)?;
        compressor.set_parameter(zstd::zstd_safe::CParameter::ChecksumFlag(true))?;
        Ok(Packer {
            compressor,
            packed: Vec::new(),
        })
    }

    /// `text` (whole lines) as one zstd frame.
    pub(crate) fn pack(&mut self, text: &[u8]) -> io::Result<&[u8]> {
        self.packed.clear();
        self.packed
            .reserve(zstd::zstd_safe::compress_bound(text.len()));
        self.compressor.compress_to_buffer(text, &mut self.packed)?;
        Ok(&self.packed)
    }
}

/// The trailer of a file whose footer chunk is at `offset`, `len` bytes long.
pub(crate) fn trailer(offset: u64, len: u32) -> [u8; TRAILER_BYTES] {
    let mut t = [0; TRAILER_BYTES];
    t[..4].copy_from_slice(&TRAILER_MAGIC.to_le_bytes());
    t[4..8].copy_from_slice(&TRAILER_CONTENT.to_le_bytes());
    t[8..16].copy_from_slice(&offset.to_le_bytes());
    t[16..].copy_from_slice(&len.to_le_bytes());
    t
}

/// Where a trailer says the footer chunk is: its offset and length. None if `t` is no
/// trailer.
pub(crate) fn read_trailer(t: &[u8]) -> Option<(u64, u64)> {
    let word = |at: usize| u32::from_le_bytes(t[at..at + 4].try_into().expect("4 bytes"));
    if t.len() != TRAILER_BYTES || word(0) != TRAILER_MAGIC || word(4) != TRAILER_CONTENT {
        return None;
    }
    let offset = u64::from_le_bytes(t[8..16].try_into().expect("8 bytes"));
    Some((offset, u64::from(word(16))))
}

/// What comes next in a chunked file.
#[derive(Debug, PartialEq)]
pub(crate) enum Piece {
    /// A chunk, now decompressed; `at` and `len` are its place in the file.
    Chunk { at: u64, len: u64 },
    /// The trailer, naming the footer chunk's offset.
    Trailer { footer_at: u64 },
    /// The input ends here, between pieces.
    End,
    /// The input ends inside a piece (a file cut there, or still being written).
    Torn { at: u64 },
    /// What is at `at` is no piece of a replay: why.
    Bad { at: u64, why: String },
}

/// Reads a chunked file's pieces one after another, each bounded.
pub(crate) struct Unpacker {
    decoder: Decoder<'static>,
    /// Where the next piece starts in the file.
    at: u64,
    /// What the decoder writes into before it is appended to a chunk's text: the text
    /// grows by at most this at a time, and never past the bound, whatever capacity it
    /// has (decoding straight into it let a chunk fill all its spare capacity, up to
    /// about twice the bound).
    scratch: Vec<u8>,
}

/// The most one decoder step writes, bytes.
const STEP_BYTES: usize = 64 * 1024;

impl Unpacker {
    /// An unpacker of pieces starting at offset `at` of their file.
    pub(crate) fn new(at: u64) -> io::Result<Unpacker> {
        let mut decoder = Decoder::new()?;
        // A chunk's window is at most its content, which is at most 2 MiB: a frame
        // asking for more is not a chunk, and must not make the reader allocate it.
        decoder.set_parameter(DParameter::WindowLogMax(22))?;
        Ok(Unpacker {
            decoder,
            at,
            scratch: vec![0; STEP_BYTES],
        })
    }

    /// Where the next piece starts.
    pub(crate) fn at(&self) -> u64 {
        self.at
    }

    /// Reads the next piece from `input`, decompressing a chunk into `text` (cleared
    /// first). After anything but a chunk or the trailer, where the unpacker stands in
    /// the input is unknown: read no further.
    pub(crate) fn next(
        &mut self,
        input: &mut impl BufRead,
        text: &mut Vec<u8>,
    ) -> io::Result<Piece> {
        text.clear();
        let at = self.at;
        let mut magic = [0; 4];
        let got = read_up_to(input, &mut magic)?;
        if got == 0 {
            return Ok(Piece::End);
        }
        if got < 4 {
            return Ok(Piece::Torn { at });
        }
        if magic == MAGIC {
            return self.chunk(input, text, magic);
        }
        if u32::from_le_bytes(magic) == TRAILER_MAGIC {
            let mut rest = [0; TRAILER_BYTES];
            rest[..4].copy_from_slice(&magic);
            if read_up_to(input, &mut rest[4..])? < TRAILER_BYTES - 4 {
                return Ok(Piece::Torn { at });
            }
            self.at += TRAILER_BYTES as u64;
            return Ok(match read_trailer(&rest) {
                Some((footer_at, _)) => Piece::Trailer { footer_at },
                None => Piece::Bad {
                    at,
                    why: "a skippable frame that is not a replay's trailer".into(),
                },
            });
        }
        Ok(Piece::Bad {
            at,
            why: "not a zstd frame".into(),
        })
    }

    /// Decompresses one frame, whose magic has been read.
    fn chunk(
        &mut self,
        input: &mut impl BufRead,
        text: &mut Vec<u8>,
        magic: [u8; 4],
    ) -> io::Result<Piece> {
        let at = self.at;
        let bad = |why: String| Ok(Piece::Bad { at, why });
        // A frame left half-read by an error or a cut is not carried into this one.
        self.decoder.reinit()?;
        let mut taken = 0u64;
        let mut head: &[u8] = &magic;
        loop {
            if taken > MAX_CHUNK_BYTES as u64 {
                return bad(format!("a chunk longer than {} MiB", MAX_CHUNK_BYTES >> 20));
            }
            let available = if head.is_empty() {
                input.fill_buf()?
            } else {
                head
            };
            let ended = available.is_empty();
            let before = text.len();
            // One byte past the bound is room enough to find a chunk too long.
            let room = STEP_BYTES.min(MAX_CHUNK_BYTES + 1 - before);
            let mut from = InBuffer::around(available);
            let mut into = OutBuffer::around(&mut self.scratch[..room]);
            let hint = self.decoder.run(&mut from, &mut into);
            let produced = into.pos();
            text.extend_from_slice(&self.scratch[..produced]);
            if text.len() > MAX_CHUNK_BYTES {
                return bad(format!("a chunk longer than {} MiB", MAX_CHUNK_BYTES >> 20));
            }
            let used = from.pos();
            if head.is_empty() {
                input.consume(used);
            } else {
                head = &head[used..];
            }
            taken += used as u64;
            match hint {
                Err(e) => return bad(format!("a chunk that does not decompress: {e}")),
                Ok(0) => {
                    self.at += taken;
                    return Ok(Piece::Chunk { at, len: taken });
                }
                Ok(_) if ended && text.len() == before => return Ok(Piece::Torn { at }),
                Ok(_) => {}
            }
        }
    }
}

/// Reads into `buf` until it is full or the input ends; returns how much was read.
fn read_up_to(input: &mut impl BufRead, buf: &mut [u8]) -> io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        let available = input.fill_buf()?;
        if available.is_empty() {
            break;
        }
        let n = available.len().min(buf.len() - got);
        buf[got..got + n].copy_from_slice(&available[..n]);
        input.consume(n);
        got += n;
    }
    Ok(got)
}

/// What starts a piece of a chunked file, told from its headers alone: how a file is
/// walked without decompressing it (see [`super::Index`]).
#[derive(Debug, PartialEq)]
pub(crate) enum Measured {
    /// A chunk of `len` bytes that says it decompresses to `content` bytes (zstd checks
    /// that it does when it is decompressed).
    Chunk { len: u64, content: u64 },
    /// The trailer, naming the footer chunk's offset.
    Trailer { footer_at: u64 },
    /// The bytes end inside the piece: more of them tell what it is.
    Short,
    /// No piece of a replay: why.
    Bad(String),
}

/// Measures the piece `bytes` starts with, reading its frame header and the headers of
/// its blocks but none of its content. A chunk is at most [`MAX_CHUNK_BYTES`] in the file
/// and decompressed, so more bytes than that which still do not hold a whole chunk are
/// [`Measured::Bad`], never [`Measured::Short`].
pub(crate) fn measure(bytes: &[u8]) -> Measured {
    /// The longest zstd frame header.
    const MAX_FRAME_HEADER: usize = 18;
    let Some(magic) = bytes.get(..4) else {
        return Measured::Short;
    };
    if magic == MAGIC {
        let content = match zstd::zstd_safe::get_frame_content_size(bytes) {
            Ok(Some(n)) if n <= MAX_CHUNK_BYTES as u64 => n,
            Ok(Some(_)) => {
                return Measured::Bad(format!("a chunk longer than {} MiB", MAX_CHUNK_BYTES >> 20))
            }
            Ok(None) => return Measured::Bad("a chunk that does not say its size".into()),
            Err(_) if bytes.len() < MAX_FRAME_HEADER => return Measured::Short,
            Err(_) => return Measured::Bad("not a zstd frame header".into()),
        };
        return match zstd::zstd_safe::find_frame_compressed_size(bytes) {
            Ok(len) if len <= MAX_CHUNK_BYTES => Measured::Chunk {
                len: len as u64,
                content,
            },
            Ok(_) => Measured::Bad(format!("a chunk longer than {} MiB", MAX_CHUNK_BYTES >> 20)),
            Err(_) if bytes.len() <= MAX_CHUNK_BYTES => Measured::Short,
            Err(_) => Measured::Bad(format!(
                "a chunk longer than {} MiB, or not a zstd frame",
                MAX_CHUNK_BYTES >> 20
            )),
        };
    }
    if u32::from_le_bytes(magic.try_into().expect("4 bytes")) == TRAILER_MAGIC {
        return match bytes.get(..TRAILER_BYTES).map(read_trailer) {
            None => Measured::Short,
            Some(Some((footer_at, _))) => Measured::Trailer { footer_at },
            Some(None) => Measured::Bad("a skippable frame that is not a replay's trailer".into()),
        };
    }
    Measured::Bad("not a zstd frame".into())
}

/// A whole chunked file read into JSON lines.
pub(crate) struct Unpacked {
    /// The whole chunks' lines, concatenated.
    pub(crate) text: Vec<u8>,
    /// Why the readable part ends before the file does, if it does.
    pub(crate) problem: Option<String>,
    /// Whether the file ends with a trailer naming its last chunk.
    pub(crate) trailer: bool,
    /// Whether `problem` is damage rather than a cut end: a piece that does not read
    /// where the file goes on, or a torn chunk in a file that was finished (its last
    /// bytes are a trailer). A file cut at its end is not damaged: its whole chunks are
    /// all it has.
    pub(crate) damaged: bool,
}

/// Decompresses every whole chunk of `bytes`, up to the first piece that does not read.
pub(crate) fn unpack(bytes: &[u8]) -> Unpacked {
    let mut unpacked = Unpacked {
        // Replays compress about 9×; a file of garbage must not reserve 9× its size.
        text: Vec::with_capacity(bytes.len().saturating_mul(9).min(64 << 20)),
        problem: None,
        trailer: false,
        damaged: false,
    };
    let mut input = bytes;
    let mut chunk = Vec::new();
    let mut unpacker = match Unpacker::new(0) {
        Ok(u) => u,
        Err(e) => {
            unpacked.problem = Some(format!("cannot decompress: {e}"));
            return unpacked;
        }
    };
    let mut last_chunk = None;
    let mut count = 0usize;
    loop {
        let piece = unpacker
            .next(&mut input, &mut chunk)
            .unwrap_or_else(|e| Piece::Bad {
                at: unpacker.at(),
                why: e.to_string(),
            });
        let problem = match piece {
            Piece::Chunk { at, .. } if unpacked.trailer => {
                Some(format!("a chunk at byte {at} follows the trailer"))
            }
            Piece::Chunk { at, .. } => match chunk_problem(&chunk, count, at) {
                Some(p) => Some(p),
                None => {
                    unpacked.text.extend_from_slice(&chunk);
                    last_chunk = Some(at);
                    count += 1;
                    continue;
                }
            },
            Piece::Trailer { footer_at } => match trailer_problem(footer_at, last_chunk) {
                Some(p) => Some(p),
                None if unpacked.trailer => Some("a second trailer".into()),
                None => {
                    unpacked.trailer = true;
                    continue;
                }
            },
            Piece::End => None,
            Piece::Torn { at } => {
                // A finished file ends with its trailer: a chunk torn before it was not
                // cut by a crash but damaged (a size field changed, say).
                let finished = bytes.len() >= TRAILER_BYTES
                    && read_trailer(&bytes[bytes.len() - TRAILER_BYTES..]).is_some();
                unpacked.problem = Some(torn(count, at));
                unpacked.damaged = finished;
                return unpacked;
            }
            Piece::Bad { at, why } => Some(format!("chunk {} (byte {at}): {why}", count + 1)),
        };
        unpacked.damaged = problem.is_some();
        unpacked.problem = problem;
        return unpacked;
    }
}

/// What is wrong with chunk `count` (0 first), at byte `at`, holding `text`, if anything.
pub(crate) fn chunk_problem(text: &[u8], count: usize, at: u64) -> Option<String> {
    (!text.ends_with(b"\n")).then(|| {
        format!(
            "chunk {} (byte {at}) does not end with a whole line",
            count + 1
        )
    })
}

/// What is wrong with a trailer naming `footer_at` after the last chunk at `last`.
pub(crate) fn trailer_problem(footer_at: u64, last: Option<u64>) -> Option<String> {
    (Some(footer_at) != last).then(|| {
        format!("the trailer names a footer chunk at byte {footer_at}, not the last chunk")
    })
}

/// The problem of a file cut inside chunk `count` (0 first), at byte `at`.
pub(crate) fn torn(count: usize, at: u64) -> String {
    format!(
        "chunk {} (byte {at}) is torn (the file was cut mid-chunk, or is being written)",
        count + 1
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn packed(chunks: &[&str]) -> (Vec<u8>, Vec<u64>) {
        let mut packer = Packer::new(LEVEL).unwrap();
        let mut bytes = Vec::new();
        let mut offsets = Vec::new();
        for c in chunks {
            offsets.push(bytes.len() as u64);
            bytes.extend_from_slice(packer.pack(c.as_bytes()).unwrap());
        }
        (bytes, offsets)
    }

    #[test]
    fn pieces_are_measured_from_their_headers_alone() {
        let lines = ["{\"a\":1}\n", &"{\"b\":2}\n".repeat(5000), "{\"c\":3}\n"];
        let (mut bytes, offsets) = packed(&lines);
        let end = bytes.len() as u64;
        bytes.extend_from_slice(&trailer(offsets[2], (end - offsets[2]) as u32));
        for (k, line) in lines.iter().enumerate() {
            let at = offsets[k] as usize;
            let len = offsets.get(k + 1).copied().unwrap_or(end) - offsets[k];
            let expected = Measured::Chunk {
                len,
                content: line.len() as u64,
            };
            assert_eq!(measure(&bytes[at..]), expected, "chunk {k}");
            // Every cut inside it is short, not bad.
            for cut in 0..len as usize {
                assert_eq!(measure(&bytes[at..at + cut]), Measured::Short, "cut {cut}");
            }
        }
        assert_eq!(
            measure(&bytes[end as usize..]),
            Measured::Trailer {
                footer_at: offsets[2]
            }
        );
        assert!(matches!(measure(b"{\"record\":1}"), Measured::Bad(_)));
        // A skippable frame of another kind is not a trailer.
        let mut other = trailer(0, 0);
        other[4] = 5;
        assert!(matches!(measure(&other), Measured::Bad(_)));
        // A frame that says it decompresses past the bound is refused from its header.
        let big = zstd::bulk::compress(&vec![b'x'; MAX_CHUNK_BYTES + 1], 1).unwrap();
        assert!(matches!(measure(&big), Measured::Bad(why) if why.contains("longer")));
        // Bytes past the bound that hold no whole chunk are not read on for ever.
        // (A frame header saying 100 bytes, then empty blocks none of which is last.)
        let mut endless = vec![0x28, 0xB5, 0x2F, 0xFD, 0x20, 100];
        endless.resize(MAX_CHUNK_BYTES + 1, 0);
        assert_eq!(measure(&endless[..1000]), Measured::Short);
        assert!(matches!(measure(&endless), Measured::Bad(_)));
    }

    #[test]
    fn chunks_read_back_one_at_a_time_with_their_places() {
        let (mut bytes, offsets) = packed(&["a\n", "b\nc\n", "footer\n"]);
        bytes.extend_from_slice(&trailer(
            offsets[2],
            (bytes.len() as u64 - offsets[2]) as u32,
        ));
        let mut input = &bytes[..];
        let mut unpacker = Unpacker::new(0).unwrap();
        let mut text = Vec::new();
        for (k, expected) in ["a\n", "b\nc\n", "footer\n"].iter().enumerate() {
            let piece = unpacker.next(&mut input, &mut text).unwrap();
            let end = offsets
                .get(k + 1)
                .copied()
                .unwrap_or(bytes.len() as u64 - 20);
            assert_eq!(
                piece,
                Piece::Chunk {
                    at: offsets[k],
                    len: end - offsets[k]
                }
            );
            assert_eq!(text, expected.as_bytes());
        }
        assert_eq!(
            unpacker.next(&mut input, &mut text).unwrap(),
            Piece::Trailer {
                footer_at: offsets[2]
            }
        );
        assert_eq!(unpacker.next(&mut input, &mut text).unwrap(), Piece::End);
        let whole = unpack(&bytes);
        assert_eq!(whole.text, b"a\nb\nc\nfooter\n");
        assert_eq!(whole.problem, None);
        assert!(whole.trailer);
        // What zstd itself makes of the file: the lines, the trailer skipped.
        assert_eq!(zstd::decode_all(&bytes[..]).unwrap(), b"a\nb\nc\nfooter\n");
    }

    #[test]
    fn a_file_cut_anywhere_reads_up_to_its_last_whole_chunk() {
        let lines: Vec<String> = (0..500).map(|k| format!("{{\"line\":{k}}}\n")).collect();
        let texts: Vec<String> = lines.chunks(60).map(|c| c.concat()).collect();
        let refs: Vec<&str> = texts.iter().map(String::as_str).collect();
        let (bytes, offsets) = packed(&refs);
        let ends: Vec<u64> = offsets[1..]
            .iter()
            .copied()
            .chain([bytes.len() as u64])
            .collect();
        for cut in (0..=bytes.len()).step_by(37).chain([bytes.len()]) {
            let whole = ends.iter().filter(|&&e| e <= cut as u64).count();
            let read = unpack(&bytes[..cut]);
            assert_eq!(
                read.text,
                texts[..whole].concat().as_bytes(),
                "cut at {cut}"
            );
            // A cut end is not damage: the whole chunks are all the file has.
            assert!(!read.damaged, "cut at {cut}");
            if cut == 0 || ends.contains(&(cut as u64)) {
                assert_eq!(read.problem, None, "cut at {cut}");
            } else {
                assert!(read.problem.unwrap().contains("torn"), "cut at {cut}");
            }
        }
    }

    #[test]
    fn a_corrupt_chunk_ends_the_readable_part_there() {
        let (mut bytes, offsets) = packed(&["a\n", "b\n", "c\n"]);
        // A byte of the second chunk's compressed content (past its frame header).
        let k = offsets[1] as usize + 7;
        bytes[k] ^= 0x55;
        let read = unpack(&bytes);
        assert_eq!(read.text, b"a\n");
        assert!(read.damaged);
        let problem = read.problem.unwrap();
        assert!(problem.starts_with("chunk 2 (byte"), "{problem}");
        // Neither a frame nor a trailer.
        let read = unpack(b"\x28\xb5\x2f\xfdnot really zstd at all");
        assert!(read.problem.unwrap().contains("chunk 1"));
        let (good, _) = packed(&["a\n"]);
        let read = unpack(&[&good[..], b"garbage!"].concat());
        assert_eq!(read.text, b"a\n");
        assert!(read.damaged);
        assert!(read.problem.unwrap().contains("not a zstd frame"));
        // A chunk with a torn line.
        let (bytes, _) = packed(&["a\n", "b"]);
        let read = unpack(&bytes);
        assert!(read.damaged);
        assert!(read.problem.unwrap().contains("whole line"));
    }

    /// The bound is the one documented, to the byte: a chunk of exactly
    /// [`MAX_CHUNK_BYTES`] reads, one byte more does not, and nothing past it is held.
    #[test]
    fn the_chunk_bound_is_in_force_to_the_byte() {
        let line = |n: usize| {
            let mut text = vec![b'x'; n - 1];
            text.push(b'\n');
            zstd::encode_all(&text[..], 1).unwrap()
        };
        let read = unpack(&line(MAX_CHUNK_BYTES));
        assert_eq!((read.text.len(), read.problem), (MAX_CHUNK_BYTES, None));
        let read = unpack(&line(MAX_CHUNK_BYTES + 1));
        assert!(read.text.is_empty());
        assert!(read.problem.unwrap().contains("longer than 2 MiB"));
        for size in [3 << 20, 7 << 19] {
            let read = unpack(&line(size));
            assert!(read.text.is_empty(), "{size}");
            assert!(read.problem.is_some(), "{size}");
        }
    }

    #[test]
    fn a_frame_bigger_than_a_chunk_is_refused_without_being_held() {
        let big = zstd::encode_all(&vec![b'x'; 3 * MAX_CHUNK_BYTES][..], 1).unwrap();
        let read = unpack(&big);
        assert!(read.text.is_empty());
        assert!(read.problem.unwrap().contains("longer than 2 MiB"));
        // Two bytes in a frame that asks for a 128 MiB window: refused, not allocated.
        let mut encoder = zstd::stream::write::Encoder::new(Vec::new(), 1).unwrap();
        encoder.window_log(27).unwrap();
        std::io::Write::write_all(&mut encoder, b"a\n").unwrap();
        let wide = encoder.finish().unwrap();
        let read = unpack(&wide);
        assert!(read.text.is_empty());
        let problem = read.problem.unwrap();
        assert!(problem.contains("does not decompress"), "{problem}");
    }
}
