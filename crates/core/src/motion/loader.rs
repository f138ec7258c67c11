//! Reading a motion library: every `DIR/<behaviour>/*.bvh`, and every
//! `DIR/<behaviour>/*.amc` with its ASF skeleton, becomes a clip of global joint
//! positions at the requested frame rate. One bad file costs one clip (a bad skeleton,
//! the clips that need it), reported with its file and line, never the library.

use super::acclaim;
use super::amc;
use super::asf::{self, Skeleton};
use super::bvh::{self, ParseError};
use super::skeleton::global_positions;
use super::{resample::resample, Clip, ClipError, LibraryError, LoadProblem};
use super::{Mirroring, MotionLibrary, MotionSource};
use sha2::{Digest, Sha256};
use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why one file did not become a clip.
#[derive(Debug, Error)]
enum ClipFileError {
    #[error("cannot read: {0}")]
    Io(#[from] std::io::Error),
    #[error("not text: BVH, ASF and AMC files are plain ASCII")]
    NotText,
    #[error(transparent)]
    Parse(#[from] ParseError),
    #[error(transparent)]
    Acclaim(#[from] asf::ParseError),
    #[error("only the reference pose: no captured frames follow it")]
    NoCapturedFrames,
    #[error("no skeleton: no {wanted}, and not exactly one .asf file beside the clip")]
    NoSkeleton { wanted: String },
    /// The skeleton `rel` (below the library's root) failed; the problem is reported at
    /// its line, naming the clip it costs.
    #[error("{error} (the skeleton of {clip}, which is not loaded)")]
    BadSkeleton {
        rel: String,
        clip: String,
        error: SkeletonError,
    },
    #[error("cannot resample to {0} frames per second")]
    BadFrameRate(f64),
    #[error(
        "{seconds:.0} s of motion at {fps} frames per second is more than a clip may hold \
         ({max} joint positions)",
        max = amc::MAX_JOINT_FRAMES
    )]
    TooLong { seconds: f64, fps: f64 },
    #[error(transparent)]
    Clip(#[from] ClipError),
}

/// Why a skeleton could not be read: the same for every clip that needs it.
#[derive(Debug, Clone, Error)]
enum SkeletonError {
    #[error("not text: ASF files are plain ASCII")]
    NotText,
    #[error("{}", .0.kind)]
    Parse(asf::ParseError),
}

impl SkeletonError {
    fn line(&self) -> Option<usize> {
        match self {
            SkeletonError::Parse(e) => Some(e.line),
            SkeletonError::NotText => None,
        }
    }
}

impl ClipFileError {
    /// The problem, reported under `root/rel` (the clip's file) or, for a bad skeleton,
    /// at the skeleton's file and line.
    fn into_problem(self, root: &Path, rel: &str) -> LoadProblem {
        let (file, line, message) = match &self {
            // The problem carries the line separately, so the message omits it.
            ClipFileError::Parse(e) => (rel, Some(e.line), e.kind.to_string()),
            ClipFileError::Acclaim(e) => (rel, Some(e.line), e.kind.to_string()),
            ClipFileError::BadSkeleton {
                rel: skeleton,
                error,
                ..
            } => (skeleton.as_str(), error.line(), self.to_string()),
            _ => (rel, None, self.to_string()),
        };
        LoadProblem {
            file: root.join(file),
            line,
            message,
        }
    }
}

/// A file or folder that could not be read at all.
fn unreadable(path: PathBuf, error: std::io::Error) -> LoadProblem {
    LoadProblem {
        file: path,
        line: None,
        message: ClipFileError::Io(error).to_string(),
    }
}

/// One file of a library: its path below the library's root (`behaviour/name.bvh`,
/// which names its behaviour and clip) and its bytes. A BVH or AMC file is a clip, an
/// ASF file the skeleton of the AMC clips beside it.
pub(super) struct MotionFile {
    pub rel: String,
    pub bytes: Vec<u8>,
}

/// The kinds of file a library reads, by extension (any case).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum FileKind {
    Bvh,
    Asf,
    Amc,
}

impl FileKind {
    pub(super) fn of(path: &Path) -> Option<FileKind> {
        let extension = path.extension()?.to_str()?.to_ascii_lowercase();
        match extension.as_str() {
            "bvh" => Some(FileKind::Bvh),
            "asf" => Some(FileKind::Asf),
            "amc" => Some(FileKind::Amc),
            _ => None,
        }
    }
}

/// Loads every `DIR/<behaviour>/*.bvh` and `*.amc` (with its `.asf`; the folder name is
/// the behaviour; other files are ignored), resampled to `fps`, sorted by (behaviour,
/// name), with `mirroring`.
#[allow(
    clippy::disallowed_methods,
    reason = "a named reader: a user's motion-capture directory, given its path"
)]
pub(super) fn load_library(
    dir: &Path,
    fps: f64,
    mirroring: Mirroring,
) -> Result<MotionLibrary, LibraryError> {
    let unreadable_dir = |source| LibraryError::Unreadable {
        dir: dir.to_path_buf(),
        source,
    };
    let mut behaviours = Vec::new();
    for entry in fs::read_dir(dir).map_err(unreadable_dir)? {
        let path = entry.map_err(unreadable_dir)?.path();
        if path.is_dir() {
            behaviours.push(path);
        }
    }
    behaviours.sort();

    let mut files = Vec::new();
    let mut problems = Vec::new();
    for behaviour_dir in behaviours {
        let paths = match motion_files(&behaviour_dir) {
            Ok(paths) => paths,
            Err(e) => {
                problems.push(unreadable(behaviour_dir, e));
                continue;
            }
        };
        for path in paths {
            match fs::read(&path) {
                Ok(bytes) => files.push(MotionFile {
                    rel: format!("{}/{}", file_name(&behaviour_dir), file_name(&path)),
                    bytes,
                }),
                Err(e) => problems.push(unreadable(path, e)),
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

/// A library's parsed clips and the files that failed.
#[derive(Debug, Clone)]
pub(super) struct Loaded {
    pub(super) clips: Vec<Clip>,
    pub(super) problems: Vec<LoadProblem>,
}

/// Parses `files` into a library whose source `source(clips, fingerprint)` names, each
/// clip followed by its mirror image with [`Mirroring::On`]. A file that fails costs its
/// clip, reported in `problems` under `root/rel`; a skeleton that fails costs the AMC
/// clips that need it, each reported at the skeleton. It is an error only if nothing
/// loads. Directory and embedded libraries both come through here, so the same files give
/// the same clips and the same fingerprint wherever they are read from.
pub(super) fn from_files(
    files: Vec<MotionFile>,
    mut problems: Vec<LoadProblem>,
    fps: f64,
    mirroring: Mirroring,
    root: &Path,
    source: impl FnOnce(usize, String) -> MotionSource,
) -> Result<MotionLibrary, LibraryError> {
    let (skeleton_files, clip_files): (Vec<MotionFile>, Vec<MotionFile>) = files
        .into_iter()
        .partition(|f| FileKind::of(Path::new(&f.rel)) == Some(FileKind::Asf));
    let mut skeletons = Skeletons::new(skeleton_files);
    // The skeletons the loaded clips were read on: they shape those clips, so they count
    // toward the fingerprint too.
    let mut used = BTreeSet::new();
    let mut clips = Vec::new();
    let mut loaded = Vec::new();
    for file in clip_files {
        let rel = Path::new(&file.rel);
        let behaviour = rel.parent().map_or_else(String::new, file_name);
        let name = rel
            .file_stem()
            .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
        let clip = match FileKind::of(rel) {
            Some(FileKind::Amc) => skeletons.for_clip(&file.rel).and_then(|(asf, skeleton)| {
                let clip = clip_from_amc(&file.bytes, skeleton, &name, &behaviour, fps)?;
                used.insert(asf);
                Ok(clip)
            }),
            _ => clip_from_bytes(&file.bytes, &name, &behaviour, fps),
        };
        match clip {
            Ok(clip) => {
                clips.push(clip);
                loaded.push(file);
            }
            Err(e) => problems.push(e.into_problem(root, &file.rel)),
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
    loaded.extend(skeletons.take(&used));
    Ok(MotionLibrary::parsed(
        source(captured, fingerprint(&mut loaded, mirroring)),
        Loaded { clips, problems },
    ))
}

/// The ASF files of a library, each read once, when a clip first needs it, on the
/// skeleton Hahne's BVH conversion uses ([`acclaim::like_hahne_bvh`]).
struct Skeletons {
    files: BTreeMap<String, MotionFile>,
    read: BTreeMap<String, Result<Skeleton, SkeletonError>>,
}

impl Skeletons {
    fn new(files: Vec<MotionFile>) -> Skeletons {
        Skeletons {
            files: files.into_iter().map(|f| (f.rel.clone(), f)).collect(),
            read: BTreeMap::new(),
        }
    }

    /// The skeleton of the AMC file `rel` (`behaviour/102_12.amc`), and its file: the
    /// folder's `102.asf` (CMU names a trial subject_trial), or else the folder's only
    /// ASF file.
    fn for_clip(&mut self, rel: &str) -> Result<(String, &Skeleton), ClipFileError> {
        let path = Path::new(rel);
        let folder = path.parent().map_or_else(String::new, file_name);
        let stem = path
            .file_stem()
            .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
        let subject = stem.split('_').next().unwrap_or_default();
        let wanted = format!("{folder}/{subject}.asf");
        let in_folder: Vec<&String> = self
            .files
            .keys()
            .filter(|k| Path::new(k).parent().map_or_else(String::new, file_name) == folder)
            .collect();
        let chosen = match in_folder.iter().find(|k| k.eq_ignore_ascii_case(&wanted)) {
            Some(k) => (*k).clone(),
            None if in_folder.len() == 1 => in_folder[0].clone(),
            None => return Err(ClipFileError::NoSkeleton { wanted }),
        };
        let bytes = &self.files[&chosen].bytes;
        let skeleton = self.read.entry(chosen.clone()).or_insert_with(|| {
            let text = std::str::from_utf8(bytes).map_err(|_| SkeletonError::NotText)?;
            let skeleton = asf::parse(text).map_err(SkeletonError::Parse)?;
            Ok(acclaim::like_hahne_bvh(&skeleton))
        });
        match skeleton {
            Ok(skeleton) => Ok((chosen, skeleton)),
            Err(error) => Err(ClipFileError::BadSkeleton {
                rel: chosen,
                clip: file_name(path),
                error: error.clone(),
            }),
        }
    }

    /// The files `rels`.
    fn take(mut self, rels: &BTreeSet<String>) -> Vec<MotionFile> {
        rels.iter()
            .filter_map(|rel| self.files.remove(rel))
            .collect()
    }
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned())
}

/// The `*.bvh`, `*.asf` and `*.amc` files in one behaviour folder, sorted.
#[allow(
    clippy::disallowed_methods,
    reason = "a named reader: a user's motion-capture directory, given its path"
)]
fn motion_files(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for entry in fs::read_dir(dir)? {
        let path = entry?.path();
        if FileKind::of(&path).is_some() && path.is_file() {
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
        .map_err(|e| e.into_problem(Path::new(""), name).to_string())
}

/// An ASF skeleton's and an AMC motion's bytes as a clip resampled to `fps`, exactly as
/// the loader reads them, or what is wrong (with the line, for a parse error). Public
/// for the fuzz target `asf_amc` (fuzz/), which feeds it arbitrary bytes.
pub fn parse_acclaim_clip(
    asf: &[u8],
    amc: &[u8],
    name: &str,
    behaviour: &str,
    fps: f64,
) -> Result<Clip, String> {
    let mut skeletons = Skeletons::new(vec![MotionFile {
        rel: format!("{behaviour}/skeleton.asf"),
        bytes: asf.to_vec(),
    }]);
    let rel = format!("{behaviour}/{name}.amc");
    skeletons
        .for_clip(&rel)
        .and_then(|(_, skeleton)| clip_from_amc(amc, skeleton, name, behaviour, fps))
        .map_err(|e| e.into_problem(Path::new(""), &rel).to_string())
}

fn clip_from_bvh(
    bvh: &bvh::Bvh,
    name: &str,
    behaviour: &str,
    fps: f64,
) -> Result<Clip, ClipFileError> {
    check_fps(fps)?;
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

/// An AMC file read on `skeleton` as a clip. Every frame is movement: AMC has no
/// reference pose.
fn clip_from_amc(
    bytes: &[u8],
    skeleton: &Skeleton,
    name: &str,
    behaviour: &str,
    fps: f64,
) -> Result<Clip, ClipFileError> {
    check_fps(fps)?;
    let text = std::str::from_utf8(bytes).map_err(|_| ClipFileError::NotText)?;
    let motion = amc::parse(text, skeleton)?;
    let names = acclaim::joint_names(skeleton);
    // The reader caps the frames captured; a slow capture rate resampled to a faster
    // one multiplies them (1 Hz to 30 fps, thirtyfold), so the clip is capped the same.
    let seconds = (motion.frame_count() - 1) as f64 / motion.frame_rate;
    if (seconds * fps + 1.0) * names.len() as f64 > amc::MAX_JOINT_FRAMES as f64 {
        return Err(ClipFileError::TooLong { seconds, fps });
    }
    let positions = acclaim::global_positions(skeleton, &motion, 0..motion.frame_count());
    let positions = resample(&positions, names.len(), motion.frame_rate, fps);
    Ok(Clip::new(name, behaviour, fps, names, positions)?.with_parents(acclaim::parents(skeleton)))
}

fn check_fps(fps: f64) -> Result<(), ClipFileError> {
    if fps.is_finite() && fps > 0.0 {
        Ok(())
    } else {
        Err(ClipFileError::BadFrameRate(fps))
    }
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
