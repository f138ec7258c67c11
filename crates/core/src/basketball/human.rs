//! What people do, beside what the capture lets the agents do: the capability model's
//! targets, each with the human figure it stands for and where that figure comes from.
//!
//! The maps are only as good as the capture: a clip that never steps left gives a
//! defender that cannot, and an offense that models it with those maps wins by an
//! artefact. So each behaviour is held to what people do from a stance, and where it
//! falls short the report shows the walk it takes, which says what motion the capture
//! lacks.

use super::capability::Mover;
use crate::costmap::{root_speed, CostMap};
use crate::motion::{MotionGraph, TurnAround};
use glam::DVec2;
use serde::Serialize;

/// How a target is measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Measure {
    /// Frames to the map cell just beyond this point of the agent's frame (+x ahead, +z
    /// right), m.
    Point(f64, f64),
    /// Frames to face the other way within 1 m of where it stood ([`turn_around`](crate::motion::turn_around)).
    TurnAround,
}

/// One target: what is measured, for which behaviours, the most it may take, and what
/// people take with the source of that figure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Target {
    /// Its key in reports, e.g. `left_1m`.
    pub key: &'static str,
    /// In words.
    pub what: &'static str,
    /// The behaviours held to it.
    pub behaviours: &'static [&'static str],
    /// The most it may take, s.
    pub target_s: f64,
    /// What people take, s (a range, as sources give it).
    pub people: &'static str,
    /// Where `people` comes from; an estimate says so.
    pub source: &'static str,
    /// How it is measured.
    pub measure: Measure,
}

const SLIDE: &str = "an estimate: one or two slide steps from a defensive stance \
    (no timed 1 m side step in the literature we found)";

/// Below this root speed a body is in a stance, m/s: the targets are measured from one.
pub const STANCE_M_S: f64 = 0.3;

/// The targets, in the order reports list them.
pub const TARGETS: [Target; 5] = [
    Target {
        key: "left_1m",
        what: "1 m to the left",
        behaviours: &["dribble", "defense"],
        target_s: 0.8,
        people: "0.4–0.6",
        source: SLIDE,
        measure: Measure::Point(0.0, -1.0),
    },
    Target {
        key: "right_1m",
        what: "1 m to the right",
        behaviours: &["dribble", "defense"],
        target_s: 0.8,
        people: "0.4–0.6",
        source: SLIDE,
        measure: Measure::Point(0.0, 1.0),
    },
    Target {
        key: "ahead_5m",
        what: "5 m ahead",
        behaviours: &["run"],
        target_s: 1.5,
        people: "0.98–1.09",
        source: "Altmann et al. 2015, J Strength Cond Res 29(8): 5 m sprints of 13 sports \
            students, starting 1.0 to 0.3 m behind the first timing gate",
        measure: Measure::Point(5.0, 0.0),
    },
    Target {
        key: "behind_5m",
        what: "5 m behind",
        behaviours: &["run", "defense"],
        target_s: 2.6,
        people: "1.5–2.0",
        source: "an estimate from the 5-0-5 test (Draper & Lancaster 1985): 5 m in, a 180° \
            turn and 5 m out take 2.2–2.9 s with a run-up; from a stance, a turn and a 5 m \
            sprint",
        measure: Measure::Point(-5.0, 0.0),
    },
    Target {
        key: "turn_around",
        what: "a 180° turn, ending within 1 m",
        behaviours: &["dribble", "run", "defense"],
        target_s: 1.0,
        people: "0.5–0.7",
        source: "an estimate: a pivot or a jump turn on the spot",
        measure: Measure::TurnAround,
    },
];

/// Left and right from a stance may differ by at most this many frames: a body is
/// symmetric, and so is a mirrored capture.
pub const SYMMETRY_FRAMES: u32 = 2;

/// One behaviour measured against one target, from its stance.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Check {
    /// The target's key.
    pub key: &'static str,
    /// In words.
    pub what: &'static str,
    /// The behaviour measured.
    pub behaviour: String,
    /// The start state it is measured from (the slowest the capture has).
    pub state: String,
    /// Its root speed, m/s: a stance only below [`STANCE_M_S`].
    pub state_speed_m_s: f64,
    /// Frames it takes; `None` beyond the horizon (or no turn found).
    pub frames: Option<u32>,
    /// The target, s.
    pub target_s: f64,
    /// What people take, s.
    pub people: &'static str,
    /// Where that figure comes from.
    pub source: &'static str,
    /// Met: within the target, from a real stance.
    pub met: bool,
    /// The walk it takes, as the clips it plays in order with frames in each: where a
    /// target is not met, this says what motion the capture lacks.
    pub walk: Vec<(String, u32)>,
}

/// A behaviour at its stance: its graph and the maps from its slowest start state and,
/// if the capture is mirrored, that stance's mirror image (a body standing still may set
/// off on either foot, as a standing agent does).
#[derive(Debug, Clone, Copy)]
pub struct Stance<'a> {
    /// The behaviour's name.
    pub behaviour: &'a str,
    /// Its motion graph.
    pub graph: &'a MotionGraph,
    /// The name of the start state (the slowest the capture has).
    pub state: &'a str,
    /// The map from it; its start node is the stance.
    pub map: &'a CostMap,
    /// The map from the stance's mirror image, if there is one.
    pub twin: Option<&'a CostMap>,
    /// The quickest turn around from either
    /// ([`quickest_turn_around`](crate::motion::quickest_turn_around)).
    pub turn: Option<&'a TurnAround>,
}

impl<'a> Stance<'a> {
    /// A mover's stance: its first start state, the slowest, and its mirror image.
    pub fn of(mover: &'a Mover) -> Stance<'a> {
        let standing = &mover.states[0];
        Stance {
            behaviour: mover.behaviour,
            graph: &mover.graph,
            state: &standing.state.name,
            map: &standing.map,
            twin: mover
                .states
                .iter()
                .find(|s| s.state.name == crate::costmap::STANDING_MIRRORED)
                .map(|s| &s.map),
            turn: mover.turn(),
        }
    }

    /// The stance's maps: its own, then its mirror image's.
    fn maps(&self) -> impl Iterator<Item = &'a CostMap> {
        std::iter::once(self.map).chain(self.twin)
    }

    /// Frames to the map cell holding `local` (the body's frame), from whichever stance
    /// gets there sooner, and that map.
    fn cost(&self, local: DVec2) -> Option<(u32, &'a CostMap)> {
        self.maps()
            .filter_map(|m| m.cost(local).map(|c| (c, m)))
            .min_by_key(|(c, _)| *c)
    }
}

/// Measures every behaviour held to a target (`stances` by name), from its stance.
pub fn check(stances: &[Stance], fps: f64) -> Vec<Check> {
    let mut checks = Vec::new();
    for target in &TARGETS {
        for &behaviour in target.behaviours {
            let Some(stance) = stances.iter().find(|s| s.behaviour == behaviour) else {
                continue;
            };
            let speed = root_speed(&stance.graph.nodes[stance.map.start_node as usize]);
            let (frames, nodes) = measure(stance, target.measure);
            checks.push(Check {
                key: target.key,
                what: target.what,
                behaviour: behaviour.to_string(),
                state: stance.state.to_string(),
                state_speed_m_s: speed,
                frames,
                target_s: target.target_s,
                people: target.people,
                source: target.source,
                met: speed < STANCE_M_S
                    && frames.is_some_and(|f| f64::from(f) / fps <= target.target_s + 1e-9),
                walk: clips_played(stance.graph, &nodes),
            });
        }
    }
    checks
}

/// Every target's measure from `stance`, whichever behaviours the targets are for:
/// (key, frames), `None` beyond the horizon.
pub fn measure_all(stance: &Stance) -> Vec<(&'static str, Option<u32>)> {
    TARGETS
        .iter()
        .map(|t| (t.key, measure(stance, t.measure).0))
        .collect()
}

/// Frames to meet `measure` from the stance, and the nodes the walk plays.
fn measure(stance: &Stance, measure: Measure) -> (Option<u32>, Vec<u32>) {
    match measure {
        Measure::Point(x, z) => match stance.cost(probe(x, z)) {
            Some((frames, map)) => {
                let cell = map.grid.cell_of(probe(x, z)).expect("the map has it");
                let nodes = map.paths[cell]
                    .iter()
                    .map(|&e| stance.graph.edges[e as usize].to)
                    .collect();
                (Some(frames), nodes)
            }
            None => (None, Vec::new()),
        },
        Measure::TurnAround => stance.turn.map_or((None, Vec::new()), |turn| {
            (Some(turn.frames), turn.nodes.clone())
        }),
    }
}

/// The cell a point `d` metres out counts as: the one just beyond it, in the row or
/// column on the +side of the agent's axis, so "1 m ahead" is the cell from 1.0 to 1.5 m.
pub fn probe(x: f64, z: f64) -> DVec2 {
    const NUDGE: f64 = 0.01;
    DVec2::new(
        x + NUDGE * if x < 0.0 { -1.0 } else { 1.0 },
        z + NUDGE * if z < 0.0 { -1.0 } else { 1.0 },
    )
}

/// The clips `nodes` play, in order, with the frames spent in each.
fn clips_played(graph: &MotionGraph, nodes: &[u32]) -> Vec<(String, u32)> {
    let mut walk: Vec<(String, u32)> = Vec::new();
    for &n in nodes {
        let clip = &graph.clip_names[graph.nodes[n as usize].clip];
        match walk.last_mut() {
            Some((last, frames)) if last == clip => *frames += 1,
            _ => walk.push((clip.clone(), 1)),
        }
    }
    walk
}

/// Left against right from each behaviour's stance, 1 m and 3 m out: (behaviour,
/// distance m, frames left, frames right).
pub fn symmetry<'a>(stances: &[Stance<'a>]) -> Vec<(&'a str, f64, Option<u32>, Option<u32>)> {
    stances
        .iter()
        .flat_map(|s| {
            [1.0, 3.0].map(|d| {
                (
                    s.behaviour,
                    d,
                    s.cost(probe(0.0, -d)).map(|(f, _)| f),
                    s.cost(probe(0.0, d)).map(|(f, _)| f),
                )
            })
        })
        .collect()
}
