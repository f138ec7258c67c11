//! One behaviour's capability: a [`Mover`] (its motion graph and a cost map per start
//! state) and a [`Reach`] (those maps embedded at one agent's pose and state), which
//! tell how soon the agent can be anywhere on the court and which way to go.

use super::{Stage, HORIZON_FRAMES};
use crate::basketball::court::Court;
use crate::basketball::footprint::Footprint;
use crate::costmap::{
    cache, root_speed, start_states, symmetrise, AgentPose, BuildParams, CostMap, LocalFrame,
    Start, StartState, STANDING_MIRRORED,
};
use crate::motion::{
    quickest_turn_around, GraphError, Jump, MotionGraph, MotionLibrary, RootStep, TurnAround,
    Walker, AUTO_WINDOWS,
};
use glam::DVec2;
use std::sync::OnceLock;

/// One behaviour an agent moves with: its motion graph and a cost map per start state.
#[derive(Debug, Clone)]
pub struct Mover {
    /// The behaviour's name (`dribble`, `run`, `defense`), as frames label a player.
    pub behaviour: &'static str,
    /// The behaviour's motion graph, built from its clips: every move is a walk on it.
    pub graph: MotionGraph,
    /// One map per start state ([`start_states`]): standing first, then each moving state.
    pub states: Vec<StateMap>,
    /// Which of `states` is the most common running state: the map shown to people.
    moving: usize,
    /// Which of `states` is the mirror image of the stance (`states[0]`), if the capture
    /// is mirrored: a standing agent gets the better of the two, cell by cell.
    stance_twin: Option<usize>,
    /// Per graph node, the walk to the start state a body playing it reaches soonest.
    leads: Vec<Lead>,
    /// Per graph edge, how it is played: one root step (with its turn as cos, sin) per
    /// data frame, and how many frames. Worked out once, since paths are walked for
    /// every move an agent considers.
    edge_frames: Vec<(RootStep, DVec2, usize)>,
    /// The quickest turn around from the stance ([`Mover::turn`]): cached with the maps,
    /// or measured when first asked for.
    turn: OnceLock<Option<TurnAround>>,
    /// The jump shots cut from the behaviour's clips (empty if not cached).
    pub jumps: Vec<cache::ClipJump>,
}

/// A start state's map, with the ground each cell's stored path covers.
#[derive(Debug, Clone)]
pub struct StateMap {
    /// The start state: its name and the graph node the map starts from.
    pub state: StartState,
    /// The map from that state, in the agent's frame.
    pub map: CostMap,
    /// Per map cell: checking a move against the court costs a few hull vertices instead
    /// of a walk of every frame. Each is made the first time a move to its cell is
    /// checked (a pure function of the graph and the map, so when changes nothing): a
    /// start pays for none of the thousands no decision asks about yet.
    footprints: Vec<OnceLock<Footprint>>,
}

/// How a body playing a node gets to a start state: the edges, their frames, and where
/// the body ends (in the frame it had at the node).
#[derive(Debug, Clone)]
struct Lead {
    state: usize,
    edges: Vec<u32>,
    frames: u32,
    end: Walker,
}

/// How a body is moving when it plans a move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Motion {
    /// Playing this node of the mover's own graph: the move goes on from it.
    Node(u32),
    /// Moving at this root speed (m/s) with another behaviour: the move starts from the
    /// start state nearest that speed.
    Speed(f64),
    /// Not yet moving: the move starts standing.
    Still,
}

/// One frame of a planned move: where the root is and which way it faces, and the
/// motion-graph node playing (so a client can draw the pose).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stride {
    pub(crate) at: Walker,
    pub(crate) node: u32,
    /// Whether the body got to `node` by a transition (a cut into another clip), which
    /// playback blends over.
    pub(crate) cut: bool,
}

impl Mover {
    pub(crate) fn new(
        behaviour: &'static str,
        graph: MotionGraph,
        maps: Vec<(StartState, CostMap)>,
    ) -> Mover {
        assert!(!maps.is_empty(), "a mover needs a map");
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
        let leads = leads(
            &graph,
            &maps.iter().map(|(s, _)| s.node).collect::<Vec<_>>(),
        );
        let moving_node = Start::Moving.node(&graph);
        let moving = maps
            .iter()
            .position(|(s, _)| Some(s.node) == moving_node)
            .unwrap_or(0);
        let stance_twin = maps
            .iter()
            .position(|(s, _)| s.name == crate::costmap::STANDING_MIRRORED);
        let mut mover = Mover {
            behaviour,
            graph,
            states: Vec::new(),
            moving,
            stance_twin,
            leads,
            edge_frames,
            turn: OnceLock::new(),
            jumps: Vec::new(),
        };
        mover.states = maps
            .into_iter()
            .map(|(state, map)| StateMap {
                state,
                footprints: (0..map.costs.len()).map(|_| OnceLock::new()).collect(),
                map,
            })
            .collect();
        mover
    }

    /// The mover of `behaviour` in `library`: its graph (the automatic choice) and a
    /// `search` map per start state, shipped or read from the cache if `reuse` allows
    /// and either holds them, telling `progress` what it is doing.
    pub fn build(
        library: &MotionLibrary,
        behaviour: &'static str,
        reuse: cache::Reuse<'_>,
        progress: &mut dyn FnMut(Stage),
    ) -> Result<Mover, GraphError> {
        let (
            cache::Cached {
                graph,
                mut maps,
                turn,
                jumps,
            },
            origin,
        ) = cache::build_or_load(
            reuse,
            library.source.fingerprint(),
            behaviour,
            &Self::inputs(),
            || Self::build_parts(library, behaviour, progress),
        )?;
        let states = start_states(&graph);
        progress(Stage::Ready { behaviour, origin });
        // The stance and its mirror image reach left and right alike (maps[0] is the
        // stance; its twin, if any, comes next).
        if let Some(t) = states.iter().position(|s| s.name == STANDING_MIRRORED) {
            let (stance, rest) = maps.split_at_mut(1);
            symmetrise(&graph, &mut stance[0], &mut rest[t - 1]);
        }
        let mut mover = Mover::new(behaviour, graph, states.into_iter().zip(maps).collect());
        mover.turn = OnceLock::from(turn);
        mover.jumps = jumps;
        Ok(mover)
    }

    /// The quickest turn around from the stance or its mirror image
    /// ([`quickest_turn_around`]).
    pub fn turn(&self) -> Option<&TurnAround> {
        self.turn
            .get_or_init(|| {
                let stances = std::iter::once(&self.states[0].map)
                    .chain(self.stance_twin.map(|t| &self.states[t].map))
                    .map(|m| m.start_node);
                quickest_turn_around(&self.graph, stances)
            })
            .as_ref()
    }

    /// What decides a behaviour's graph and maps besides the motion and the code: the
    /// windows the automatic graph choice tries and the maps' build parameters. The
    /// cache and the shipped files are keyed by them.
    fn inputs() -> (&'static [usize], BuildParams) {
        let params = BuildParams {
            depth: HORIZON_FRAMES,
            ..BuildParams::default()
        };
        (&AUTO_WINDOWS, params)
    }

    /// The name of the file holding the graph and maps of `behaviour` in `library`,
    /// cached or shipped.
    pub fn file_name(library: &MotionLibrary, behaviour: &str) -> String {
        cache::file_name(library.source.fingerprint(), behaviour, &Self::inputs())
    }

    /// Builds the graph of `behaviour` in `library` and its maps, as they are cached
    /// (before the stance's maps are made symmetric).
    pub fn build_parts(
        library: &MotionLibrary,
        behaviour: &'static str,
        progress: &mut dyn FnMut(Stage),
    ) -> Result<cache::Cached, GraphError> {
        let (windows, params) = Self::inputs();
        let owned = library.ground_clips(behaviour);
        let clips: Vec<_> = owned.iter().collect();
        progress(Stage::Graph {
            behaviour,
            frames: clips.iter().map(|c| c.frame_count()).sum(),
        });
        let graph = MotionGraph::build_auto(behaviour, &clips, windows)?;
        let states = start_states(&graph);
        let starts: Vec<u32> = states.iter().map(|s| s.node).collect();
        progress(Stage::Map { behaviour });
        let maps = CostMap::build_from(&graph, &params, &starts, &mut |_| {});
        // The stance and its mirror image, as `Mover::turn` measures them.
        let stances = states
            .iter()
            .zip(&maps)
            .enumerate()
            .filter(|(i, (s, _))| *i == 0 || s.name == STANDING_MIRRORED)
            .map(|(_, (_, m))| m.start_node);
        let turn = quickest_turn_around(&graph, stances);
        let jumps = library
            .clips_of(behaviour)
            .filter_map(|c| {
                Jump::find(c).map(|jump| cache::ClipJump {
                    clip: c.name.clone(),
                    jump,
                })
            })
            .collect();
        Ok(cache::Cached {
            graph,
            maps,
            turn,
            jumps,
        })
    }

    /// The ground the stored path to `cell` of start state `state`'s map covers, from
    /// the origin.
    fn footprint(&self, state: usize, cell: usize) -> &Footprint {
        let s = &self.states[state];
        s.footprints[cell].get_or_init(|| {
            Footprint::of(
                self.path(&s.map, Walker::START, cell)
                    .map(|stride| stride.at.position),
            )
        })
    }

    /// The map of the most common running state: the one shown to people.
    pub fn map(&self) -> &CostMap {
        &self.states[self.moving].map
    }

    /// The map's horizon: what "beyond the map" is at least, in seconds.
    pub fn horizon_s(&self) -> f64 {
        let map = self.map();
        f64::from(map.depth) / map.fps
    }

    /// The behaviour's top speed over the frames its graph kept, m/s.
    pub fn top_speed_m_s(&self) -> f64 {
        self.graph.stats.top_speed_m_s
    }

    /// What an agent at `pose`, moving as `motion`, can reach: the map of the start state
    /// its walk on the graph gets to soonest, placed where that walk ends.
    pub fn reach(&self, pose: &AgentPose, motion: Motion) -> Reach<'_> {
        let (state, lead) = match motion {
            Motion::Node(n) => match self.leads.get(n as usize) {
                Some(lead) => (lead.state, Some(lead)),
                None => (0, None),
            },
            Motion::Speed(v) => {
                let off =
                    |s: &StateMap| (root_speed(&self.graph.nodes[s.state.node as usize]) - v).abs();
                let nearest = (0..self.states.len())
                    .min_by(|&a, &b| off(&self.states[a]).total_cmp(&off(&self.states[b])))
                    .unwrap_or(0);
                (nearest, None)
            }
            Motion::Still => (0, None),
        };
        // A standing body may set off on either foot.
        let twin = match motion {
            Motion::Still => self.stance_twin,
            _ => None,
        };
        let start = Walker {
            position: pose.position,
            facing: DVec2::from_angle(pose.heading),
        };
        let at = match lead {
            Some(l) => Walker {
                position: start.position + l.end.position.rotate(start.facing),
                facing: start.facing.rotate(l.end.facing),
            },
            None => start,
        };
        let frame = AgentPose {
            position: at.position,
            heading: at.heading(),
        }
        .frame();
        Reach {
            mover: self,
            state,
            twin,
            lead,
            start,
            node: match motion {
                Motion::Node(n) => n,
                _ => self.states[state].state.node,
            },
            frame,
            origin: at,
        }
    }

    /// The strides of the stored path to `cell` of `map`, played from `at`, without
    /// collecting them (the first is `at` itself, at the map's start node).
    fn path<'a>(
        &'a self,
        map: &'a CostMap,
        at: Walker,
        cell: usize,
    ) -> impl Iterator<Item = Stride> + 'a {
        let start = Stride {
            at,
            node: map.start_node,
            cut: false,
        };
        std::iter::once(start).chain(self.play(&map.paths[cell], at))
    }

    /// The strides of `edges` played from `at` (not including `at`).
    fn play<'a>(&'a self, edges: &'a [u32], at: Walker) -> impl Iterator<Item = Stride> + 'a {
        let steps = edges.iter().flat_map(move |&id| {
            let (step, turn, k) = self.edge_frames[id as usize];
            let e = &self.graph.edges[id as usize];
            // A transition is a cut on its first frame only.
            (0..k).map(move |i| (step, turn, e.to, e.transition && i == 0))
        });
        steps.scan(at, |at, (step, turn, node, cut)| {
            *at = at.after(&step, turn);
            Some(Stride { at: *at, node, cut })
        })
    }
}

/// What one agent can reach from where it is and how it is moving: the walk to its start
/// state (the lead; none when it is not moving on this graph), then that state's map.
/// Every move it plans is the lead followed by a stored path, one continuous walk on the
/// graph from the node it is playing.
pub struct Reach<'a> {
    mover: &'a Mover,
    state: usize,
    /// For a standing agent, the stance's mirror image: each cell is reached by whichever
    /// of the two stances gets there sooner.
    twin: Option<usize>,
    lead: Option<&'a Lead>,
    /// The agent as it is, and the node it plays.
    start: Walker,
    node: u32,
    /// Where the lead leaves it: the map's origin, and the frame of it look-ups use.
    origin: Walker,
    frame: LocalFrame,
}

impl Reach<'_> {
    fn map(&self) -> &CostMap {
        &self.mover.states[self.state].map
    }

    /// The state whose map reaches `cell` soonest: the agent's, or for a standing agent
    /// the stance's mirror image when that is quicker.
    #[inline]
    fn state_for(&self, cell: usize) -> usize {
        let cost = |s: usize| self.mover.states[s].map.costs[cell].unwrap_or(u32::MAX);
        match self.twin {
            Some(t) if cost(t) < cost(self.state) => t,
            _ => self.state,
        }
    }

    /// Frames to `cell` by its map (the lead not included), if either stance reaches it.
    #[inline]
    fn frames_to(&self, cell: usize) -> Option<u32> {
        self.mover.states[self.state_for(cell)].map.costs[cell]
    }

    fn lead_frames(&self) -> u32 {
        self.lead.map_or(0, |l| l.frames)
    }

    /// The name of the start state the map is of.
    pub fn state(&self) -> &str {
        &self.mover.states[self.state].state.name
    }

    /// Where the agent stands now.
    pub fn position(&self) -> DVec2 {
        self.start.position
    }

    /// Seconds to reach the world point `world`: the lead, then the map; `None` beyond
    /// the map (farther than its horizon or its extent).
    #[inline]
    pub fn seconds(&self, world: DVec2) -> Option<f64> {
        self.seconds_local(self.frame.to_local(world))
    }

    /// [`Reach::seconds`] of a point already in the map's frame ([`Reach::frame`]).
    #[inline]
    pub fn seconds_local(&self, local: DVec2) -> Option<f64> {
        let map = self.map();
        let cell = map.grid.cell_of(local)?;
        self.frames_to(cell)
            .map(|frames| f64::from(frames + self.lead_frames()) / map.fps)
    }

    /// The frame the map is looked up in: where the lead leaves the agent.
    pub fn frame(&self) -> LocalFrame {
        self.frame
    }

    /// The map's horizon, s: what "beyond the map" is at least.
    pub fn horizon_s(&self) -> f64 {
        self.mover.horizon_s()
    }

    /// The map cell holding `world`, if the map reaches it.
    pub fn cell(&self, world: DVec2) -> Option<usize> {
        let cell = self.map().grid.cell_of(self.frame.to_local(world))?;
        self.frames_to(cell).map(|_| cell)
    }

    /// The move to map cell `cell`: one stride per data frame, starting with the agent as
    /// it is, through the lead, then the stored path.
    pub fn strides(&self, cell: usize) -> Vec<Stride> {
        let state = &self.mover.states[self.state_for(cell)];
        let first = Stride {
            at: self.start,
            // A standing agent sets off in the stance the path starts from.
            node: if self.lead.is_none() && self.twin.is_some() {
                state.state.node
            } else {
                self.node
            },
            cut: false,
        };
        let lead = self.lead.map_or(&[][..], |l| &l.edges[..]);
        std::iter::once(first)
            .chain(self.mover.play(lead, self.start))
            .chain(self.mover.play(&state.map.paths[cell], self.origin))
            .collect()
    }

    /// Whether the move to `cell` keeps the body on `court`, or at most `margin_m` beyond
    /// its lines, at every frame (and between frames, where it moves in straight lines).
    pub fn on_court(&self, cell: usize, court: &Court, margin_m: f64) -> bool {
        self.lead_on_court(court, margin_m) && self.path_on_court(cell, court, margin_m)
    }

    /// Whether the lead keeps the body on `court` (within `margin_m` of its lines).
    fn lead_on_court(&self, court: &Court, margin_m: f64) -> bool {
        self.lead.is_none_or(|l| {
            self.mover
                .play(&l.edges, self.start)
                .all(|s| court.inside_by(s.at.position) + margin_m >= 0.0)
        })
    }

    /// Whether the stored path to `cell`, after the lead, keeps the body on `court`.
    fn path_on_court(&self, cell: usize, court: &Court, margin_m: f64) -> bool {
        self.mover
            .footprint(self.state_for(cell), cell)
            .within(&self.frame, court, margin_m)
    }

    /// Of the cells this agent reaches along a move that stays on `court` (within
    /// `margin_m` of its lines) and ends on it at least a cell nearer `goal`, the one that
    /// gets it there soonest: the frames to the cell plus the rest of the way at the
    /// behaviour's top speed. This is the "cheapest heading" toward a goal the map itself
    /// may not reach, or reaches only by a path that leaves the court; `None` if no such
    /// move gets nearer.
    ///
    /// A move must make progress: the rest of the way is counted at top speed, which no
    /// real move beats, so the cell the agent stands in (no frames, the whole way at top
    /// speed) would otherwise always win and the agent would never set off.
    pub fn toward(&self, goal: DVec2, court: &Court, margin_m: f64) -> Option<usize> {
        let map = self.map();
        let grid = &map.grid;
        let speed = self.mover.top_speed_m_s().max(0.1);
        let nearer_than = self.start.position.distance(goal) - grid.cell_m;
        // Every move starts with the lead: checked once, not once per cell.
        if !self.lead_on_court(court, margin_m) {
            return None;
        }
        let mut best: Option<(f64, usize)> = None;
        for cell in 0..map.costs.len() {
            let Some(frames) = self.frames_to(cell) else {
                continue;
            };
            let world = self.frame.to_world(grid.centre(cell));
            let remaining = world.distance(goal);
            let eta = f64::from(frames + self.lead_frames()) / map.fps + remaining / speed;
            // The path check costs most: only a cell that would win is checked.
            if best.is_some_and(|(b, _)| eta >= b)
                || remaining > nearer_than
                || !court.contains(world)
                || !self.path_on_court(cell, court, margin_m)
            {
                continue;
            }
            best = Some((eta, cell));
        }
        best.map(|(_, cell)| cell)
    }
}

/// Per node of `graph`, the walk to the nearest of `starts` (in frames), found by one
/// search backward from all of them at once. Every node has one: the graph is strongly
/// connected.
fn leads(graph: &MotionGraph, starts: &[u32]) -> Vec<Lead> {
    let n = graph.node_count();
    let mut into: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (i, e) in graph.edges.iter().enumerate() {
        into[e.to as usize].push(i);
    }
    // (frames to a start, the state reached, the first edge of the way)
    let mut best: Vec<Option<(u32, usize, Option<usize>)>> = vec![None; n];
    let mut queue = std::collections::BinaryHeap::new();
    for (state, &s) in starts.iter().enumerate() {
        if best[s as usize].is_none() {
            best[s as usize] = Some((0, state, None));
            queue.push(std::cmp::Reverse((0u32, s)));
        }
    }
    while let Some(std::cmp::Reverse((f, node))) = queue.pop() {
        let Some((known, state, _)) = best[node as usize] else {
            continue;
        };
        if known != f {
            continue;
        }
        for &i in &into[node as usize] {
            let e = &graph.edges[i];
            let g = f + e.frames;
            if best[e.from as usize].is_none_or(|(b, _, _)| g < b) {
                best[e.from as usize] = Some((g, state, Some(i)));
                queue.push(std::cmp::Reverse((g, e.from)));
            }
        }
    }
    (0..n)
        .map(|node| {
            let (frames, state, _) = best[node].expect("strongly connected");
            let mut edges = Vec::new();
            let mut at = Walker::START;
            let mut v = node;
            while let Some((_, _, Some(i))) = best[v] {
                let e = &graph.edges[i];
                at = at.step(&e.step);
                edges.push(i as u32);
                v = e.to as usize;
            }
            Lead {
                state,
                edges,
                frames,
                end: at,
            }
        })
        .collect()
}
