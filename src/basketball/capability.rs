//! What each agent can do, as the paper's physical capability model: per behaviour, the
//! motion graph and the cost map built from it, embedded at any agent's pose.

use super::court::Court;
use super::footprint::Footprint;
use crate::costmap::{cache, AgentPose, BuildParams, CostMap, LocalFrame};
use crate::motion::{
    GraphError, MotionGraph, MotionLibrary, MotionSource, RootStep, Walker, AUTO_WINDOWS,
};
use glam::DVec2;
use std::path::Path;

/// One behaviour an agent moves with: its motion graph and cost map.
#[derive(Debug, Clone)]
pub struct Mover {
    /// The behaviour's name (`dribble`, `run`, `defense`), as frames label a player.
    pub behaviour: &'static str,
    pub graph: MotionGraph,
    pub map: CostMap,
    /// Per map cell, the ground its stored path covers: checking a move against the
    /// court costs a few hull vertices instead of a walk of every frame.
    footprints: Vec<Footprint>,
    /// Per graph edge, how it is played: one root step (with its turn as cos, sin) per
    /// data frame, and how many frames. Worked out once, since paths are walked for
    /// every move an agent considers.
    edge_frames: Vec<(RootStep, DVec2, usize)>,
}

/// One frame of a planned move: where the root is and which way it faces, and the
/// motion-graph node playing (so a client can draw the pose).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stride {
    pub at: Walker,
    pub node: u32,
}

impl Mover {
    pub fn new(behaviour: &'static str, graph: MotionGraph, map: CostMap) -> Mover {
        let edge_frames = graph
            .edges
            .iter()
            .map(|e| {
                // An edge of a graph built from clips takes one frame; split a longer one
                // evenly so playback keeps the data's rate.
                let k = e.frames.max(1);
                let step = RootStep {
                    dx: e.step.dx / f64::from(k),
                    dz: e.step.dz / f64::from(k),
                    dheading: e.step.dheading / f64::from(k),
                };
                (step, DVec2::from_angle(step.dheading), k as usize)
            })
            .collect();
        let mut mover = Mover {
            behaviour,
            graph,
            map,
            footprints: Vec::new(),
            edge_frames,
        };
        let origin = AgentPose {
            position: DVec2::ZERO,
            heading: 0.0,
        };
        mover.footprints = (0..mover.map.costs.len())
            .map(|cell| Footprint::of(mover.walk(&origin, cell).map(|s| s.at.position)))
            .collect();
        mover
    }

    /// Seconds for an agent whose frame is `frame` ([`AgentPose::frame`], prepared once
    /// for many look-ups) to reach the world point `world`; `None` beyond the map
    /// (farther than its horizon or its extent).
    #[inline]
    pub fn seconds_in(&self, frame: &LocalFrame, world: DVec2) -> Option<f64> {
        self.map
            .cost_in(frame, world)
            .map(|frames| f64::from(frames) / self.map.fps)
    }

    /// The map's horizon: what "beyond the map" is at least, in seconds.
    pub fn horizon_s(&self) -> f64 {
        f64::from(self.map.depth) / self.map.fps
    }

    /// The stored path to map cell `cell` played from `pose`: one stride per data frame,
    /// starting with the pose itself. Root motion is relative, so the path found from the
    /// map's start pose holds at any pose (the paper's TEAMBOTS agents did the same).
    pub fn strides_to(&self, pose: &AgentPose, cell: usize) -> Vec<Stride> {
        self.walk(pose, cell).collect()
    }

    /// Whether the stored path to `cell`, played by the agent whose frame is `frame`
    /// ([`AgentPose::frame`]), keeps the body on `court`, or at most `margin_m` beyond its
    /// lines, at every frame (and between frames, where the body moves in straight lines).
    pub fn path_on_court(
        &self,
        frame: &LocalFrame,
        cell: usize,
        court: &Court,
        margin_m: f64,
    ) -> bool {
        self.footprints[cell].within(frame, court, margin_m)
    }

    /// The strides of the stored path to `cell` from `pose`, without collecting them.
    fn walk<'a>(&'a self, pose: &AgentPose, cell: usize) -> impl Iterator<Item = Stride> + 'a {
        let start = Stride {
            at: Walker {
                position: pose.position,
                facing: DVec2::from_angle(pose.heading),
            },
            node: self.map.start_node,
        };
        let steps = self.map.paths[cell].iter().flat_map(move |&id| {
            let (step, turn, k) = self.edge_frames[id as usize];
            std::iter::repeat_n((step, turn, self.graph.edges[id as usize].to), k)
        });
        std::iter::once(start).chain(steps.scan(start.at, |at, (step, turn, node)| {
            *at = at.after(&step, turn);
            Some(Stride { at: *at, node })
        }))
    }

    /// Of the cells this agent reaches along a path that stays on `court` (within
    /// `margin_m` of its lines) and ends on it at least a cell nearer `goal`, the one that
    /// gets it there soonest: the frames to the cell plus the rest of the way at the
    /// behaviour's top speed. This is the "cheapest heading" toward a goal the map itself
    /// may not reach, or reaches only by a path that leaves the court; `None` if no such
    /// move gets nearer.
    ///
    /// A move must make progress: the rest of the way is counted at top speed, which no
    /// real move beats, so the cell the agent stands in (no frames, the whole way at top
    /// speed) would otherwise always win and the agent would never set off.
    pub fn cell_toward(
        &self,
        pose: &AgentPose,
        goal: DVec2,
        court: &Court,
        margin_m: f64,
    ) -> Option<usize> {
        let grid = &self.map.grid;
        let speed = self.map.top_speed_m_s.max(0.1);
        let nearer_than = pose.position.distance(goal) - grid.cell_m;
        let frame = pose.frame();
        let mut best: Option<(f64, usize)> = None;
        for (cell, cost) in self.map.costs.iter().enumerate() {
            let Some(frames) = cost else { continue };
            let world = frame.to_world(grid.centre(cell));
            let remaining = world.distance(goal);
            let eta = f64::from(*frames) / self.map.fps + remaining / speed;
            // The path check costs most: only a cell that would win is checked.
            if best.is_some_and(|(b, _)| eta >= b)
                || remaining > nearer_than
                || !court.contains(world)
                || !self.path_on_court(&frame, cell, court, margin_m)
            {
                continue;
            }
            best = Some((eta, cell));
        }
        best.map(|(_, cell)| cell)
    }

    /// The farthest an agent with this map gets from where it stands within `seconds`,
    /// in any direction, m: a danger radius read off the map rather than fixed.
    pub fn radius_within(&self, seconds: f64) -> f64 {
        let grid = &self.map.grid;
        self.map
            .costs
            .iter()
            .enumerate()
            .filter(|(_, c)| c.is_some_and(|f| f64::from(f) / self.map.fps <= seconds))
            .map(|(cell, _)| grid.centre(cell).length())
            .fold(0.0, f64::max)
    }

    /// The map cell holding the world point `world` for an agent at `pose`, if reachable.
    pub fn reachable_cell(&self, pose: &AgentPose, world: DVec2) -> Option<usize> {
        let cell = self.map.grid.cell_of(pose.to_local(world))?;
        self.map.costs[cell].map(|_| cell)
    }
}

/// Which behaviour a defender moves with: the paper's defender "can use any form of
/// nondribbling movement".
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DefenderMotion {
    Defense,
    Run,
}

impl DefenderMotion {
    pub fn name(self) -> &'static str {
        match self {
            DefenderMotion::Defense => "defense",
            DefenderMotion::Run => "run",
        }
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
        behaviour: &'static str,
        frames: usize,
    },
    /// Searching a behaviour's cost map (none was cached).
    Map { behaviour: &'static str },
    /// A behaviour's cost map is ready: read from the cache, or just built.
    Ready {
        behaviour: &'static str,
        cached: bool,
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
                "{behaviour}: searching its cost map ({HORIZON_FRAMES} frames ahead; cached for next time)"
            ),
            Stage::Ready { behaviour, cached } => write!(
                f,
                "{behaviour}: cost map {}",
                if *cached { "read from the cache" } else { "built" }
            ),
        }
    }
}

/// The three behaviours of the basketball domain.
#[derive(Debug, Clone)]
pub struct Capabilities {
    /// The ball handler's.
    pub dribble: Mover,
    /// An offensive player's without the ball; also how a shooter models a defender it
    /// knows nothing about (the paper: its own non-dribbling map).
    pub run: Mover,
    /// Defensive footwork.
    pub defense: Mover,
    pub source: MotionSource,
}

impl Capabilities {
    /// Builds (or reads from the cache under `cache_dir`) the graphs and `search` maps of
    /// `run`, `dribble` and `defense` from `library`, telling `progress` what it is doing.
    pub fn build(
        library: &MotionLibrary,
        cache_dir: Option<&Path>,
        progress: &mut dyn FnMut(Stage),
    ) -> Result<Capabilities, GraphError> {
        let mut mover = |behaviour: &'static str| -> Result<Mover, GraphError> {
            let owned = library.ground_clips(behaviour);
            let clips: Vec<_> = owned.iter().collect();
            progress(Stage::Graph {
                behaviour,
                frames: clips.iter().map(|c| c.frame_count()).sum(),
            });
            let graph = MotionGraph::build_auto(behaviour, &clips, &AUTO_WINDOWS)?;
            let params = BuildParams {
                depth: HORIZON_FRAMES,
                ..BuildParams::default()
            };
            let mut searching = false;
            let (map, cached) = cache::build_or_load(
                cache_dir,
                library.source.fingerprint(),
                &graph,
                &params,
                &mut |_| {
                    if !searching {
                        searching = true;
                        progress(Stage::Map { behaviour });
                    }
                },
            );
            progress(Stage::Ready { behaviour, cached });
            Ok(Mover::new(behaviour, graph, map))
        };
        Ok(Capabilities {
            dribble: mover("dribble")?,
            run: mover("run")?,
            defense: mover("defense")?,
            source: library.source.clone(),
        })
    }

    /// The mover of a behaviour by name (`dribble`, `run`, `defense`).
    pub fn by_behaviour(&self, behaviour: &str) -> Option<&Mover> {
        match behaviour {
            "dribble" => Some(&self.dribble),
            "run" => Some(&self.run),
            "defense" => Some(&self.defense),
            _ => None,
        }
    }

    pub fn defender(&self, motion: DefenderMotion) -> &Mover {
        match motion {
            DefenderMotion::Defense => &self.defense,
            DefenderMotion::Run => &self.run,
        }
    }
}
