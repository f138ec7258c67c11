//! What each agent can do, as the paper's physical capability model: per behaviour, the
//! motion graph and the cost map built from it, embedded at any agent's pose.

use crate::costmap::{cache, AgentPose, BuildParams, CostMap, LocalFrame};
use crate::motion::{
    GraphError, GraphParams, MotionGraph, MotionLibrary, MotionSource, RootStep, Walker,
};
use glam::DVec2;
use std::path::Path;

/// One behaviour an agent moves with: its motion graph and cost map.
#[derive(Debug, Clone)]
pub struct Mover {
    pub graph: MotionGraph,
    pub map: CostMap,
}

/// One frame of a planned move: where the root is and which way it faces, and the
/// motion-graph node playing (so a client can draw the pose).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stride {
    pub at: Walker,
    pub node: u32,
}

impl Mover {
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
        let mut at = Walker {
            position: pose.position,
            facing: DVec2::from_angle(pose.heading),
        };
        let mut out = vec![Stride {
            at,
            node: self.map.start_node,
        }];
        for &id in &self.map.paths[cell] {
            let e = &self.graph.edges[id as usize];
            // An edge of a graph built from clips takes one frame; split a longer one
            // evenly so playback keeps the data's rate.
            let k = e.frames.max(1);
            let step = RootStep {
                dx: e.step.dx / f64::from(k),
                dz: e.step.dz / f64::from(k),
                dheading: e.step.dheading / f64::from(k),
            };
            for _ in 0..k {
                at = at.step(&step);
                out.push(Stride { at, node: e.to });
            }
        }
        out
    }

    /// Of the cells this agent reaches, the one that gets it to `goal` soonest: the
    /// frames to the cell plus the rest of the way at the behaviour's top speed. This is
    /// the "cheapest heading" toward a goal the map itself may not reach.
    pub fn cell_toward(
        &self,
        pose: &AgentPose,
        goal: DVec2,
        allowed: impl Fn(DVec2) -> bool,
    ) -> Option<usize> {
        let grid = &self.map.grid;
        let speed = self.map.top_speed_m_s.max(0.1);
        let mut best: Option<(f64, usize)> = None;
        for (cell, cost) in self.map.costs.iter().enumerate() {
            let Some(frames) = cost else { continue };
            let world = pose.to_world(grid.centre(cell));
            if !allowed(world) {
                continue;
            }
            let eta = f64::from(*frames) / self.map.fps + world.distance(goal) / speed;
            if best.is_none_or(|(b, _)| eta < b) {
                best = Some((eta, cell));
            }
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
/// Transition threshold of the dribbling graph, RMS metres.
pub const DRIBBLE_THRESHOLD_M: f64 = 0.12;

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
    /// `run`, `dribble` and `defense` from `library`.
    pub fn build(
        library: &MotionLibrary,
        cache_dir: Option<&Path>,
    ) -> Result<Capabilities, GraphError> {
        let mover = |behaviour: &str| -> Result<Mover, GraphError> {
            let clips: Vec<_> = library.clips_of(behaviour).collect();
            let window = GraphParams::default().window;
            let graph = match behaviour {
                // The automatic threshold keeps the CMU dribbling at 0.08 m, where its two
                // clips barely meet: the map then reaches 46 cells in 5 s. At 0.12 m it
                // reaches most of the court.
                "dribble" => MotionGraph::build(
                    behaviour,
                    &clips,
                    GraphParams {
                        window,
                        threshold_m: DRIBBLE_THRESHOLD_M,
                    },
                )?,
                _ => MotionGraph::build_auto(behaviour, &clips, window)?,
            };
            let params = BuildParams {
                depth: HORIZON_FRAMES,
                ..BuildParams::default()
            };
            let (map, from_cache) = cache::build_or_load(
                cache_dir,
                library.source.fingerprint(),
                &graph,
                &params,
                &mut |_| {},
            );
            tracing::debug!(behaviour, from_cache, "cost map ready");
            Ok(Mover { graph, map })
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
