//! Start states: where in the motion graph a body is when a cost map begins. A map is a
//! function of how the body is moving, not only of where it stands (the paper's maps are
//! invariant to position and heading), so the capability model holds one map per start
//! state: standing, and each distinct way the data moves.

use crate::motion::{MotionGraph, Node};
use serde::Serialize;
use std::str::FromStr;

/// A start state a user names: `default` (running forward at about half the top speed,
/// the one pose maps used to start from), `standing` (the slowest node the data offers),
/// `moving` (the most common running state), or a node id.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Start {
    /// The graph's default: running forward at about half the top speed.
    Default,
    /// The slowest node.
    Standing,
    /// The most common running state.
    Moving,
    /// This node of the graph.
    Node(u32),
}

impl FromStr for Start {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "default" => Ok(Start::Default),
            "standing" => Ok(Start::Standing),
            "moving" => Ok(Start::Moving),
            _ => s.parse::<u32>().map(Start::Node).map_err(|_| {
                format!("start \"{s}\": write default, standing, moving or a node id")
            }),
        }
    }
}

impl Start {
    /// The node this start names in `graph`; `None` for a node id the graph lacks.
    pub fn node(self, graph: &MotionGraph) -> Option<u32> {
        match self {
            Start::Default => Some(graph.default_start()),
            Start::Standing => Some(standing(graph)),
            Start::Moving => Some(moving(graph)),
            Start::Node(n) => ((n as usize) < graph.node_count()).then_some(n),
        }
    }
}

/// A start state of a graph: its name and the node a map of it starts from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct StartState {
    /// What people call it: `standing`, or pace, direction and turn of the way the
    /// data moves (`slow-forward-straight`).
    pub name: String,
    /// The graph node a map of it starts from.
    pub node: u32,
}

/// Root speed over the ground, m/s.
pub fn root_speed(n: &Node) -> f64 {
    n.forward_speed.hypot(n.lateral_speed)
}

/// The slowest node: standing, or as near it as the data comes.
fn standing(graph: &MotionGraph) -> u32 {
    (0..graph.node_count() as u32)
        .min_by(|&a, &b| {
            root_speed(&graph.nodes[a as usize]).total_cmp(&root_speed(&graph.nodes[b as usize]))
        })
        .unwrap_or(0)
}

/// Below this root speed a body counts as standing, m/s.
const STANDING_M_S: f64 = 0.5;
/// Turning faster than this counts as a turn, rad/s (about 30° a second).
const TURNING_RAD_S: f64 = 0.5;
/// A moving state needs this share of the graph's nodes to get a map of its own.
const MIN_SHARE: f64 = 0.03;

/// A kind of moving: speed class, direction of travel in the body's frame, and turn.
type Kind = (&'static str, &'static str, &'static str);

/// Which kind of moving a node shows.
fn kind(n: &Node) -> Option<Kind> {
    let speed = root_speed(n);
    if speed < STANDING_M_S {
        return None;
    }
    let pace = match speed {
        s if s < 1.5 => "slow",
        s if s < 3.0 => "medium",
        _ => "fast",
    };
    // Sectors of 90° around the body's axes; +z (lateral > 0) is its right.
    let angle = n.lateral_speed.atan2(n.forward_speed).to_degrees();
    let direction = match angle {
        a if a.abs() <= 45.0 => "forward",
        a if a.abs() >= 135.0 => "backward",
        a if a > 0.0 => "right",
        _ => "left",
    };
    let turn = match n.turn_rate {
        t if t > TURNING_RAD_S => "turning-right",
        t if t < -TURNING_RAD_S => "turning-left",
        _ => "straight",
    };
    Some((pace, direction, turn))
}

/// The moving states of `graph` with at least [`MIN_SHARE`] of its nodes, most common
/// first, each with its node nearest the state's mean speed and turn.
fn moving_states(graph: &MotionGraph) -> Vec<StartState> {
    let mut groups: Vec<(Kind, Vec<u32>)> = Vec::new();
    for (i, n) in graph.nodes.iter().enumerate() {
        let Some(k) = kind(n) else { continue };
        match groups.iter_mut().find(|(g, _)| *g == k) {
            Some((_, members)) => members.push(i as u32),
            None => groups.push((k, vec![i as u32])),
        }
    }
    groups.retain(|(_, m)| m.len() as f64 >= MIN_SHARE * graph.node_count() as f64);
    groups.sort_by(|a, b| b.1.len().cmp(&a.1.len()).then(a.0.cmp(&b.0)));
    groups
        .into_iter()
        .map(|((pace, direction, turn), members)| {
            let nodes = || members.iter().map(|&i| &graph.nodes[i as usize]);
            let count = members.len() as f64;
            let mean = |f: fn(&Node) -> f64| nodes().map(f).sum::<f64>() / count;
            let (fwd, lat, turn_rate) = (
                mean(|n| n.forward_speed),
                mean(|n| n.lateral_speed),
                mean(|n| n.turn_rate),
            );
            let off = |n: &Node| {
                (n.forward_speed - fwd).hypot(n.lateral_speed - lat)
                    + (n.turn_rate - turn_rate).abs()
            };
            let node = *members
                .iter()
                .min_by(|&&a, &&b| {
                    off(&graph.nodes[a as usize]).total_cmp(&off(&graph.nodes[b as usize]))
                })
                .expect("groups are not empty");
            StartState {
                name: format!("{pace}-{direction}-{turn}"),
                node,
            }
        })
        .collect()
}

/// The most common running state: the commonest moving state going forward without
/// turning, else the commonest of any.
fn moving(graph: &MotionGraph) -> u32 {
    let states = moving_states(graph);
    states
        .iter()
        .find(|s| s.name.ends_with("-forward-straight"))
        .or(states.first())
        .map(|s| s.node)
        .unwrap_or_else(|| graph.default_start())
}

/// The name of the stance that mirrors `standing`.
pub const STANDING_MIRRORED: &str = "standing-mirrored";

/// The start states the capability model keeps a map for: `standing`, its mirror image
/// (when the capture is mirrored: a body standing still may set off on either foot, so
/// a standing agent gets the better of the two), then every moving state of the data
/// with at least 3 % of its nodes, most common first.
pub fn start_states(graph: &MotionGraph) -> Vec<StartState> {
    let stance = standing(graph);
    let mut states = vec![StartState {
        name: "standing".into(),
        node: stance,
    }];
    if let Some(twin) = graph.mirror_twin(stance) {
        states.push(StartState {
            name: STANDING_MIRRORED.into(),
            node: twin,
        });
    }
    states.extend(moving_states(graph));
    states
}
