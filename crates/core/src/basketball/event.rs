//! What a game reports: events as they happen, and snapshots of the whole court.

use super::agent::{Action, Team};
use super::decision::Chosen;
use super::safe::SafeSquares;
use serde::Serialize;

/// How a possession ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    Made,
    Missed,
    Blocked,
    Stolen,
    Intercepted,
    ShotClock,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Event {
    /// An agent chose a new action (or, with the ball, a new shooting square). `chosen`
    /// is that of `basketball-decide`; `safe` the squares that satisfied the rule, as a
    /// bitmap, so a spectator can outline them (`None` when none did, or for a play that
    /// chose no square).
    Decision {
        agent: String,
        action: Action,
        reason: String,
        #[serde(serialize_with = "chosen_on_the_wire")]
        chosen: Option<Chosen>,
        safe: Option<SafeSquares>,
    },
    Pass {
        from: String,
        to: String,
    },
    PassCaught {
        by: String,
    },
    /// The ball is away (or was blocked on the way up).
    Shot {
        by: String,
        from: [f64; 2],
        distance_m: f64,
        success: f64,
        made: bool,
        blocked: bool,
        points: u32,
    },
    PossessionEnded {
        possession: u64,
        outcome: Outcome,
        points: u32,
        /// From the start of the possession to the moment its outcome was settled.
        duration_s: f64,
        passes: u32,
    },
}

/// `chosen` as frames carry it: without T_s and ε, which are the match's (the hello's
/// `field.decision`) and the same in every decision.
fn chosen_on_the_wire<S: serde::Serializer>(
    chosen: &Option<Chosen>,
    s: S,
) -> Result<S::Ok, S::Error> {
    #[derive(Serialize)]
    struct OnTheWire {
        cell: [f64; 2],
        success: f64,
        c_o: f64,
        c_d: f64,
        here: bool,
    }
    chosen
        .map(|c| OnTheWire {
            cell: c.cell,
            success: c.success,
            c_o: c.c_o,
            c_d: c.c_d,
            here: c.here,
        })
        .serialize(s)
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct AgentView {
    pub(crate) id: String,
    /// Not in frames: a player's team never changes, and the `hello` lists it.
    #[serde(skip)]
    pub team: Team,
    pub(crate) behaviour: &'static str,
    pub(crate) position: [f64; 2],
    /// Radians from +x toward +z.
    pub heading: f64,
    pub(crate) node: Option<u32>,
    pub(crate) action: Action,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct BallView {
    /// `held`, `pass` or `shot`.
    pub state: &'static str,
    /// x, y (height), z, m.
    pub position: [f64; 3],
    pub(crate) holder: Option<String>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct Snapshot {
    pub(crate) tick: u64,
    pub(crate) time_s: f64,
    pub(crate) possession: u64,
    pub(crate) shot_clock_s: f64,
    pub(crate) score: u32,
    pub(crate) ball: BallView,
    pub(crate) agents: Vec<AgentView>,
}
