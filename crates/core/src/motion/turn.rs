//! Turning around on the spot: how soon a body playing a node of a motion graph can face
//! the other way while staying near where it stood. A cost map cannot say (it keeps where
//! a walk gets, not which way it then faces), and it is what a defender beaten by a pass
//! or a dribbler reversing does.

use super::{MotionGraph, Walker};
use glam::DVec2;
use rustc_hash::FxHashSet;
use serde::{Deserialize, Serialize};

/// What counts as a turn around: facing within `tolerance_deg` of the reverse of the way
/// the body faced, with the root within `within_m` of where it stood.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TurnParams {
    /// How far from where it stood the turn may end, m.
    pub within_m: f64,
    /// How far from the reverse heading still counts as turned around, degrees: the
    /// heading follows the hips, which sway by about ±10° within a stride.
    pub tolerance_deg: f64,
    /// The longest turn looked for, frames.
    pub max_frames: u32,
    /// How far from where it stood a walk may stray on the way, m: turning on the spot
    /// is not running a loop, and the bound keeps the search small.
    pub stray_m: f64,
}

impl Default for TurnParams {
    fn default() -> Self {
        TurnParams {
            within_m: 1.0,
            tolerance_deg: 20.0,
            max_frames: 90,
            stray_m: 2.0,
        }
    }
}

/// The quickest turn around found: a real walk on the graph.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TurnAround {
    /// Frames it takes.
    pub frames: u32,
    /// Where it ends, relative to where the body stood (+x ahead, +z right), m.
    pub end_m: [f64; 2],
    /// The way it ends facing, degrees from the way it faced (±180 is straight back).
    pub heading_deg: f64,
    /// The nodes it plays, after the start.
    pub nodes: Vec<u32>,
}

/// How finely walks are told apart: a walk that reaches a node within these of the
/// position and heading another walk reached it at, no later, is taken to go on as that
/// one does, and is not followed (bounded work on graphs of thousands of nodes). Measured
/// on the CMU graphs from standing: 35, 85 and 73 frames (dribble, run, defense) in
/// 0.1–0.7 s, against 33, 82 and 73 with bins of 0.1 m and 10°, ten times slower.
const POSITION_BIN_M: f64 = 0.25;
const HEADING_BIN_DEG: f64 = 15.0;

/// The quickest turn around from `start`, frame by frame over the graph's walks; `None`
/// if no walk turns around within `params.max_frames`.
///
/// Walks are followed in frame order, so the first that meets the conditions is the
/// quickest, up to the binning that keeps the search bounded (0.25 m and 15°).
/// A walk that strays farther than `stray_m` is dropped, and so is one too far away to
/// come back within `within_m` by the last frame at the behaviour's top speed.
pub fn turn_around(graph: &MotionGraph, start: u32, params: &TurnParams) -> Option<TurnAround> {
    let tolerance = params.tolerance_deg.to_radians();
    // The most any one frame moves or turns the body: bounds on what the rest of a walk
    // can still do, so a walk that cannot finish a turn in time is dropped.
    let step_m = graph
        .edges
        .iter()
        .map(|e| e.step.length())
        .fold(1e-6, f64::max);
    let turn_rad = graph
        .edges
        .iter()
        .map(|e| e.step.dheading.abs())
        .fold(1e-6, f64::max);
    let turns: Vec<DVec2> = graph
        .edges
        .iter()
        .map(|e| DVec2::from_angle(e.step.dheading))
        .collect();
    // Every state followed after the start: its node and its parent's index here (`None`
    // for the start), so the walk that turns can be read back.
    let mut trail: Vec<(u32, Option<usize>)> = Vec::new();
    // This frame's states: node, walker, and the parent's index in `trail`.
    let mut layer: Vec<(u32, Walker, Option<usize>)> = vec![(start, Walker::START, None)];
    let mut seen = Seen::new(graph.node_count(), params.stray_m + step_m);
    for frame in 0..=params.max_frames {
        let mut next = Vec::new();
        for &(node, at, parent) in &layer {
            let here = (frame > 0).then(|| {
                trail.push((node, parent));
                trail.len() - 1
            });
            let turned = (at.heading().abs() - std::f64::consts::PI).abs() <= tolerance;
            if frame > 0 && turned && at.position.length() <= params.within_m {
                let mut nodes = Vec::new();
                let mut k = here;
                while let Some(i) = k {
                    nodes.push(trail[i].0);
                    k = trail[i].1;
                }
                nodes.reverse();
                return Some(TurnAround {
                    frames: frame,
                    end_m: at.position.to_array(),
                    heading_deg: at.heading().to_degrees(),
                    nodes,
                });
            }
            let left = f64::from(params.max_frames - frame);
            let away = at.position.length();
            let to_turn = std::f64::consts::PI - tolerance - at.heading().abs();
            if away > params.stray_m
                || away - params.within_m > step_m * left
                || to_turn > turn_rad * left
            {
                continue;
            }
            for i in graph.out_edges(node) {
                let e = &graph.edges[i];
                if e.frames != 1 {
                    // Graphs built from clips have one-frame edges; a longer edge would
                    // need its own layer, and no graph here has one.
                    continue;
                }
                let to = at.after(&e.step, turns[i]);
                if seen.insert(e.to, &to) {
                    next.push((e.to, to, here));
                }
            }
        }
        if next.is_empty() {
            return None;
        }

        layer = next;
    }
    None
}

/// The states a search has reached: a bit per (node, position bin, heading bin) within
/// reach of the start, the search's whole cost as a hash set (58 % of a profile), and a
/// hash set of [`state_key`]s for any state beyond (none, given the bound the search
/// prunes by, but a bound is only as good as its arithmetic).
struct Seen {
    bits: Vec<u64>,
    /// Position bins either side of the start the bits cover.
    reach: i64,
    beyond: FxHashSet<u64>,
}

/// Heading bins: round(heading / 15°) over (−180°, 180°] is −12 to 12.
const HEADING_BINS: i64 = 25;

impl Seen {
    /// For `nodes` nodes and positions within `radius_m` of the start.
    fn new(nodes: usize, radius_m: f64) -> Seen {
        let reach = (radius_m / POSITION_BIN_M).ceil() as i64 + 1;
        let side = (2 * reach + 1) as usize;
        let states = nodes * side * side * HEADING_BINS as usize;
        Seen {
            // Zeroed pages cost nothing until a walk touches them.
            bits: vec![0; states.div_ceil(64)],
            reach,
            beyond: FxHashSet::default(),
        }
    }

    /// Marks the state of `node` at `at`; true if it was not marked before. The same
    /// bins as [`state_key`], so the search follows exactly the walks it followed with
    /// a hash set of keys.
    fn insert(&mut self, node: u32, at: &Walker) -> bool {
        let bin = |v: f64, size: f64| (v / size).round() as i64;
        let (x, z) = (
            bin(at.position.x, POSITION_BIN_M),
            bin(at.position.y, POSITION_BIN_M),
        );
        let h = bin(at.heading().to_degrees(), HEADING_BIN_DEG) + HEADING_BINS / 2;
        let side = 2 * self.reach + 1;
        if x.abs() > self.reach || z.abs() > self.reach || !(0..HEADING_BINS).contains(&h) {
            return self.beyond.insert(state_key(node, at));
        }
        let i = (((i64::from(node) * side + x + self.reach) * side + z + self.reach) * HEADING_BINS
            + h) as usize;
        let (word, bit) = (i / 64, 1u64 << (i % 64));
        let fresh = self.bits[word] & bit == 0;
        self.bits[word] |= bit;
        fresh
    }
}

/// The quickest turn around from any of `starts` (a stance and its mirror image, say),
/// with the default [`TurnParams`]: the search takes about a second on the CMU graphs, so
/// movers keep what it finds beside their maps.
pub fn quickest_turn_around(
    graph: &MotionGraph,
    starts: impl IntoIterator<Item = u32>,
) -> Option<TurnAround> {
    starts
        .into_iter()
        .filter_map(|start| turn_around(graph, start, &TurnParams::default()))
        .min_by_key(|turn| turn.frames)
}

/// A walk's node, position bin and heading bin packed in one integer: node in the high
/// 32 bits, then 12 bits for each position bin and 8 for the heading's (positions are
/// within `stray_m` of the start, a few metres, so 12 bits of 0.1 m hold ±200 m).
fn state_key(node: u32, at: &Walker) -> u64 {
    let bin = |v: f64, size: f64, bits: u32| {
        let mask = (1u64 << bits) - 1;
        ((v / size).round() as i64 as u64) & mask
    };
    u64::from(node) << 32
        | bin(at.position.x, POSITION_BIN_M, 12) << 20
        | bin(at.position.y, POSITION_BIN_M, 12) << 8
        | bin(at.heading().to_degrees(), HEADING_BIN_DEG, 8)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures;
    use crate::motion::{Clip, GraphParams};

    /// A body circling at 1.5 m/s on a 0.3 m radius faces back after half a circle:
    /// π·0.3 m at 1.5 m/s, 0.63 s or 19 frames (within a frame or two, the heading being
    /// measured from the hips), and ends 0.6 m from where it started, within 1 m.
    #[test]
    fn a_tight_circle_turns_around_in_half_its_period() {
        let clips: Vec<Clip> = vec![fixtures::clip("pivot", 4.0, fixtures::circle(1.5, 0.3))];
        let refs: Vec<&Clip> = clips.iter().collect();
        let graph = MotionGraph::build(
            "run",
            &refs,
            GraphParams {
                window: 6,
                threshold_m: 0.05,
            },
        )
        .unwrap();
        let turn = turn_around(&graph, 0, &TurnParams::default()).expect("it turns");
        let exact = (std::f64::consts::PI * 0.3 / 1.5 * 30.0).round() as i64;
        assert!(
            (i64::from(turn.frames) - exact).abs() <= 2,
            "{turn:?} against {exact}"
        );
        assert!((turn.heading_deg.abs() - 180.0).abs() <= 20.0);
        let end = glam::DVec2::from_array(turn.end_m);
        assert!((end.length() - 0.6).abs() < 0.05, "{end}");
        assert_eq!(turn.nodes.len(), turn.frames as usize);
    }

    /// Running straight never turns around; a wide circle turns, but ends far away.
    #[test]
    fn no_turn_on_the_spot_in_straight_or_wide_running() {
        for path in [
            Box::new(fixtures::straight(3.0)) as Box<dyn Fn(f64) -> (glam::DVec2, f64)>,
            Box::new(fixtures::circle(3.0, 4.0)),
        ] {
            let clips = [fixtures::clip("c", 6.0, path)];
            let refs: Vec<&Clip> = clips.iter().collect();
            let graph = MotionGraph::build("run", &refs, GraphParams::default()).unwrap();
            assert_eq!(turn_around(&graph, 0, &TurnParams::default()), None);
        }
    }
}
