//! Reading a motion library from disk: every `DIR/<behaviour>/*.bvh` becomes a clip of
//! global joint positions at the requested frame rate. One bad file costs one clip,
//! reported with its file and line, never the library.

use super::bvh::{self, ParseError};
use super::skeleton::global_positions;
use super::{resample::resample, Clip, ClipError, LibraryError, LoadProblem};
use super::{MotionLibrary, MotionSource};
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

/// Loads every `DIR/<behaviour>/*.bvh` (the folder name is the behaviour; other files
/// are ignored), resampled to `fps`, sorted by (behaviour, name).
pub(super) fn load_library(dir: &Path, fps: f64) -> Result<MotionLibrary, LibraryError> {
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

    let mut clips = Vec::new();
    let mut problems = Vec::new();
    // (relative path, bytes) of each loaded file, for the fingerprint.
    let mut loaded = Vec::new();
    for behaviour_dir in behaviours {
        let behaviour = file_name(&behaviour_dir);
        let files = match bvh_files(&behaviour_dir) {
            Ok(files) => files,
            Err(e) => {
                problems.push(ClipFileError::Io(e).into_problem(behaviour_dir));
                continue;
            }
        };
        for file in files {
            let name = file
                .file_stem()
                .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
            match load_clip(&file, &name, &behaviour, fps) {
                Ok((clip, bytes)) => {
                    loaded.push((format!("{behaviour}/{}", file_name(&file)), bytes));
                    clips.push(clip);
                }
                Err(e) => problems.push(e.into_problem(file)),
            }
        }
    }
    for problem in &problems {
        tracing::warn!(%problem, "skipped a motion clip");
    }
    if clips.is_empty() {
        return Err(LibraryError::Empty {
            dir: dir.to_path_buf(),
            problems,
        });
    }
    clips.sort_by(|a, b| (&a.behaviour, &a.name).cmp(&(&b.behaviour, &b.name)));
    let fingerprint = fingerprint(&mut loaded);
    tracing::info!(dir = %dir.display(), clips = clips.len(), skipped = problems.len(), %fingerprint, "loaded motion capture");
    Ok(MotionLibrary {
        source: MotionSource::Mocap {
            dir: dir.to_path_buf(),
            fingerprint,
        },
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

/// Reads one file into a clip, returning its bytes too for the fingerprint.
fn load_clip(
    file: &Path,
    name: &str,
    behaviour: &str,
    fps: f64,
) -> Result<(Clip, Vec<u8>), ClipFileError> {
    let bytes = fs::read(file)?;
    Ok((clip_from_bytes(&bytes, name, behaviour, fps)?, bytes))
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
    Ok(Clip::new(name, behaviour, fps, names, positions)?)
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
/// sorted by path: the same data gives the same fingerprint on any machine. Lengths
/// prefix each part so no two different libraries can run together the same stream.
fn fingerprint(files: &mut [(String, Vec<u8>)]) -> String {
    files.sort_by(|a, b| a.0.cmp(&b.0));
    let mut hash = Sha256::new();
    for (path, bytes) in files.iter() {
        hash.update((path.len() as u64).to_le_bytes());
        hash.update(path.as_bytes());
        hash.update((bytes.len() as u64).to_le_bytes());
        hash.update(bytes);
    }
    hash.finalize()[..8]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

#[cfg(test)]
mod tests;
