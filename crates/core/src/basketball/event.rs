//! What a game reports: events as they happen, and snapshots of the whole court.

use super::agent::{Action, Team};
use super::decision::Chosen;
use super::safe::SafeSquares;
use crate::tags;
use schemars::JsonSchema;
use serde::Serialize;

/// How a possession ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
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
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[serde(untagged)]
#[schemars(rename = "HoopsEvent", transform = tags::one_of)]
pub enum Event {
    // The variants' docs describe the events in the schema: their structs are inlined
    // there, and their own docs only point back here.
    /// An agent chose a new action (or, with the ball, a new shooting square). `chosen`
    /// is that of `basketball-decide`; `safe` the squares that satisfied the rule, as a
    /// bitmap, so a spectator can outline them (`None` when none did, or for a play that
    /// chose no square).
    Decision(Decided),
    /// A pass is thrown.
    Pass(Passed),
    /// A pass reached its receiver, who now has the ball.
    PassCaught(PassCaught),
    /// The ball is away (or was blocked on the way up).
    Shot(Shot),
    /// A possession is over; the next one starts at once.
    PossessionEnded(PossessionEnded),
}

/// What an [`Event::Decision`] says.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[schemars(inline)]
pub struct Decided {
    /// What it does now.
    pub action: Action,
    /// The agent that decided.
    pub agent: String,
    /// The shooting square chosen, with C_o, C_d and the shot's chance.
    pub chosen: Option<ChosenView>,
    /// Always `decision`.
    pub kind: tags::Decision,
    /// Why, for people: the rule or threshold that decided it, or `bot order`.
    pub reason: String,
    /// The squares that satisfied the rule.
    pub safe: Option<SafeSquares>,
}

/// What an [`Event::Pass`] says.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[schemars(inline)]
pub struct Passed {
    /// The passer.
    pub from: String,
    /// Always `pass`.
    pub kind: tags::Pass,
    /// The teammate it is thrown to.
    pub to: String,
}

/// What an [`Event::PassCaught`] says.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[schemars(inline)]
pub struct PassCaught {
    /// The receiver.
    pub by: String,
    /// Always `pass_caught`.
    pub kind: tags::PassCaught,
}

/// What an [`Event::Shot`] says.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[schemars(inline)]
pub struct Shot {
    /// Whether a defender blocked it before the ball was away (then `made` is false).
    pub blocked: bool,
    /// The shooter.
    pub by: String,
    /// Distance from there to the basket, m.
    pub distance_m: f64,
    /// Where it shot from on the court, (x, z), m.
    pub from: [f64; 2],
    /// Always `shot`.
    pub kind: tags::Shot,
    /// Whether it went in.
    pub made: bool,
    /// Points scored: 2 or 3 if made, else 0.
    pub points: u32,
    /// The chance the shot had of going in ([`ShotModel`](super::ShotModel)).
    pub success: f64,
}

/// What an [`Event::PossessionEnded`] says.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[schemars(inline)]
pub struct PossessionEnded {
    /// From the start of the possession to the moment its outcome was settled.
    pub duration_s: f64,
    /// Always `possession_ended`.
    pub kind: tags::PossessionEnded,
    /// How it ended.
    pub outcome: Outcome,
    /// Passes thrown during it.
    pub passes: u32,
    /// Points it scored.
    pub points: u32,
    /// Which possession, counted from 0.
    pub possession: u64,
}

/// A decision's `chosen` as frames carry it: without T_s and ε, which are the match's
/// (the hello's `field.decision`) and the same in every decision.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
pub struct ChosenView {
    /// Present, as `true`, when `c_o` is the horizon of a map that does not reach the
    /// square: the defender needs at least that long.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub beyond_horizon: bool,
    /// C_d: the shooter's dribbling time to the square, s.
    pub c_d: f64,
    /// C_o: the defenders' soonest time to the square, s.
    pub c_o: f64,
    /// The square's centre on the court, [x, z], m.
    pub cell: [f64; 2],
    /// True when the shooter already stands on the square: shoot now.
    pub here: bool,
    /// The chance a shot from the square goes in.
    pub success: f64,
}

impl From<&Chosen> for ChosenView {
    fn from(c: &Chosen) -> ChosenView {
        ChosenView {
            beyond_horizon: c.beyond_horizon,
            c_d: c.c_d,
            c_o: c.c_o,
            cell: c.cell,
            here: c.here,
            success: c.success,
        }
    }
}

/// A player in a frame: where it is, what it does, and the motion it plays.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[schemars(rename = "Player")]
pub struct PlayerView<'a> {
    /// What it is doing.
    pub action: Action,
    /// The behaviour whose motion graph it walks: `dribble`, `run` or `defense`.
    pub behaviour: &'static str,
    /// Present while the pose blends across a cut (protocol 3): the node of the clip being
    /// left and the weight of `node`'s pose, as the motion graph's playback blends them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blend: Option<PoseBlend>,
    /// Present, as `bot`, while a connected bot moves the player.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub controller: Option<tags::Bot>,
    /// Present when `node` is of another behaviour's graph than `behaviour` (protocol 3):
    /// a player standing after a move of another behaviour still shows that move's last
    /// pose.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub graph: Option<&'static str>,
    /// Radians from +x toward +z.
    pub heading: f64,
    /// Its id.
    pub id: &'a str,
    /// The motion graph node it is playing, while it moves (and, once it stops, the last
    /// one it played).
    pub node: Option<u32>,
    /// [x, z] on the court, m.
    pub position: [f64; 2],
    /// Not in frames: a player's team never changes, and the `hello` lists it.
    #[serde(skip)]
    pub(crate) team: Team,
}

/// A pose blended across a cut: `[from, weight]`, the node of the clip being left and
/// how much of the node being entered shows (0 to 1). A client poses the body as
/// `pose(from) + weight × (pose(node) − pose(from))`, joint by joint, from the poses
/// `GET /api/motion/{behaviour}` serves. An array, since frames go 30 times a second to
/// every spectator.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
pub struct PoseBlend(pub u32, pub f64);

/// Where the ball is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
#[schemars(rename = "HoopsBallState")]
pub enum BallState {
    /// A player has it (`holder`).
    Held,
    /// In the air between two players.
    Pass,
    /// On its way to the basket.
    Shot,
}

/// The ball in a basketball frame.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[schemars(rename = "HoopsBall")]
pub struct BallView<'a> {
    /// The player holding it, if one is.
    pub holder: Option<&'a str>,
    /// [x, y, z], m, y up.
    pub position: [f64; 3],
    /// `held`, `pass` or `shot`.
    pub state: BallState,
}

/// The court at one tick, as a game shows it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Snapshot<'a> {
    pub(crate) tick: u64,
    pub(crate) possession: u64,
    pub(crate) shot_clock_s: f64,
    pub(crate) score: u32,
    pub(crate) ball: BallView<'a>,
    pub(crate) agents: Vec<PlayerView<'a>>,
}
