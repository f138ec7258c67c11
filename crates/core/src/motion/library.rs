//! A behaviour-labelled collection of clips: the CMU motion capture embedded in the
//! binary, or a user's own capture read from a directory (one folder per behaviour).

use super::loader::{self, Loaded};
use super::{embedded, Clip, Jump};
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use thiserror::Error;

/// Whether a library also plays every clip mirrored, left and right exchanged (see
/// [`Clip::mirrored`](super::Clip)): on by default, since one take of a movement to one
/// side says what a body can do to the other.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Mirroring {
    /// Every clip and its mirror image.
    #[default]
    On,
    /// The clips as captured, only.
    Off,
}

/// Where the motion came from: named wherever motion is used, so everyone knows what the
/// agents move with.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MotionSource {
    /// The CMU motion capture compiled into the binary (the repository's `data/mocap`).
    Embedded {
        /// Clips loaded (captured ones; mirror images are not counted).
        clips: usize,
        /// Whether each clip is also played mirrored.
        mirroring: Mirroring,
        /// See [`MotionSource::fingerprint`].
        fingerprint: String,
    },
    /// A user's own capture (BVH, or CMU's ASF/AMC), read from `dir`.
    Directory {
        /// The directory given (`--mocap DIR`).
        dir: PathBuf,
        /// Clips loaded (captured ones; mirror images are not counted).
        clips: usize,
        /// Whether each clip is also played mirrored.
        mirroring: Mirroring,
        /// See [`MotionSource::fingerprint`].
        fingerprint: String,
    },
}

impl MotionSource {
    /// A hash over every loaded file's relative path and bytes, and whether the clips are
    /// also mirrored: the same data gives the same fingerprint, embedded or read from a
    /// directory, on any machine. What cached artefacts built from the motion are keyed
    /// by, and what a replay records.
    pub fn fingerprint(&self) -> &str {
        match self {
            MotionSource::Embedded { fingerprint, .. }
            | MotionSource::Directory { fingerprint, .. } => fingerprint,
        }
    }

    /// The directory a user's capture was read from: for the operator's own log only,
    /// never for visitors (the [`Display`](fmt::Display) form names no path).
    pub fn dir(&self) -> Option<&Path> {
        match self {
            MotionSource::Embedded { .. } => None,
            MotionSource::Directory { dir, .. } => Some(dir),
        }
    }
}

/// What visitors are shown (the page, `/readyz`, `/api/matches`, command output): the
/// kind of motion and its size, never a path of the machine it runs on.
impl fmt::Display for MotionSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let plural = |n: usize| if n == 1 { "" } else { "s" };
        let mirrored = |m: &Mirroring| match m {
            Mirroring::On => " and their mirror images",
            Mirroring::Off => "",
        };
        match self {
            MotionSource::Embedded {
                clips, mirroring, ..
            } => {
                write!(
                    f,
                    "CMU motion capture, embedded: {clips} clip{}{}",
                    plural(*clips),
                    mirrored(mirroring)
                )
            }
            MotionSource::Directory {
                clips,
                mirroring,
                fingerprint,
                ..
            } => write!(
                f,
                "user capture: {clips} clip{}{}, fingerprint {fingerprint}",
                plural(*clips),
                mirrored(mirroring)
            ),
        }
    }
}

/// A clip that could not be loaded; the others still are.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{}{}: {message}", file.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct LoadProblem {
    /// The file (or behaviour folder) that could not be read or parsed.
    pub(crate) file: PathBuf,
    /// 1-based line of the problem, where there is one.
    pub line: Option<usize>,
    /// What is wrong with it.
    pub(crate) message: String,
}

/// Why a motion directory gave no library.
#[derive(Debug, Error)]
pub enum LibraryError {
    /// The chain printed with `{:#}` adds the OS error once, after this message.
    #[error("cannot read motion directory {}", dir.display())]
    Unreadable {
        /// The directory given.
        dir: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// Not one clip loaded.
    #[error(
        "no motion clip could be loaded from {} (looked for DIR/<behaviour>/*.bvh, and *.amc with their .asf skeleton)",
        dir.display()
    )]
    Empty {
        /// The directory given.
        dir: PathBuf,
        /// Why each file failed.
        problems: Vec<LoadProblem>,
    },
}

/// Every clip of a motion source, labelled by behaviour.
///
/// The embedded library is parsed when its clips are first asked for, not when it is
/// made: its [`MotionSource`] is known from the build (clip count and fingerprint), and
/// a command whose graphs and maps are shipped or cached never needs a clip, so it starts
/// without the ~0.3 s that parsing the capture takes.
#[derive(Debug, Clone)]
pub struct MotionLibrary {
    /// Where the clips came from.
    pub source: MotionSource,
    loaded: OnceLock<Loaded>,
    /// The embedded library's frame rate and mirroring, to parse it with on first use;
    /// `None` for a directory's, parsed as it is read.
    embedded: Option<(f64, Mirroring)>,
}

impl MotionLibrary {
    /// A library whose clips are parsed already.
    pub(super) fn parsed(source: MotionSource, loaded: Loaded) -> MotionLibrary {
        MotionLibrary {
            source,
            loaded: OnceLock::from(loaded),
            embedded: None,
        }
    }

    /// Loads every `DIR/<behaviour>/*.bvh`, and every `DIR/<behaviour>/*.amc` with its
    /// skeleton (the folder's `<subject>.asf` for `<subject>_<trial>.amc`, or its only
    /// `.asf`), resampled to `fps`, with `mirroring`. A clip that fails to parse is
    /// reported in `problems` and the rest still load; it is an error only if nothing
    /// loads.
    pub fn load(dir: &Path, fps: f64, mirroring: Mirroring) -> Result<MotionLibrary, LibraryError> {
        loader::load_library(dir, fps, mirroring)
    }

    /// The CMU motion capture compiled into the binary, resampled to `fps`, with
    /// `mirroring`: the motion every command uses unless told to read a directory.
    /// Parsed on first use of its clips.
    pub fn embedded(fps: f64, mirroring: Mirroring) -> MotionLibrary {
        MotionLibrary {
            source: embedded::source(mirroring),
            loaded: OnceLock::new(),
            embedded: Some((fps, mirroring)),
        }
    }

    /// The source and the parsed clips.
    pub(super) fn into_parts(self) -> (MotionSource, Loaded) {
        self.loaded();
        let loaded = self.loaded.into_inner().expect("parsed just now");
        (self.source, loaded)
    }

    fn loaded(&self) -> &Loaded {
        self.loaded.get_or_init(|| {
            let (fps, mirroring) = self
                .embedded
                .expect("a directory's library is parsed as it is read");
            embedded::parse(fps, mirroring)
        })
    }

    /// Clips sorted by behaviour, then name, so everything built from them is
    /// deterministic whatever order the file system lists them in; with
    /// [`Mirroring::On`], each clip's mirror image follows it (named `…-mirror`).
    pub fn clips(&self) -> &[Clip] {
        &self.loaded().clips
    }

    /// Clips that failed to load, with file and line.
    pub fn problems(&self) -> &[LoadProblem] {
        &self.loaded().problems
    }

    /// The behaviours present, sorted.
    pub fn behaviours(&self) -> Vec<&str> {
        let mut names: Vec<&str> = self.clips().iter().map(|c| c.behaviour.as_str()).collect();
        names.dedup();
        names
    }

    /// A behaviour's clips as its motion graph uses them: each cut at the crouch before
    /// its first jump, if it has one (see [`Jump`]). The graphs are of moving on the
    /// ground; in the CMU dribbling the jumps are the jump shots that end 06_14 and 06_15,
    /// and what follows them is the shooter standing without the ball.
    pub fn ground_clips(&self, behaviour: &str) -> Vec<Clip> {
        self.clips_of(behaviour)
            .map(|c| match Jump::find(c) {
                Some(jump) => c.head(jump.crouch),
                None => c.clone(),
            })
            .collect()
    }

    /// The clips of `behaviour`, whole (jumps included).
    pub fn clips_of<'a>(&'a self, behaviour: &'a str) -> impl Iterator<Item = &'a Clip> + 'a {
        self.clips()
            .iter()
            .filter(move |c| c.behaviour == behaviour)
    }
}
