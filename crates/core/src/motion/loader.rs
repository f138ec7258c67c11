//! Reading a motion library from disk: every `DIR/<behaviour>/*.bvh` becomes a clip of
//! global joint positions at the requested frame rate. One bad file costs one clip,
//! reported with its file and line, never the library.

use super::bvh::{self, ParseError};
use super::skeleton::global_positions;
use super::{resample::resample, Clip, ClipError, LibraryError, LoadProblem};
use super::{Mirroring, MotionLibrary, MotionSource};
use sha2::{Digest, Sha256};
use std::fs;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why one file did not become a clip.
#[derive(Debug, Error)]
enum ClipFileError {
    #[error("cannot read: {0}")]
    Io(#[from] std::io::Error),
    #[error("not text: BVH is plain ASCII")]
    NotText,
    #[error(transparent)]
    Parse(#[from] ParseError),
    #[error("only the reference pose: no captured frames follow it")]
    NoCapturedFrames,
    #[error("cannot resample to {0} frames per second")]
    BadFrameRate(f64),
    #[error(transparent)]
    Clip(#[from] ClipError),
}

impl ClipFileError {
    fn into_problem(self, file: PathBuf) -> LoadProblem {
        let (line, message) = match self {
            // The problem carries the line separately, so the message omits it.
            ClipFileError::Parse(e) => (Some(e.line), e.kind.to_string()),
            other => (None, other.to_string()),
        };
        LoadProblem {
            file,
            line,
            message,
        }
    }
}

/// One BVH file of a library: its path below the library's root (`behaviour/name.bvh`,
/// which names its behaviour and clip) and its bytes.
pub(super) struct MotionFile {
    pub rel: String,
    pub bytes: Vec<u8>,
}

/// Loads every `DIR/<behaviour>/*.bvh` (the folder name is the behaviour; other files
/// are ignored), resampled to `fps`, sorted by (behaviour, name), with `mirroring`.
pub(super) fn load_library(
    dir: &Path,
    fps: f64,
    mirroring: Mirroring,
) -> Result<MotionLibrary, LibraryError> {
    let unreadable = |source| LibraryError::Unreadable {
        dir: dir.to_path_buf(),
        source,
    };
    let mut behaviours = Vec::new();
    for entry in fs::read_dir(dir).map_err(unreadable)? {
        let path = entry.map_err(unreadable)?.path();
        if path.is_dir() {
            behaviours.push(path);
        }
    }
    behaviours.sort();

    let mut files = Vec::new();
    let mut problems = Vec::new();
    for behaviour_dir in behaviours {
        let paths = match bvh_files(&behaviour_dir) {
            Ok(paths) => paths,
            Err(e) => {
                problems.push(ClipFileError::Io(e).into_problem(behaviour_dir));
                continue;
            }
        };
        for path in paths {
            match fs::read(&path) {
                Ok(bytes) => files.push(MotionFile {
                    rel: format!("{}/{}", file_name(&behaviour_dir), file_name(&path)),
                    bytes,
                }),
                Err(e) => problems.push(ClipFileError::Io(e).into_problem(path)),
            }
        }
    }
    from_files(
        files,
        problems,
        fps,
        mirroring,
        dir,
        |clips, fingerprint| MotionSource::Directory {
            dir: dir.to_path_buf(),
            clips,
            mirroring,
            fingerprint,
        },
    )
}

/// Parses `files` into a library whose source `source(clips, fingerprint)` names, each
/// clip followed by its mirror image with [`Mirroring::On`]. A file that fails costs its
/// clip, reported in `problems` under `root/rel`; it is an error only if nothing loads.
/// Directory and embedded libraries both come through here, so the same files give the
/// same clips and the same fingerprint wherever they are read from.
pub(super) fn from_files(
    files: Vec<MotionFile>,
    mut problems: Vec<LoadProblem>,
    fps: f64,
    mirroring: Mirroring,
    root: &Path,
    source: impl FnOnce(usize, String) -> MotionSource,
) -> Result<MotionLibrary, LibraryError> {
    let mut clips = Vec::new();
    let mut loaded = Vec::new();
    for file in files {
        let rel = Path::new(&file.rel);
        let behaviour = rel.parent().map_or_else(String::new, file_name);
        let name = rel
            .file_stem()
            .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
        match clip_from_bytes(&file.bytes, &name, &behaviour, fps) {
            Ok(clip) => {
                clips.push(clip);
                loaded.push(file);
            }
            Err(e) => problems.push(e.into_problem(root.join(rel))),
        }
    }
    for problem in &problems {
        tracing::warn!(%problem, "skipped a motion clip");
    }
    if clips.is_empty() {
        return Err(LibraryError::Empty {
            dir: root.to_path_buf(),
            problems,
        });
    }
    clips.sort_by(|a, b| (&a.behaviour, &a.name).cmp(&(&b.behaviour, &b.name)));
    let captured = clips.len();
    if mirroring == Mirroring::On {
        clips = clips
            .into_iter()
            .flat_map(|clip| {
                let mirror = clip.mirrored();
                [clip, mirror]
            })
            .collect();
    }
    Ok(MotionLibrary {
        source: source(captured, fingerprint(&mut loaded, mirroring)),
        clips,
        problems,
    })
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned())
}

/// The `*.bvh` files in one behaviour folder, sorted.
fn bvh_files(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for entry in fs::read_dir(dir)? {
        let path = entry?.path();
        let is_bvh = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("bvh"));
        if is_bvh && path.is_file() {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}

fn clip_from_bytes(
    bytes: &[u8],
    name: &str,
    behaviour: &str,
    fps: f64,
) -> Result<Clip, ClipFileError> {
    let text = std::str::from_utf8(bytes).map_err(|_| ClipFileError::NotText)?;
    clip_from_bvh(&bvh::parse(text)?, name, behaviour, fps)
}

/// One BVH file's bytes as a clip resampled to `fps`, exactly as the loader reads each
/// file, or what is wrong with it (with the line, for a parse error). Public for the
/// fuzz target `bvh` (fuzz/), which feeds it arbitrary bytes.
pub fn parse_clip(bytes: &[u8], name: &str, behaviour: &str, fps: f64) -> Result<Clip, String> {
    clip_from_bytes(bytes, name, behaviour, fps)
        .map_err(|e| e.into_problem(PathBuf::from(name)).to_string())
}

fn clip_from_bvh(
    bvh: &bvh::Bvh,
    name: &str,
    behaviour: &str,
    fps: f64,
) -> Result<Clip, ClipFileError> {
    if !(fps.is_finite() && fps > 0.0) {
        return Err(ClipFileError::BadFrameRate(fps));
    }
    // The first frame is the reference (T-)pose the capture was calibrated on, not
    // movement: a motion graph must never blend into it.
    if bvh.frame_count() < 2 {
        return Err(ClipFileError::NoCapturedFrames);
    }
    let positions = global_positions(bvh, 1..bvh.frame_count());
    let joints = bvh.joints.len();
    let positions = resample(&positions, joints, capture_rate(bvh.frame_time), fps);
    let names = bvh.joints.iter().map(|j| j.name.clone()).collect();
    let parents = bvh.joints.iter().map(|j| j.parent).collect();
    Ok(Clip::new(name, behaviour, fps, names, positions)?.with_parents(parents))
}

/// The capture rate in Hz. Files write the frame time rounded (`.0083333` for 120 Hz),
/// and capture systems run at whole rates, so a rate within 0.1% of a whole number is
/// taken as that number: 120 → 30 then samples exactly every 4th frame instead of
/// drifting by 4 ppm and blending neighbours.
fn capture_rate(frame_time: f64) -> f64 {
    let rate = 1.0 / frame_time;
    let whole = rate.round();
    if whole >= 1.0 && (rate - whole).abs() < 1e-3 * whole {
        whole
    } else {
        rate
    }
}

/// Hex of the first 8 bytes of a SHA-256 over each file's relative path and bytes,
/// sorted by path, and the mirroring: the same data gives the same fingerprint on any
/// machine. Lengths prefix each part so no two different libraries can run together the
/// same stream; a mirrored library hashes a marker first (no file record starts with it,
/// a length prefix being eight bytes), and an unmirrored one hashes exactly its files.
fn fingerprint(files: &mut [MotionFile], mirroring: Mirroring) -> String {
    files.sort_by(|a, b| a.rel.cmp(&b.rel));
    let mut hash = Sha256::new();
    if mirroring == Mirroring::On {
        hash.update(b"mirrored");
    }
    for file in files.iter() {
        hash.update((file.rel.len() as u64).to_le_bytes());
        hash.update(file.rel.as_bytes());
        hash.update((file.bytes.len() as u64).to_le_bytes());
        hash.update(&file.bytes);
    }
    hash.finalize()[..8]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

#[cfg(test)]
mod tests;
