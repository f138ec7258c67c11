//! Cost maps (Sukthankar, Mandel & Sycara 2008): for each square around an agent, how many
//! frames a real human needs to get there with a behaviour, from a start state (`start`:
//! a node of the motion graph; standing, or one of the ways the data moves). Three
//! builders behind one interface: the paper's Monte Carlo (`mc`), a systematic search
//! (`search`: backward over per-node cost-to-go maps, one pass for any number of starts,
//! or forward where obstacles break the pose invariance) and the grassfire distance
//! baseline (`grassfire`). `mirror` makes a stance's map and its mirror twin's exact
//! reflections of each other.

mod backward;
pub mod cache;
mod grassfire;
mod grid;
mod mc;
mod mirror;
mod prepared;
mod search;
mod start;

pub use crate::motion::Walker;
pub use grid::{AgentPose, Grid, LocalFrame, LocalLattice, Obstacle};
pub use mirror::symmetrise;
pub use search::SearchParams;
pub use start::{root_speed, start_states, Start, StartState, STANDING_MIRRORED};

use crate::motion::{Constraints, MotionGraph};
use crate::names::{lookup, UnknownName};
use glam::DVec2;
use prepared::Prepared;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::str::FromStr;

/// How a cost map is built.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// The paper's: random walks on the motion graph, keeping the cheapest arrival in
    /// each cell.
    Mc,
    /// Systematic search of the graph's walks: backward over cost-to-go maps, topped up
    /// near the start with random walks; forward where there are obstacles.
    Search,
    /// The baseline: distance around obstacles at the behaviour's top speed, ignoring
    /// how a body turns; it stores no paths.
    Grassfire,
}

impl Method {
    /// The method's name, as users write it and maps record it.
    pub fn name(self) -> &'static str {
        match self {
            Method::Mc => "mc",
            Method::Search => "search",
            Method::Grassfire => "grassfire",
        }
    }
}

impl FromStr for Method {
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        lookup(
            "method",
            s,
            &["mc", "search", "grassfire"],
            &[Method::Mc, Method::Search, Method::Grassfire],
        )
    }
}

/// Everything that decides a map, besides the motion graph.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BuildParams {
    /// How the map is built.
    pub method: Method,
    /// The cells it covers, in the agent's frame.
    pub grid: Grid,
    /// Monte Carlo walks.
    pub iterations: u64,
    /// Longest walk or search horizon, in frames.
    pub depth: u32,
    /// Seeds the random walks (Monte Carlo, and those `search` adds near the start).
    pub seed: u64,
    /// How finely `search` tells states apart.
    #[serde(skip)]
    pub search: SearchParams,
    /// If set, the graph's edges whose root moves faster than this (m/s) are left out.
    pub max_speed: Option<f64>,
    /// The start pose: a node of the graph; `None` picks the graph's default (running
    /// forward at a moderate speed).
    pub start_node: Option<u32>,
    /// Rectangles no path may enter, in the agent's frame.
    pub obstacles: Vec<Obstacle>,
}

impl Default for BuildParams {
    fn default() -> Self {
        BuildParams {
            method: Method::Search,
            grid: Grid::new(20.0, 0.5),
            iterations: 20_000,
            depth: 150,
            seed: 1,
            search: SearchParams::default(),
            max_speed: None,
            start_node: None,
            obstacles: Vec::new(),
        }
    }
}

/// Random walks `search` adds near the start, and how long they are (frames).
///
/// Search merges walks that end close together, and near the start, where few walks
/// reach a cell and the first to arrive may only graze it, a merge can lose a cell
/// outright; random walks are dense there (their first seconds are where they all
/// pass). So the map is the cheaper, cell by cell, of search and these walks: both are
/// real walks whose paths replay exactly. The walks are the same whatever the horizon
/// (cut to it afterwards), so a longer horizon still never makes a cell dearer.
/// Measured in BENCHMARKS.md ("search against 200,000 walks").
const NEAR_WALKS: u64 = 50_000;
const NEAR_WALK_FRAMES: u32 = 60;

/// Takes into `costs` and `paths` every cell [`NEAR_WALKS`] random walks reach sooner.
fn near_walks(
    prepared: &Prepared,
    grid: &Grid,
    start: u32,
    params: &BuildParams,
    costs: &mut [Option<u32>],
    paths: &mut [Vec<u32>],
) {
    let input = BuildInput {
        grid: *grid,
        obstacles: Vec::new(),
        start,
    };
    let walks = mc::build(
        &input,
        prepared,
        NEAR_WALKS,
        NEAR_WALK_FRAMES,
        params.seed,
        &[],
        &mut |_| {},
    );
    for (c, (cost, path)) in walks.costs.into_iter().zip(walks.paths).enumerate() {
        if let Some(f) = cost.filter(|&f| f <= params.depth) {
            if costs[c].is_none_or(|v| f < v) {
                costs[c] = Some(f);
                paths[c] = path;
            }
        }
    }
}

/// The Monte Carlo costs of a few fixed cells after a number of walks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConvergencePoint {
    pub(crate) iterations: u64,
    pub(crate) costs: Vec<Option<u32>>,
}

/// Points (agent frame, metres) whose Monte Carlo cost is recorded against iterations.
pub const WATCHED_POINTS: [(f64, f64); 5] =
    [(3.0, 0.0), (6.0, 0.0), (0.0, 3.0), (-3.0, 0.0), (5.0, 5.0)];

pub(crate) struct BuildInput {
    pub grid: Grid,
    pub obstacles: Vec<Obstacle>,
    pub start: u32,
}

/// A cost map in the agent's frame: the agent at (0, 0) facing +x, so +z is on its right
/// (y up; see [`Grid`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CostMap {
    /// How it was built.
    pub method: Method,
    /// The behaviour whose motion graph it is of.
    pub behaviour: String,
    /// The cells it covers.
    pub grid: Grid,
    /// Frames per second of the motion data: costs are in these frames.
    pub fps: f64,
    /// The behaviour's top root speed over the graph's frames, m/s.
    pub top_speed_m_s: f64,
    /// The graph node every path starts from (the start state).
    pub start_node: u32,
    /// The horizon: no path longer than this many frames was followed, so an
    /// unreachable cell costs at least this much.
    pub depth: u32,
    /// The obstacles it was built around, in the agent's frame.
    pub obstacles: Vec<Obstacle>,
    /// Frames to reach each cell, row-major (row i along z, column j along x); `None`
    /// where no path reaches it.
    pub costs: Vec<Option<u32>>,
    /// Per cell, the motion-graph edges of the cheapest path found (empty for grassfire),
    /// so an agent can play it back.
    pub paths: Vec<Vec<u32>>,
    /// Monte Carlo only: the costs of [`WATCHED_POINTS`] against iterations.
    pub convergence: Vec<ConvergencePoint>,
}

impl CostMap {
    /// Whether a map read from elsewhere (a cache file) fits `graph` as a built one does:
    /// a cost and a path per cell, its start a node, its paths' edges the graph's.
    pub(crate) fn check(&self, graph: &MotionGraph) -> Result<(), String> {
        let cells = self.grid.n.saturating_mul(self.grid.n);
        if self.grid.n == 0 || self.costs.len() != cells || self.paths.len() != cells {
            return Err(format!(
                "{} costs and {} paths on a grid of {} cells a side",
                self.costs.len(),
                self.paths.len(),
                self.grid.n
            ));
        }
        if !(self.grid.cell_m > 0.0 && self.grid.cell_m.is_finite()) {
            return Err(format!("cells of {} m", self.grid.cell_m));
        }
        if self.start_node as usize >= graph.node_count() {
            return Err(format!(
                "start node {} of {}",
                self.start_node,
                graph.node_count()
            ));
        }
        if self
            .paths
            .iter()
            .flatten()
            .any(|&e| e as usize >= graph.edges.len())
        {
            return Err("a path along an edge the graph does not have".into());
        }
        Ok(())
    }

    /// Builds a map of `graph` with `params`. `progress` is told how many walks are done
    /// (Monte Carlo) now and then, so a caller can show a progress bar.
    pub fn build(
        graph: &MotionGraph,
        params: &BuildParams,
        progress: &mut dyn FnMut(u64),
    ) -> CostMap {
        let start = params.start_node.unwrap_or_else(|| graph.default_start());
        Self::build_from(graph, params, &[start], progress)
            .pop()
            .expect("one map per start")
    }

    /// The maps of `graph` from each of `starts` (nodes), in order, with `params` (whose
    /// `start_node` is ignored). `search` without obstacles finds them all in one
    /// backward pass; the other methods build one after another.
    pub fn build_from(
        graph: &MotionGraph,
        params: &BuildParams,
        starts: &[u32],
        progress: &mut dyn FnMut(u64),
    ) -> Vec<CostMap> {
        let enabled = graph.enabled(&Constraints {
            max_speed: params.max_speed,
        });
        let prepared = Prepared::new(graph, &enabled);
        let grid = &params.grid;
        let map = |start: u32, costs, paths, convergence| CostMap {
            method: params.method,
            behaviour: graph.behaviour.clone(),
            grid: *grid,
            fps: graph.fps,
            top_speed_m_s: graph.stats.top_speed_m_s,
            start_node: start,
            depth: params.depth,
            obstacles: params.obstacles.clone(),
            costs,
            paths,
            convergence,
        };
        if params.method == Method::Search && params.obstacles.is_empty() {
            let found = backward::build(grid, &prepared, graph.node_count(), params.depth, starts);
            // The starts' walks are independent (each seeded the same), so they run in
            // parallel; the result does not depend on the threads.
            return starts
                .par_iter()
                .zip(found)
                .map(|(&start, mut r)| {
                    near_walks(&prepared, grid, start, params, &mut r.costs, &mut r.paths);
                    map(start, r.costs, r.paths, Vec::new())
                })
                .collect();
        }
        let mut maps = Vec::with_capacity(starts.len());
        for &start in starts {
            let input = BuildInput {
                grid: params.grid,
                obstacles: params.obstacles.clone(),
                start,
            };
            let (costs, paths, convergence) = match params.method {
                Method::Mc => {
                    let watch: Vec<usize> = WATCHED_POINTS
                        .iter()
                        .filter_map(|&(x, z)| grid.cell_of(DVec2::new(x, z)))
                        .collect();
                    let r = mc::build(
                        &input,
                        &prepared,
                        params.iterations,
                        params.depth,
                        params.seed,
                        &watch,
                        progress,
                    );
                    (r.costs, r.paths, r.convergence)
                }
                Method::Search => {
                    let r = search::build(
                        &input,
                        &prepared,
                        graph.node_count(),
                        params.depth,
                        params.search,
                    );
                    let paths = (0..grid.cells()).map(|c| r.path(c)).collect();
                    (r.costs, paths, Vec::new())
                }
                Method::Grassfire => {
                    let costs = grassfire::build(
                        grid,
                        &params.obstacles,
                        graph.stats.top_speed_m_s,
                        graph.fps,
                    );
                    (costs, vec![Vec::new(); grid.cells()], Vec::new())
                }
            };
            maps.push(map(start, costs, paths, convergence));
        }
        maps
    }

    /// Cost in frames of the cell holding `local` (agent frame).
    pub fn cost(&self, local: DVec2) -> Option<u32> {
        self.costs[self.grid.cell_of(local)?]
    }

    /// The cost for an agent standing at `pose` to reach the world point `world`: the
    /// same map, rotated and translated onto the agent.
    pub fn cost_for(&self, pose: &AgentPose, world: DVec2) -> Option<u32> {
        self.cost(pose.to_local(world))
    }

    /// [`CostMap::cost_for`] in a frame prepared once with [`AgentPose::frame`].
    #[inline]
    pub fn cost_in(&self, frame: &LocalFrame, world: DVec2) -> Option<u32> {
        self.cost(frame.to_local(world))
    }

    /// Costs as rows (row i along z), as `--json` prints them.
    pub fn rows(&self) -> Vec<&[Option<u32>]> {
        self.costs.chunks(self.grid.n).collect()
    }

    /// Bytes the map holds: costs plus stored paths.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.costs.as_slice())
            + self
                .paths
                .iter()
                .map(|p| std::mem::size_of_val(p.as_slice()) + std::mem::size_of::<Vec<u32>>())
                .sum::<usize>()
    }

    /// Cells some path reaches.
    pub fn reachable_cells(&self) -> usize {
        self.costs.iter().filter(|c| c.is_some()).count()
    }
}
#[cfg(test)]
mod oracles;
