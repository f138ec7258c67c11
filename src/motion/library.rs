//! A behaviour-labelled collection of clips: loaded from a BVH directory (one folder per
//! behaviour) or, without one, the built-in synthetic locomotion library.

use super::{loader, synthetic, Clip};
use std::fmt;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Where the motion came from: shown wherever motion is used, so nobody mistakes the
/// synthetic stand-in for human data.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MotionSource {
    /// BVH motion capture read from `dir`. `fingerprint` is a hash over every loaded
    /// file's relative path and bytes: the same data gives the same fingerprint.
    Mocap { dir: PathBuf, fingerprint: String },
    /// The built-in synthetic locomotion library.
    Synthetic,
}

impl MotionSource {
    /// What cached artefacts built from this motion are keyed by.
    pub fn fingerprint(&self) -> &str {
        match self {
            MotionSource::Mocap { fingerprint, .. } => fingerprint,
            MotionSource::Synthetic => "synthetic",
        }
    }
}

impl fmt::Display for MotionSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MotionSource::Mocap { dir, fingerprint } => {
                write!(f, "mocap {} ({fingerprint})", dir.display())
            }
            MotionSource::Synthetic => f.write_str("synthetic"),
        }
    }
}

/// A clip that could not be loaded; the others still are.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{}{}: {message}", file.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct LoadProblem {
    pub file: PathBuf,
    /// 1-based line of the problem, where there is one.
    pub line: Option<usize>,
    pub message: String,
}

#[derive(Debug, Error)]
pub enum LibraryError {
    #[error("cannot read motion directory {dir}: {source}")]
    Unreadable {
        dir: PathBuf,
        source: std::io::Error,
    },
    #[error("no BVH clip could be loaded from {dir} (looked for DIR/<behaviour>/*.bvh)")]
    Empty {
        dir: PathBuf,
        problems: Vec<LoadProblem>,
    },
}

#[derive(Debug, Clone)]
pub struct MotionLibrary {
    pub source: MotionSource,
    /// Clips sorted by behaviour, then name, so everything built from them is
    /// deterministic whatever order the file system lists them in.
    pub clips: Vec<Clip>,
    /// Clips that failed to load, with file and line.
    pub problems: Vec<LoadProblem>,
}

impl MotionLibrary {
    /// Loads every `DIR/<behaviour>/*.bvh`, resampled to `fps`. A clip that fails to
    /// parse is reported in `problems` and the rest still load; it is an error only if
    /// nothing loads.
    pub fn load(dir: &Path, fps: f64) -> Result<MotionLibrary, LibraryError> {
        loader::load_library(dir, fps)
    }

    /// The built-in synthetic locomotion library at `fps`.
    pub fn synthetic(fps: f64) -> MotionLibrary {
        MotionLibrary {
            source: MotionSource::Synthetic,
            clips: synthetic::clips(fps),
            problems: vec![],
        }
    }

    /// The behaviours present, sorted.
    pub fn behaviours(&self) -> Vec<&str> {
        let mut names: Vec<&str> = self.clips.iter().map(|c| c.behaviour.as_str()).collect();
        names.dedup();
        names
    }

    pub fn clips_of<'a>(&'a self, behaviour: &'a str) -> impl Iterator<Item = &'a Clip> + 'a {
        self.clips.iter().filter(move |c| c.behaviour == behaviour)
    }
}
