//! What each agent can do, as the paper's physical capability model: per behaviour, the
//! motion graph and the cost map built from it, embedded at any agent's pose.

mod mover;

pub use mover::{Motion, Mover, Reach, StateMap, Stride};

use crate::costmap::cache;
use crate::motion::{GraphError, MotionLibrary, MotionSource};

/// Which behaviour a defender moves with: the paper's defender "can use any form of
/// nondribbling movement".
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DefenderMotion {
    /// Defensive footwork: the `defense` clips.
    Defense,
    /// Running, as an offensive player without the ball does.
    Run,
    /// Another capture of the motion library, by its behaviour (folder) name, such as a
    /// second running subject (`run-127`): a defender whose motion the offense has no
    /// maps of, for experiments ([`Capabilities::with_capture`] must have built it).
    Capture(&'static str),
}

impl DefenderMotion {
    /// The behaviour's name, as users write it and frames label a player.
    pub fn name(self) -> &'static str {
        match self {
            DefenderMotion::Defense => "defense",
            DefenderMotion::Run => "run",
            DefenderMotion::Capture(name) => name,
        }
    }

    /// `defense`, `run`, or any other behaviour of a motion library (a capture).
    pub fn any(name: &str) -> DefenderMotion {
        name.parse()
            .unwrap_or_else(|_| DefenderMotion::Capture(crate::names::intern(name)))
    }
}

impl serde::Serialize for DefenderMotion {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for DefenderMotion {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        Ok(DefenderMotion::any(&name))
    }
}

impl std::str::FromStr for DefenderMotion {
    type Err = crate::names::UnknownName;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        crate::names::lookup(
            "defender motion",
            s,
            &["defense", "run"],
            &[DefenderMotion::Defense, DefenderMotion::Run],
        )
    }
}

/// How far ahead the basketball maps look, frames at 30 fps (8 s): a slow dribbler
/// must be able to cross most of the half court within a map.
pub const HORIZON_FRAMES: u32 = 240;

/// What building the capabilities is busy with, for a progress display: on first start
/// the graphs and maps take seconds, and a user should see why.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Building a behaviour's motion graph from this many frames of capture.
    Graph {
        /// The behaviour (`dribble`, `run`, `defense`).
        behaviour: &'static str,
        /// Frames of capture the graph is built from.
        frames: usize,
    },
    /// Searching a behaviour's cost map (none was cached).
    Map {
        /// The behaviour (`dribble`, `run`, `defense`).
        behaviour: &'static str,
    },
    /// A behaviour's cost map is ready: shipped, read from the cache, or just built.
    Ready {
        /// The behaviour (`dribble`, `run`, `defense`).
        behaviour: &'static str,
        /// Where its graph and maps came from.
        origin: cache::Origin,
    },
}

impl std::fmt::Display for Stage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stage::Graph { behaviour, frames } => {
                write!(f, "{behaviour}: motion graph of {frames} frames")
            }
            Stage::Map { behaviour } => write!(
                f,
                "{behaviour}: searching its cost maps, one per start state ({HORIZON_FRAMES} frames ahead; cached for next time)"
            ),
            Stage::Ready { behaviour, origin } => write!(f, "{behaviour}: cost maps {origin}"),
        }
    }
}

/// The three behaviours of the basketball domain, and any other captures asked for.
#[derive(Debug, Clone)]
pub struct Capabilities {
    /// The ball handler's.
    pub dribble: Mover,
    /// An offensive player's without the ball; also how a shooter models a defender it
    /// knows nothing about (the paper: its own non-dribbling map).
    pub run: Mover,
    /// Defensive footwork.
    pub defense: Mover,
    /// Other behaviours of the library, built on request ([`Capabilities::with_capture`]):
    /// another subject's running, say, as a defender the offense has no maps of.
    pub captures: Vec<Mover>,
    /// Where the motion capture came from (the embedded CMU clips or a user's
    /// directory), as runs report it.
    pub source: MotionSource,
}

impl Capabilities {
    /// Builds (or finds shipped or cached, as `reuse` allows) the graphs and `search`
    /// maps of `run`, `dribble` and `defense` from `library`, telling `progress` what it
    /// is doing.
    pub fn build(
        library: &MotionLibrary,
        reuse: cache::Reuse<'_>,
        progress: &mut dyn FnMut(Stage),
    ) -> Result<Capabilities, GraphError> {
        Ok(Capabilities {
            dribble: Mover::build(library, "dribble", reuse, progress)?,
            run: Mover::build(library, "run", reuse, progress)?,
            defense: Mover::build(library, "defense", reuse, progress)?,
            captures: Vec::new(),
            source: library.source.clone(),
        })
    }

    /// These capabilities with the behaviour `name` of `library` built too (graph and
    /// maps, cached like the others), for a defender that moves with it
    /// ([`DefenderMotion::Capture`]) or a model made of its maps. Built once: asking
    /// again for a behaviour already there changes nothing.
    pub fn with_capture(
        mut self,
        library: &MotionLibrary,
        name: &str,
        reuse: cache::Reuse<'_>,
        progress: &mut dyn FnMut(Stage),
    ) -> Result<Capabilities, GraphError> {
        if self.by_behaviour(name).is_none() {
            let name = crate::names::intern(name);
            self.captures
                .push(Mover::build(library, name, reuse, progress)?);
        }
        Ok(self)
    }

    /// The mover of a behaviour by name (`dribble`, `run`, `defense`, or a capture built
    /// with [`Capabilities::with_capture`]).
    pub fn by_behaviour(&self, behaviour: &str) -> Option<&Mover> {
        match behaviour {
            "dribble" => Some(&self.dribble),
            "run" => Some(&self.run),
            "defense" => Some(&self.defense),
            _ => self.captures.iter().find(|m| m.behaviour == behaviour),
        }
    }

    /// The mover a defender moving with `motion` uses.
    ///
    /// # Panics
    /// For a [`DefenderMotion::Capture`] these capabilities were not built with: callers
    /// check with [`Capabilities::by_behaviour`] when they take the name.
    pub fn defender(&self, motion: DefenderMotion) -> &Mover {
        match motion {
            DefenderMotion::Defense => &self.defense,
            DefenderMotion::Run => &self.run,
            DefenderMotion::Capture(name) => self.by_behaviour(name).unwrap_or_else(|| {
                panic!("the capture \"{name}\" was not built (Capabilities::with_capture)")
            }),
        }
    }
}
