//! Basketball on the wire: the court, the players, the ball, the score, the events, and
//! what a bot's player perceives.
//!
//! The game shows itself through views defined beside it ([`Player`], [`Ball`],
//! [`Event`]), re-exported here; what only the protocol needs is defined
//! here. Objects list their keys in alphabetical order, as protocol 2 always has
//! ([`crate::tags`]).

pub use crate::basketball::{
    Action, BallState, BallView as Ball, ChosenView, Event, Outcome, PlayerView as Player, Team,
};
use crate::basketball::{Court, DecisionParams};
use crate::tags;
use schemars::JsonSchema;
use serde::Serialize;

/// The court as a client draws it, and the match's constants of the decision rule.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[schemars(rename = "BasketballField")]
pub struct Field {
    /// The half court and the squares a shooter considers.
    pub court: Court,
    /// T_s and ε of the rule `C_o > C_d + T_s + ε`: the same in every decision, so
    /// decisions leave them out.
    pub decision: DecisionParams,
    /// How defenders move: the footwork of their motion graph.
    pub defender_motion: &'static str,
    /// Always `basketball`.
    pub kind: tags::Basketball,
    /// The offense's brain.
    pub offense: &'static str,
    /// The shot clock, s.
    pub shot_clock_s: f64,
}

/// A player as `hello` lists it.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct PlayerInfo {
    /// Its id.
    pub id: String,
    /// Its team's brain (offense) or footwork (defense).
    pub strategy: &'static str,
    /// Its side.
    pub team: Team,
}

/// The score of a basketball match.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
#[schemars(rename = "HoopsScore")]
pub struct Score {
    /// Points scored so far.
    pub points: u32,
    /// The possession being played, counted from 0.
    pub possession: u64,
    /// Time left on the shot clock, s.
    #[schemars(range(min = 0))]
    pub shot_clock_s: f64,
}

/// What a bot's player perceives: the whole court as a player sees it.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[schemars(rename = "PlayerPerception")]
pub struct Sensed<'a> {
    /// Every player, the perceiving one included.
    pub agents: Vec<Seen<'a>>,
    /// The ball.
    pub ball: Ball<'a>,
    /// The basket, [x, z], m.
    pub basket: [f64; 2],
    /// Whether the perceiving player holds the ball.
    pub has_ball: bool,
    /// The perceiving player's id.
    #[serde(rename = "self")]
    pub me: &'a str,
    /// Time left on the shot clock, s.
    pub shot_clock_s: f64,
    /// The perceiving player's team.
    pub team: Team,
}

/// Another player (or oneself) as a player sees it.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[schemars(rename = "SeenPlayer")]
pub struct Seen<'a> {
    /// What it is doing.
    pub action: Action,
    /// Radians from +x toward +z.
    pub heading: f64,
    /// Its id.
    pub id: &'a str,
    /// [x, z] on the court, m.
    pub position: [f64; 2],
    /// Its side.
    pub team: Team,
}

impl<'a> From<&Player<'a>> for Seen<'a> {
    fn from(p: &Player<'a>) -> Seen<'a> {
        Seen {
            action: p.action,
            heading: p.heading,
            id: p.id,
            position: p.position,
            team: p.team,
        }
    }
}
