//! The motion graph of one behaviour: every frame a node, the clips' own frame-to-frame
//! steps plus the transitions found between similar frames as edges, pruned to its
//! largest strongly connected component so that no walk gets stuck.

use super::cuts;
use super::step::{Node, RootStep};
use super::transitions::{self, Transition};
use super::Clip;
use glam::DVec3;
use petgraph::algo::tarjan_scc;
use petgraph::graph::{DiGraph, NodeIndex};
use serde::{Deserialize, Serialize};
use std::ops::ControlFlow;
use thiserror::Error;

/// How a motion graph is built.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GraphParams {
    /// Frames compared on each side of a transition (10 at 30 fps: Kovar's ⅓ s), which
    /// is also the blend length at playback.
    pub window: usize,
    /// Largest RMS joint distance (metres, after alignment) a transition may have: lower
    /// gives smoother cuts, higher a better connected graph.
    pub threshold_m: f64,
}

/// Thresholds (RMS metres) [`MotionGraph::build_auto`] tries, smoothest first.
pub const AUTO_THRESHOLDS_M: [f64; 11] = [
    0.06, 0.08, 0.10, 0.12, 0.15, 0.18, 0.22, 0.26, 0.32, 0.40, 0.50,
];

/// Windows (frames) [`MotionGraph::build_auto`] tries, longest first: Kovar's ⅓ s down
/// to ⅕ s. The CMU running and footwork clips last 1.1–2.2 s, and a cut needs a whole
/// window of its clip after it, so a ⅓ s window leaves little of a short clip that a
/// transition can reach; a shorter window compares (and blends) less.
pub const AUTO_WINDOWS: [usize; 3] = [10, 8, 6];

impl Default for GraphParams {
    fn default() -> Self {
        GraphParams {
            window: 10,
            threshold_m: 0.12,
        }
    }
}

/// Why a motion graph could not be built.
#[derive(Debug, Error)]
pub enum GraphError {
    /// No clip shows the behaviour asked for.
    #[error("no clips of behaviour \"{behaviour}\"")]
    NoClips {
        /// The behaviour asked for.
        behaviour: String,
    },
    /// Every clip is shorter than the frames a transition compares.
    #[error("behaviour \"{behaviour}\": clips are too short for a {window}-frame window")]
    TooShort {
        /// The behaviour asked for.
        behaviour: String,
        /// The window, frames.
        window: usize,
    },
}

/// An edge of the graph: play from node `from` to node `to`, moving the root by `step`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Edge {
    /// The node the edge leaves.
    pub from: u32,
    /// The node the edge enters.
    pub to: u32,
    /// The root's motion over the edge, in the body's frame at `from`.
    pub(crate) step: RootStep,
    /// Frames the edge takes to play; 1 for the edges of a graph built from clips.
    pub frames: u32,
    /// A cut between (or within) clips rather than the clip's own next frame.
    pub transition: bool,
}

/// Counts a user checks a graph by.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GraphStats {
    /// Frames of all the clips: the nodes before pruning.
    pub frames: usize,
    /// Clips the graph was built from.
    pub clips: usize,
    /// Transitions found under the threshold.
    pub transitions_before_pruning: usize,
    /// Transitions left in the largest strongly connected component.
    pub transitions_after_pruning: usize,
    /// Nodes in the largest strongly connected component: the nodes kept.
    pub largest_scc: usize,
    /// Fastest root speed over the frames the graph kept (over ⅓ s, so the hips' sway
    /// within a stride does not count as speed), m/s: a walk on the graph can never be
    /// faster, whatever the clips it pruned did.
    pub top_speed_m_s: f64,
    /// The roughest kept transition and the 95th percentile of them: RMS joint distance
    /// after alignment, m (0 when no transition is kept).
    pub transition_worst_m: f64,
    /// See `transition_worst_m`: the 95th percentile, m.
    pub transition_p95_m: f64,
    /// How far the blends of the kept transitions drag a planted foot, m: the 95th
    /// percentile over transitions (see `cuts`).
    pub foot_slide_p95_m: f64,
    /// The root's acceleration across the kept transitions, m/s²: the 95th percentile.
    pub root_accel_p95_m_s2: f64,
    /// The capture's own root accelerations over the same span, m/s²: the 95th
    /// percentile over every span of the clips, what a cut is held against.
    pub capture_root_accel_p95_m_s2: f64,
}

/// How much of one clip the graph kept, and how it is joined to the rest.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClipCoverage {
    /// The clip's name.
    pub name: String,
    /// Frames the clip offered the graph.
    pub frames: usize,
    /// Of those, frames kept in the largest strongly connected component.
    pub kept: usize,
    /// Kept transitions into and out of the clip's frames (from any clip, itself included).
    pub transitions_in: usize,
    /// See `transitions_in`: the ones leaving the clip.
    pub transitions_out: usize,
    /// The smallest distance of any transition (found at the loosest threshold tried)
    /// between this clip and another, m: what a threshold must allow to join it at all.
    pub best_transition_m: Option<f64>,
}

impl ClipCoverage {
    /// At least half its frames kept: the bar [`MotionGraph::build_auto`] sets.
    pub fn joined(&self) -> bool {
        2 * self.kept >= self.frames
    }
}

/// Constraints that disable edges before a cost map is built.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Constraints {
    /// Disable every edge whose root moves faster than this (m/s).
    pub max_speed: Option<f64>,
}

/// The motion graph of one behaviour (Kovar et al. 2002): every kept frame a node, the
/// clips' own next frames and the transitions between similar frames as edges, pruned to
/// the largest strongly connected component.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MotionGraph {
    /// The behaviour its clips show, e.g. `run`.
    pub behaviour: String,
    /// Frames per second: each edge plays in `frames / fps` s.
    pub fps: f64,
    /// The window and threshold it was built with.
    pub params: GraphParams,
    /// Its clips' names; [`Node::clip`] indexes this.
    pub clip_names: Vec<String>,
    /// Per clip, in the order of `clip_names`: frames kept and transitions.
    pub coverage: Vec<ClipCoverage>,
    /// Kept nodes; node ids are indices here.
    pub nodes: Vec<Node>,
    /// Edges sorted by `from`, then `to`.
    pub edges: Vec<Edge>,
    /// `edges[out_start[n]..out_start[n + 1]]` leave node n.
    out_start: Vec<usize>,
    /// Each node's joint positions in its own character frame (root on the ground at the
    /// origin, facing +x), for playback.
    poses: Vec<DVec3>,
    joints: usize,
    /// The skeleton the poses are of: joint names, in the order of a pose's positions.
    pub joint_names: Vec<String>,
    /// Each joint's parent (`None` for the root), for drawing bones.
    pub joint_parents: Vec<Option<usize>>,
    /// The counts a user checks the graph by.
    pub stats: GraphStats,
}

impl MotionGraph {
    /// Builds the graph whose cuts are as smooth as the capture, with as many of them as
    /// that allows: of the windows and thresholds tried ([`AUTO_THRESHOLDS_M`] ×
    /// `windows`), those at which *every* clip keeps at least half its frames in the
    /// largest strongly connected component, the loosest whose transitions change the
    /// root's velocity no faster than the clips themselves do (95th percentiles of
    /// [`GraphStats::root_accel_p95_m_s2`] against
    /// [`GraphStats::capture_root_accel_p95_m_s2`]).
    ///
    /// A looser threshold adds transitions, so walks get more places sooner (what a body
    /// can do, the cost maps, improves) and cuts get rougher; `fieldhouse motion-graph
    /// --sweep` shows both for every candidate. Joining every clip comes first, since a
    /// bar on the total would let a behaviour drop its rarest motion (the fastest runs,
    /// the sideways shuffle), which matters most. If no graph that joins every clip has
    /// cuts as smooth as the capture, the smoothest that joins them all is built; if none
    /// joins them all, the one that joins the most clips (then keeps the most frames),
    /// and [`MotionGraph::coverage`] says which clip is left out and its best transition.
    pub fn build_auto(
        behaviour: &str,
        clips: &[&Clip],
        windows: &[usize],
    ) -> Result<MotionGraph, GraphError> {
        let mut most_joined: Option<(usize, MotionGraph)> = None;
        let mut smoothest_joining_all = None;
        let mut loosest_smooth = None;
        Self::each_candidate(behaviour, clips, windows, |graph| {
            let joined = graph.coverage.iter().filter(|c| c.joined()).count();
            if joined == clips.len() {
                let s = &graph.stats;
                if s.root_accel_p95_m_s2 <= s.capture_root_accel_p95_m_s2 {
                    loosest_smooth = Some(graph);
                } else if smoothest_joining_all.is_none() {
                    smoothest_joining_all = Some(graph);
                }
                return ControlFlow::Continue(());
            }
            let better = most_joined
                .as_ref()
                .is_none_or(|(j, b)| (joined, graph.stats.largest_scc) > (*j, b.stats.largest_scc));
            if better {
                most_joined = Some((joined, graph));
            }
            ControlFlow::Continue(())
        })?;
        loosest_smooth
            .or(smoothest_joining_all)
            .or(most_joined.map(|(_, g)| g))
            .ok_or(GraphError::TooShort {
                behaviour: behaviour.to_string(),
                window: windows.iter().copied().max().unwrap_or(0),
            })
    }

    /// Every graph [`MotionGraph::build_auto`] considers, smoothest first (each threshold
    /// of [`AUTO_THRESHOLDS_M`], and at each every one of `windows` in the order given),
    /// handed to `visit` until it breaks. The transitions are found once for all of them.
    pub fn each_candidate(
        behaviour: &str,
        clips: &[&Clip],
        windows: &[usize],
        mut visit: impl FnMut(MotionGraph) -> ControlFlow<()>,
    ) -> Result<(), GraphError> {
        require_clips(behaviour, clips)?;
        let loosest = AUTO_THRESHOLDS_M[AUTO_THRESHOLDS_M.len() - 1];
        let by_window = transitions::find_windows(clips, windows, loosest);
        for threshold_m in AUTO_THRESHOLDS_M {
            for (&window, all) in windows.iter().zip(&by_window) {
                let found: Vec<Transition> = all
                    .iter()
                    .copied()
                    .filter(|t| t.rms_m < threshold_m)
                    .collect();
                let params = GraphParams {
                    window,
                    threshold_m,
                };
                let Ok(mut graph) = Self::from_transitions(behaviour, clips, params, &found) else {
                    continue;
                };
                set_best_transitions(&mut graph.coverage, all);
                if visit(graph).is_break() {
                    return Ok(());
                }
            }
        }
        Ok(())
    }

    /// Builds the graph of `behaviour` from its clips (one subject's, so one skeleton).
    pub fn build(
        behaviour: &str,
        clips: &[&Clip],
        params: GraphParams,
    ) -> Result<MotionGraph, GraphError> {
        require_clips(behaviour, clips)?;
        let loosest = AUTO_THRESHOLDS_M[AUTO_THRESHOLDS_M.len() - 1].max(params.threshold_m);
        let all = transitions::find(clips, params.window, loosest);
        let found: Vec<Transition> = all
            .iter()
            .copied()
            .filter(|t| t.rms_m < params.threshold_m)
            .collect();
        let mut graph = Self::from_transitions(behaviour, clips, params, &found)?;
        set_best_transitions(&mut graph.coverage, &all);
        Ok(graph)
    }

    fn from_transitions(
        behaviour: &str,
        clips: &[&Clip],
        params: GraphParams,
        found: &[Transition],
    ) -> Result<MotionGraph, GraphError> {
        let offsets: Vec<usize> = clips
            .iter()
            .scan(0, |acc, c| {
                let start = *acc;
                *acc += c.frame_count();
                Some(start)
            })
            .collect();
        let frames: usize = clips.iter().map(|c| c.frame_count()).sum();
        let mut all_edges = Vec::with_capacity(frames + found.len());
        for (c, clip) in clips.iter().enumerate() {
            for f in 0..clip.frame_count().saturating_sub(1) {
                all_edges.push(Edge {
                    from: (offsets[c] + f) as u32,
                    to: (offsets[c] + f + 1) as u32,
                    step: RootStep::of(clip, f),
                    frames: 1,
                    transition: false,
                });
            }
        }
        for t in found {
            all_edges.push(Edge {
                from: (offsets[t.from_clip] + t.from) as u32,
                to: (offsets[t.to_clip] + t.to) as u32,
                step: RootStep::of(clips[t.from_clip], t.from),
                frames: 1,
                transition: true,
            });
        }

        let keep = largest_scc(frames, &all_edges);
        if keep.iter().filter(|k| k.is_some()).count() < 2 {
            return Err(GraphError::TooShort {
                behaviour: behaviour.to_string(),
                window: params.window,
            });
        }
        let mut edges: Vec<Edge> = all_edges
            .iter()
            .filter_map(|e| {
                let (from, to) = (keep[e.from as usize]?, keep[e.to as usize]?);
                Some(Edge { from, to, ..*e })
            })
            .collect();
        edges.sort_by_key(|e| (e.from, e.to));
        let node_of = |global: usize| {
            let c = offsets.partition_point(|&o| o <= global) - 1;
            Node::of(clips[c], c, global - offsets[c])
        };
        let nodes: Vec<Node> = (0..frames)
            .filter(|&g| keep[g].is_some())
            .map(node_of)
            .collect();
        let mut out_start = vec![0; nodes.len() + 1];
        for e in &edges {
            out_start[e.from as usize + 1] += 1;
        }
        for n in 0..nodes.len() {
            out_start[n + 1] += out_start[n];
        }
        let joints = clips[0].joint_count();
        let poses = nodes
            .iter()
            .flat_map(|r| local_pose(clips[r.clip], r.frame))
            .collect();
        let kept_at = |c: usize, f: usize| keep[offsets[c] + f].is_some();
        let kept: Vec<&Transition> = found
            .iter()
            .filter(|t| kept_at(t.from_clip, t.from) && kept_at(t.to_clip, t.to))
            .collect();
        let kept_rms: Vec<f64> = kept.iter().map(|t| t.rms_m).collect();
        let feet: Vec<cuts::Feet> = clips.iter().map(|c| cuts::Feet::of(c)).collect();
        let quality: Vec<cuts::CutQuality> = kept
            .iter()
            .map(|t| {
                cuts::quality(
                    (clips[t.from_clip], &feet[t.from_clip]),
                    t.from,
                    (clips[t.to_clip], &feet[t.to_clip]),
                    t.to,
                    params.window,
                )
            })
            .collect();
        let coverage = clips
            .iter()
            .enumerate()
            .map(|(c, clip)| ClipCoverage {
                name: clip.name.clone(),
                frames: clip.frame_count(),
                kept: (0..clip.frame_count()).filter(|&f| kept_at(c, f)).count(),
                transitions_in: found
                    .iter()
                    .filter(|t| t.to_clip == c && kept_at(c, t.to) && kept_at(t.from_clip, t.from))
                    .count(),
                transitions_out: found
                    .iter()
                    .filter(|t| t.from_clip == c && kept_at(c, t.from) && kept_at(t.to_clip, t.to))
                    .count(),
                best_transition_m: None,
            })
            .collect();
        let stats = GraphStats {
            frames,
            clips: clips.len(),
            transitions_before_pruning: found.len(),
            transitions_after_pruning: edges.iter().filter(|e| e.transition).count(),
            largest_scc: nodes.len(),
            top_speed_m_s: clips
                .iter()
                .enumerate()
                .map(|(c, clip)| top_speed(clip, |f| kept_at(c, f)))
                .fold(0.0, f64::max),
            transition_worst_m: kept_rms.iter().copied().fold(0.0, f64::max),
            transition_p95_m: percentile(&kept_rms, 0.95),
            foot_slide_p95_m: percentile(
                &quality.iter().map(|q| q.foot_slide_m).collect::<Vec<_>>(),
                0.95,
            ),
            root_accel_p95_m_s2: percentile(
                &quality
                    .iter()
                    .map(|q| q.root_accel_m_s2)
                    .collect::<Vec<_>>(),
                0.95,
            ),
            capture_root_accel_p95_m_s2: percentile(
                &cuts::capture_accelerations(clips, params.window),
                0.95,
            ),
        };
        Ok(MotionGraph {
            behaviour: behaviour.to_string(),
            fps: clips[0].fps,
            params,
            clip_names: clips.iter().map(|c| c.name.clone()).collect(),
            coverage,
            nodes,
            edges,
            out_start,
            poses,
            joints,
            joint_names: clips[0].joint_names.clone(),
            joint_parents: clips[0].parents.clone(),
            stats,
        })
    }

    /// A digest of the graph's nodes and edges (hex of the first 8 bytes of a SHA-256):
    /// two graphs with the same digest walk alike, which is what cached maps are keyed by.
    pub fn digest(&self) -> String {
        use sha2::{Digest, Sha256};
        let mut hash = Sha256::new();
        for n in &self.nodes {
            hash.update((n.clip as u64).to_le_bytes());
            hash.update((n.frame as u64).to_le_bytes());
        }
        for e in &self.edges {
            hash.update(e.from.to_le_bytes());
            hash.update(e.to.to_le_bytes());
            hash.update(e.frames.to_le_bytes());
            hash.update([u8::from(e.transition)]);
            for v in [e.step.dx, e.step.dz, e.step.dheading] {
                hash.update(v.to_bits().to_le_bytes());
            }
        }
        hash.finalize()[..8]
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect()
    }

    /// Nodes kept: node ids run from 0 to this, exclusive.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The edges leaving `node`, with their indices into [`MotionGraph::edges`].
    pub fn out_edges(&self, node: u32) -> std::ops::Range<usize> {
        self.out_start[node as usize]..self.out_start[node as usize + 1]
    }

    /// Which edges the constraints leave enabled, indexed like [`MotionGraph::edges`].
    ///
    /// Disabling edges can leave nodes with no way on, and a walk that wanders into one is
    /// stuck; so, as when the graph was built, only the largest strongly connected
    /// component of what is left stays enabled.
    pub fn enabled(&self, constraints: &Constraints) -> Vec<bool> {
        let allowed: Vec<bool> = self
            .edges
            .iter()
            .map(|e| {
                constraints
                    .max_speed
                    .is_none_or(|v| e.step.length() * self.fps <= v)
            })
            .collect();
        if allowed.iter().all(|a| *a) {
            return allowed;
        }
        let kept: Vec<Edge> = self
            .edges
            .iter()
            .zip(&allowed)
            .filter(|(_, a)| **a)
            .map(|(e, _)| *e)
            .collect();
        let keep = largest_scc(self.nodes.len(), &kept);
        self.edges
            .iter()
            .zip(allowed)
            .map(|(e, a)| a && keep[e.from as usize].is_some() && keep[e.to as usize].is_some())
            .collect()
    }

    /// The default start pose for a cost map: a node running forward at a moderate speed
    /// (closest to half the behaviour's top speed, moving mostly forward and turning less
    /// than 0.3 rad/s).
    pub fn default_start(&self) -> u32 {
        let target = 0.5 * self.stats.top_speed_m_s;
        let off = |n: &Node| (n.forward_speed - target).abs();
        (0..self.nodes.len() as u32)
            .filter(|&i| {
                let n = &self.nodes[i as usize];
                n.forward_speed > 2.0 * n.lateral_speed.abs() && n.turn_rate.abs() < 0.3
            })
            .min_by(|&a, &b| off(&self.nodes[a as usize]).total_cmp(&off(&self.nodes[b as usize])))
            .unwrap_or(0)
    }

    /// Whether the parts of a graph read from elsewhere (a cache file) fit together as
    /// a built one's do, so that no index into them can fall outside: every edge's ends
    /// are nodes, the edges are grouped by node as `out_start` says, every node has its
    /// pose, every node's clip is named. `Err` says what does not fit.
    pub(crate) fn check(&self) -> Result<(), String> {
        let nodes = self.nodes.len();
        if nodes == 0 || nodes > u32::MAX as usize {
            return Err(format!("{nodes} nodes"));
        }
        if let Some(e) = self
            .edges
            .iter()
            .find(|e| e.from as usize >= nodes || e.to as usize >= nodes)
        {
            return Err(format!("an edge {} → {} among {nodes} nodes", e.from, e.to));
        }
        let grouped = self.out_start.len() == nodes + 1
            && self.out_start.first() == Some(&0)
            && self.out_start.last() == Some(&self.edges.len())
            && self.out_start.windows(2).all(|w| w[0] <= w[1])
            && (0..nodes).all(|n| {
                self.edges[self.out_start[n]..self.out_start[n + 1]]
                    .iter()
                    .all(|e| e.from as usize == n)
            });
        if !grouped {
            return Err("edges not grouped by node as out_start says".into());
        }
        if self.joints == 0 || self.poses.len() != nodes * self.joints {
            return Err(format!(
                "{} pose points for {nodes} nodes of {} joints",
                self.poses.len(),
                self.joints
            ));
        }
        if self.joint_names.len() != self.joints || self.joint_parents.len() != self.joints {
            return Err("joint names or parents not one per joint".into());
        }
        if self
            .joint_parents
            .iter()
            .flatten()
            .any(|&p| p >= self.joints)
        {
            return Err("a joint's parent is no joint".into());
        }
        if self.nodes.iter().any(|n| n.clip >= self.clip_names.len()) {
            return Err("a node of an unnamed clip".into());
        }
        Ok(())
    }

    /// A node's joints in its character frame (root at the origin on the ground, facing +x).
    pub fn pose(&self, node: u32) -> &[DVec3] {
        let j = self.joints;
        &self.poses[node as usize * j..(node as usize + 1) * j]
    }
}

fn require_clips(behaviour: &str, clips: &[&Clip]) -> Result<(), GraphError> {
    if clips.is_empty() {
        return Err(GraphError::NoClips {
            behaviour: behaviour.to_string(),
        });
    }
    Ok(())
}

/// Marks the nodes of the largest strongly connected component with their new, compact
/// ids (in order of the old ids, so the numbering is deterministic).
fn largest_scc(nodes: usize, edges: &[Edge]) -> Vec<Option<u32>> {
    let mut g: DiGraph<(), ()> = DiGraph::with_capacity(nodes, edges.len());
    for _ in 0..nodes {
        g.add_node(());
    }
    for e in edges {
        g.add_edge(
            NodeIndex::new(e.from as usize),
            NodeIndex::new(e.to as usize),
            (),
        );
    }
    let mut components = tarjan_scc(&g);
    for c in &mut components {
        c.sort();
    }
    let largest = components
        .iter()
        .max_by(|a, b| a.len().cmp(&b.len()).then(b[0].cmp(&a[0])))
        .cloned()
        .unwrap_or_default();
    let mut keep = vec![None; nodes];
    for (new, old) in largest.iter().enumerate() {
        keep[old.index()] = Some(new as u32);
    }
    keep
}

/// Joint positions of a frame in its own character frame.
fn local_pose(clip: &Clip, f: usize) -> Vec<DVec3> {
    let root = clip.root(f);
    let (sin, cos) = clip.heading(f).sin_cos();
    clip.frame(f)
        .iter()
        .map(|p| {
            let (x, z) = (p.x - root.x, p.z - root.y);
            // Rotate by −heading so the body faces +x.
            DVec3::new(x * cos + z * sin, p.y, -x * sin + z * cos)
        })
        .collect()
}

/// Fastest root speed over a ⅓ s span of frames all `kept`, which averages out the
/// sway within a stride.
fn top_speed(clip: &Clip, kept: impl Fn(usize) -> bool) -> f64 {
    let span = ((clip.fps / 3.0).round() as usize).max(1);
    (0..clip.frame_count().saturating_sub(span))
        .filter(|&f| (f..=f + span).all(&kept))
        .map(|f| (clip.root(f + span) - clip.root(f)).length() * clip.fps / span as f64)
        .fold(0.0, f64::max)
}

/// The `q` quantile of `values` (nearest rank), 0 when empty.
fn percentile(values: &[f64], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let rank = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    sorted[rank - 1]
}

/// Fills each clip's best transition to or from another clip, from every transition
/// found at the loosest threshold.
fn set_best_transitions(coverage: &mut [ClipCoverage], all: &[Transition]) {
    for (c, cov) in coverage.iter_mut().enumerate() {
        cov.best_transition_m = all
            .iter()
            .filter(|t| t.from_clip != t.to_clip && (t.from_clip == c || t.to_clip == c))
            .map(|t| t.rms_m)
            .min_by(f64::total_cmp);
    }
}
