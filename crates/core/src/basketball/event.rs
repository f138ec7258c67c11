//! What a game reports: events as they happen, and snapshots of the whole court.

use super::agent::{Action, Team};
use super::decision::Chosen;
use super::safe::SafeSquares;
use serde::Serialize;

/// How a possession ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// A shot went in.
    Made,
    /// A shot missed (there are no rebounds).
    Missed,
    /// A defender blocked the shot before the ball was away.
    Blocked,
    /// A defender stole the ball off the dribble.
    Stolen,
    /// A defender intercepted a pass.
    Intercepted,
    /// The shot clock ran out before a shot was away.
    ShotClock,
}

/// Something that happened in a tick of [`Game::step`](super::Game::step), as frames
/// carry it (`kind` names the variant). Agents are named by id.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Event {
    /// An agent chose a new action (or, with the ball, a new shooting square). `chosen`
    /// is that of `basketball-decide`; `safe` the squares that satisfied the rule, as a
    /// bitmap, so a spectator can outline them (`None` when none did, or for a play that
    /// chose no square).
    Decision {
        /// The agent that decided.
        agent: String,
        /// What it does now.
        action: Action,
        /// Why, for people: the rule or threshold that decided it, or `bot order`.
        reason: String,
        /// The shooting square chosen, with C_o, C_d and the shot's chance.
        #[serde(serialize_with = "chosen_on_the_wire")]
        chosen: Option<Chosen>,
        /// The squares that satisfied the rule.
        safe: Option<SafeSquares>,
    },
    /// A pass is thrown.
    Pass {
        /// The passer.
        from: String,
        /// The teammate it is thrown to.
        to: String,
    },
    /// A pass reached its receiver, who now has the ball.
    PassCaught {
        /// The receiver.
        by: String,
    },
    /// The ball is away (or was blocked on the way up).
    Shot {
        /// The shooter.
        by: String,
        /// Where it shot from on the court, (x, z), m.
        from: [f64; 2],
        /// Distance from there to the basket, m.
        distance_m: f64,
        /// The chance the shot had of going in ([`ShotModel`](super::ShotModel)).
        success: f64,
        /// Whether it went in.
        made: bool,
        /// Whether a defender blocked it before the ball was away (then `made` is false).
        blocked: bool,
        /// Points scored: 2 or 3 if made, else 0.
        points: u32,
    },
    /// A possession is over; the next one starts at once.
    PossessionEnded {
        /// Which possession, counted from 0.
        possession: u64,
        /// How it ended.
        outcome: Outcome,
        /// Points it scored.
        points: u32,
        /// From the start of the possession to the moment its outcome was settled.
        duration_s: f64,
        /// Passes thrown during it.
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
    pub(crate) team: Team,
    pub(crate) behaviour: &'static str,
    pub(crate) position: [f64; 2],
    /// Radians from +x toward +z.
    pub(crate) heading: f64,
    pub(crate) node: Option<u32>,
    pub(crate) action: Action,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct BallView {
    /// `held`, `pass` or `shot`.
    pub(crate) state: &'static str,
    /// x, y (height), z, m.
    pub(crate) position: [f64; 3],
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
