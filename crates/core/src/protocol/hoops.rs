//! Basketball on the wire: the court, the players, the ball, the score, the events, and
//! what a bot's player perceives.
//!
//! The game shows itself through views defined beside it ([`Player`], [`Ball`],
//! [`Event`]), re-exported here; what only the protocol needs is defined here, converted
//! from the game's own types (the court, the decision rule's parameters). Objects list
//! their keys in alphabetical order, as protocol 2 always has ([`crate::tags`]), and a
//! test reads every object of a frame for it.

use crate::basketball::{self, BeyondHorizon};
pub use crate::basketball::{
    Action, BallState, BallView as Ball, ChosenView, Event, Outcome, PlayerView as Player, Team,
};
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

/// The half court's dimensions and the squares a shooter considers. Points are (x, z)
/// on the floor, m: x from the baseline, z across, the basket on z = 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
pub struct Court {
    /// The backboard's face, m from the baseline (FIBA: 1.2, the ring's centre 0.375 m in
    /// front of it): no shot goes in from behind its plane.
    pub backboard_m: f64,
    /// The centre of the ring above the floor, projected onto it, [x, z], m.
    pub basket: [f64; 2],
    /// Baseline to half-court line, m (FIBA: 14).
    pub length_m: f64,
    /// Side of a square the shooter considers, m.
    pub square_m: f64,
    /// Distance of the three-point line from the basket, m (FIBA: 6.75).
    pub three_point_m: f64,
    /// Sideline to sideline, m (FIBA: 15).
    pub width_m: f64,
}

impl From<&basketball::Court> for Court {
    fn from(c: &basketball::Court) -> Court {
        Court {
            backboard_m: c.backboard_m,
            basket: c.basket.to_array(),
            length_m: c.length_m,
            square_m: c.square_m,
            three_point_m: c.three_point_m,
            width_m: c.width_m,
        }
    }
}

/// The parameters of the decision rule `C_o > C_d + T_s + ε`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
pub struct DecisionParams {
    /// What a square the defender's model does not reach within its horizon counts as.
    pub beyond_horizon: BeyondHorizon,
    /// ε: the margin the defender must be late by, s.
    pub epsilon_s: f64,
    /// T_s: from the decision to shoot until the ball leaves the hands, s.
    pub shot_time_s: f64,
}

impl From<&basketball::DecisionParams> for DecisionParams {
    fn from(d: &basketball::DecisionParams) -> DecisionParams {
        DecisionParams {
            beyond_horizon: d.beyond_horizon,
            epsilon_s: d.epsilon_s,
            shot_time_s: d.shot_time_s,
        }
    }
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
