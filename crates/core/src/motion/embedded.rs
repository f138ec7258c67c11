//! The CMU motion capture compiled into the binary: `build.rs` packs the repository's
//! `data/mocap/<behaviour>/*.{bvh,asf,amc}` into one zstd stream, and this module unpacks it and
//! hands the files to the same loader a directory goes through. So the embedded library
//! and `--mocap data/mocap` give the same clips and the same fingerprint.

use super::loader::{self, Loaded, MotionFile};
use super::{Mirroring, MotionSource};
use std::path::Path;

/// The pack: records of `u32 path length, path, u64 data length, data` (little-endian)
/// in sorted path order, zstd-compressed as one stream (see `build.rs`).
static PACK: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/mocap.zst"));

/// The embedded library's source with `mirroring`, as the build computed it from the
/// files it packed (see `build.rs`): the same the loader gives once the clips are
/// parsed (`embedded_source_is_known_before_parsing`).
pub(super) fn source(mirroring: Mirroring) -> MotionSource {
    let fingerprint = match mirroring {
        Mirroring::On => env!("FIELDHOUSE_EMBEDDED_FINGERPRINT_MIRRORED"),
        Mirroring::Off => env!("FIELDHOUSE_EMBEDDED_FINGERPRINT_PLAIN"),
    };
    MotionSource::Embedded {
        clips: env!("FIELDHOUSE_EMBEDDED_CLIPS")
            .parse()
            .expect("build.rs writes a count"),
        mirroring,
        fingerprint: fingerprint.to_string(),
    }
}

/// The embedded clips at `fps`, with `mirroring`, parsed.
///
/// # Panics
/// If the pack does not unpack or none of its clips parses. Both are build defects that
/// the test suite catches (`embedded_library_is_the_repository_copy`), not conditions a
/// user can meet, so they are not part of the signature.
pub(super) fn parse(fps: f64, mirroring: Mirroring) -> Loaded {
    let (source, loaded) = parse_with_source(fps, mirroring);
    debug_assert_eq!(
        source,
        self::source(mirroring),
        "build.rs and the loader agree"
    );
    loaded
}

/// The embedded clips parsed, with the source the loader computes from them.
fn parse_with_source(fps: f64, mirroring: Mirroring) -> (MotionSource, Loaded) {
    let files = unpack(PACK).expect("the embedded motion capture unpacks");
    loader::from_files(
        files,
        Vec::new(),
        fps,
        mirroring,
        Path::new("embedded"),
        |clips, fingerprint| MotionSource::Embedded {
            clips,
            mirroring,
            fingerprint,
        },
    )
    .expect("the embedded motion capture loads")
    .into_parts()
}

/// The files of a pack, or what is wrong with it.
fn unpack(pack: &[u8]) -> Result<Vec<MotionFile>, String> {
    let raw = zstd::decode_all(pack).map_err(|e| format!("zstd: {e}"))?;
    let mut files = Vec::new();
    let mut rest = raw.as_slice();
    while !rest.is_empty() {
        let path_len = take_u32(&mut rest)? as usize;
        let rel = std::str::from_utf8(take(&mut rest, path_len)?)
            .map_err(|_| "a path is not UTF-8".to_string())?
            .to_string();
        let data_len =
            usize::try_from(take_u64(&mut rest)?).map_err(|_| "a file is too long".to_string())?;
        let bytes = take(&mut rest, data_len)?.to_vec();
        files.push(MotionFile { rel, bytes });
    }
    Ok(files)
}

fn take<'a>(rest: &mut &'a [u8], n: usize) -> Result<&'a [u8], String> {
    if rest.len() < n {
        return Err(format!("the pack ends {} bytes early", n - rest.len()));
    }
    let (head, tail) = rest.split_at(n);
    *rest = tail;
    Ok(head)
}

fn take_u32(rest: &mut &[u8]) -> Result<u32, String> {
    Ok(u32::from_le_bytes(
        take(rest, 4)?.try_into().expect("4 bytes"),
    ))
}

fn take_u64(rest: &mut &[u8]) -> Result<u64, String> {
    Ok(u64::from_le_bytes(
        take(rest, 8)?.try_into().expect("8 bytes"),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::{MotionLibrary, FPS};

    #[test]
    fn embedded_library_is_the_repository_copy() {
        let from_dir =
            MotionLibrary::load(&crate::fixtures::mocap_dir(), FPS, Mirroring::On).unwrap();
        let embedded = MotionLibrary::embedded(FPS, Mirroring::On);
        assert!(embedded.problems().is_empty(), "{:?}", embedded.problems());
        assert_eq!(embedded.source.fingerprint(), from_dir.source.fingerprint());
        assert_eq!(embedded.clips().len(), from_dir.clips().len());
        let MotionSource::Embedded { clips, .. } = embedded.source else {
            panic!("{}", embedded.source)
        };
        // Each captured clip and its mirror image.
        assert_eq!(2 * clips, embedded.clips().len());
        for (a, b) in embedded.clips().iter().zip(from_dir.clips()) {
            assert_eq!((&a.behaviour, &a.name), (&b.behaviour, &b.name));
            assert_eq!(a.frame_count(), b.frame_count());
            assert_eq!(a.frame(a.frame_count() - 1), b.frame(b.frame_count() - 1));
        }
    }

    #[test]
    fn embedded_source_is_known_before_parsing() {
        // What the build says of the pack (count and fingerprints) is what the loader
        // computes from the parsed files, with and without mirroring.
        for mirroring in [Mirroring::On, Mirroring::Off] {
            assert_eq!(parse_with_source(FPS, mirroring).0, source(mirroring));
        }
        assert_ne!(
            source(Mirroring::On).fingerprint(),
            source(Mirroring::Off).fingerprint()
        );
    }

    #[test]
    fn a_cut_or_corrupt_pack_is_refused() {
        let raw = zstd::decode_all(PACK).unwrap();
        // A pack cut inside a record names how much is missing.
        let cut = zstd::encode_all(&raw[..raw.len() - 10], 1).unwrap();
        assert_eq!(unpack(&cut).err().unwrap(), "the pack ends 10 bytes early");
        assert!(unpack(&PACK[..PACK.len() / 2])
            .err()
            .unwrap()
            .starts_with("zstd"));
    }
}
