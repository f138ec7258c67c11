//! Everything that decides a basketball game besides the motion data, with the defaults
//! of the paper's setting (two offensive agents against one defender).

use super::capability::DefenderMotion;
use super::court::Court;
use super::decision::DecisionParams;
use super::parametric::{Isotropic, Kinematic};
use super::shot::ShotModel;
use crate::names::{lookup, UnknownName};
use serde::{Deserialize, Serialize};
use std::str::FromStr;

/// How the offense decides.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Brain {
    /// Straight toward the goal; pass when the defender comes within a fixed radius;
    /// shoot from a fixed range.
    Simple,
    /// The cheapest heading from the cost map; pass when the defender's cost map says it
    /// is about to arrive; shoot from the square opponent modelling picks.
    Costmap,
}

impl Brain {
    /// The offense's name, as users write it and reports print it.
    pub fn name(self) -> &'static str {
        match self {
            Brain::Simple => "simple",
            Brain::Costmap => "costmap",
        }
    }
}

impl FromStr for Brain {
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        lookup(
            "offense",
            s,
            &["simple", "costmap"],
            &[Brain::Simple, Brain::Costmap],
        )
    }
}

/// How the shooter models a defender's time to reach a square (C_o), for the shot and
/// for the pass: the ablations of the paper's claim that modelling the opponent with
/// *human* capability pays.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum DefenderModel {
    /// The defender's own maps (the behaviour it moves with), from the state it is in:
    /// exact by construction, since the defender moves on that very graph. An upper
    /// bound: a real opponent is never known that well.
    Own,
    /// Another behaviour's maps, embedded at the defender's pose and state: `run` is the
    /// paper's ("without prior knowledge of the defender", the shooter's own
    /// non-dribbling maps); another subject's are another human's capability.
    Maps {
        /// The behaviour whose maps model the defender.
        behaviour: DefenderMotion,
    },
    /// Reaction, turn, acceleration and a top speed each way ([`Kinematic`]), from the
    /// defender's pose and velocity: what a game AI would use, fitted to maps.
    Kinematic(Kinematic),
    /// A reaction time and one speed in every direction ([`Isotropic`]): a defender that
    /// turns for free.
    Isotropic(Isotropic),
    /// No model at all: every square in range is safe (shoot from the best one), and
    /// the pass falls back to the `simple` offense's fixed radius.
    None,
}

impl DefenderModel {
    /// The model's name, as reports print it: `own`, `maps:BEHAVIOUR`, `kinematic`,
    /// `isotropic`, `none`.
    pub fn name(self) -> String {
        match self {
            DefenderModel::Own => "own".into(),
            DefenderModel::Maps { behaviour } => format!("maps:{}", behaviour.name()),
            DefenderModel::Kinematic(_) => "kinematic".into(),
            DefenderModel::Isotropic(_) => "isotropic".into(),
            DefenderModel::None => "none".into(),
        }
    }
}

/// Where the defender heads.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DefenderAim {
    /// The ball, where it is: the paper's defender "simply tries to move toward the
    /// ball".
    #[default]
    Ball,
    /// Where the ball handler is dribbling to (the ball, if it is not dribbling to a
    /// square): a defender that reads the play, the opponent the shooter's rule assumes,
    /// one that races it to the square it shoots from.
    Goal,
}

impl DefenderAim {
    /// The aim's name, as users write it.
    pub fn name(self) -> &'static str {
        match self {
            DefenderAim::Ball => "ball",
            DefenderAim::Goal => "goal",
        }
    }
}

impl FromStr for DefenderAim {
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        lookup(
            "defender aim",
            s,
            &["ball", "goal"],
            &[DefenderAim::Ball, DefenderAim::Goal],
        )
    }
}

/// The defender's reach and how often it wins the ball.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DefenderParams {
    /// How close (m, root to root or root to ball) it must be to steal or block.
    pub reach_m: f64,
    /// Chance one steal attempt on a dribbler or a pass in flight succeeds.
    pub steal_success: f64,
    /// Chance it blocks a shot it reaches before the ball is away.
    pub block_success: f64,
    /// Seconds between its steal attempts on the same dribbler.
    pub attempt_every_s: f64,
    /// The behaviour it moves with.
    pub motion: DefenderMotion,
    /// Where it heads.
    #[serde(default)]
    pub aim: DefenderAim,
}

impl Default for DefenderParams {
    fn default() -> Self {
        DefenderParams {
            reach_m: 1.0,
            steal_success: 0.3,
            block_success: 0.6,
            attempt_every_s: 1.0,
            motion: DefenderMotion::Defense,
            aim: DefenderAim::Ball,
        }
    }
}

/// The `simple` offense's fixed thresholds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SimpleParams {
    /// Pass when a defender is this close, m.
    pub pass_radius_m: f64,
    /// Shoot from this close to the basket, m.
    pub shoot_range_m: f64,
}

impl Default for SimpleParams {
    fn default() -> Self {
        SimpleParams {
            pass_radius_m: 2.0,
            shoot_range_m: 5.0,
        }
    }
}

/// A game's whole setting; the default is the paper's two offensive players against one
/// defender, at 60 Hz, with the `costmap` offense.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GameParams {
    /// Ticks per second of game time, Hz.
    pub tick_hz: f64,
    /// How the offense decides.
    pub offense: Brain,
    /// Offensive players; the first starts each possession with the ball.
    pub offense_players: usize,
    /// Defenders.
    pub defenders: usize,
    /// The half court.
    pub court: Court,
    /// Shot success against distance.
    pub shot: ShotModel,
    /// T_s and ε of opponent modelling.
    pub decision: DecisionParams,
    /// The defenders' reach and chances.
    pub defender: DefenderParams,
    /// The `simple` offense's thresholds.
    pub simple: SimpleParams,
    /// The `costmap` offense passes when a defender can reach it within this, s (its
    /// passing radius, measured in the defender's time rather than metres).
    pub pass_pressure_s: f64,
    /// How the `costmap` offense models the defender when it picks a square to shoot
    /// from, and when it decides whether it is pressed.
    pub shot_model: DefenderModel,
    /// How the `costmap` offense models the defender when it decides whether to pass
    /// (see `shot_model`).
    pub pass_model: DefenderModel,
    /// The shot clock each possession starts with, s (FIBA: 24).
    pub shot_clock_s: f64,
    /// How often agents decide, s.
    pub replan_s: f64,
    /// Speed of a pass, m/s.
    pub pass_speed_m_s: f64,
    /// Speed of a shot toward the ring, m/s (only how long spectators see it fly: the
    /// outcome is settled at release).
    pub shot_speed_m_s: f64,
    /// Seeds every random draw: the possessions' starts and their shots, steals and
    /// blocks. The same seed gives the same game.
    pub seed: u64,
}

impl Default for GameParams {
    fn default() -> Self {
        GameParams {
            tick_hz: 60.0,
            offense: Brain::Costmap,
            offense_players: 2,
            defenders: 1,
            court: Court::default(),
            shot: ShotModel::default(),
            decision: DecisionParams::default(),
            defender: DefenderParams::default(),
            simple: SimpleParams::default(),
            pass_pressure_s: 1.0,
            shot_model: DefenderModel::Own,
            pass_model: DefenderModel::Own,
            shot_clock_s: 24.0,
            replan_s: 0.25,
            pass_speed_m_s: 8.0,
            shot_speed_m_s: 7.0,
            seed: 1,
        }
    }
}
