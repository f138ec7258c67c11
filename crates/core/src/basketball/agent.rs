//! An agent on the court: where it is, what it is doing, and the move it is playing.

use super::capability::Stride;
use crate::costmap::AgentPose;
use crate::motion::{Blend, MotionGraph, Walker};
use glam::DVec2;
use schemars::JsonSchema;
use serde::Serialize;

/// Which side a player is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Team {
    /// With the ball: scores.
    Offense,
    /// Without it: defends the basket.
    Defense,
}

/// What an agent is doing: the paper's offensive actions, and the defender's one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
#[schemars(rename = "PlayerAction")]
pub enum Action {
    /// Between possessions, or a move that has run out.
    Standing,
    /// With the ball, toward the goal.
    Maneuver,
    /// With the ball, to the square opponent modelling chose.
    DribbleToShot,
    /// Without the ball: toward the goal, staying open for a pass.
    ReadyForPass,
    /// With the ball: shooting.
    Shoot,
    /// With the ball: passing to a teammate.
    Pass,
    /// The defender: toward the ball.
    Defend,
}

/// A move being played: the strides of a cost-map path, one per data frame, sampled at
/// the tick rate by interpolating between frames.
#[derive(Debug, Clone)]
pub struct Movement {
    strides: Vec<Stride>,
    /// Per stride, the blend its pose shows ([`MotionGraph::blend_on`] along the walk),
    /// so a spectator poses the body as playback would, cuts blended.
    blends: Vec<Option<Blend>>,
    /// Data frames played so far (fractional: ticks need not fall on frames).
    played: f64,
    /// What the move was planned for: the goal on the court and the behaviour.
    pub goal: DVec2,
    pub(crate) behaviour: &'static str,
}

impl Movement {
    /// A move along `strides` on `graph`; `carried` is the blend the body shows at the
    /// first stride (a move that goes on from the node being played goes on with its
    /// blend).
    pub(crate) fn new(
        strides: Vec<Stride>,
        goal: DVec2,
        behaviour: &'static str,
        graph: &MotionGraph,
        carried: Option<Blend>,
    ) -> Movement {
        debug_assert!(!strides.is_empty());
        let mut shown = carried;
        let blends = std::iter::once(carried)
            .chain(strides.windows(2).map(|w| {
                shown = graph.blend_on(shown, w[0].node, w[1].cut);
                shown
            }))
            .collect();
        Movement {
            strides,
            blends,
            played: 0.0,
            goal,
            behaviour,
        }
    }

    /// Plays `frames` more data frames; returns where the body is, the node playing and
    /// the blend its pose shows.
    pub fn advance(&mut self, frames: f64) -> (Walker, u32, Option<Blend>) {
        let last = self.strides.len() - 1;
        self.played = (self.played + frames).min(last as f64);
        let k = (self.played as usize).min(last);
        let f = self.played - k as f64;
        let a = self.strides[k];
        let Some(b) = self.strides.get(k + 1) else {
            return (a.at, a.node, self.blends[k]);
        };
        let facing = a.at.facing.lerp(b.at.facing, f);
        let at = Walker {
            position: a.at.position.lerp(b.at.position, f),
            facing: if facing.length_squared() > 1e-12 {
                facing.normalize()
            } else {
                b.at.facing
            },
        };
        // The pose is the nearer stride's, with its blend.
        let shown = if f < 0.5 { k } else { k + 1 };
        (at, self.strides[shown].node, self.blends[shown])
    }

    pub(crate) fn finished(&self) -> bool {
        self.played >= (self.strides.len() - 1) as f64
    }
}

#[derive(Debug, Clone)]
pub(crate) struct Agent {
    pub(crate) id: String,
    pub(crate) team: Team,
    pub(crate) pose: AgentPose,
    /// The motion-graph node playing, for drawing the body; `None` before it first moves.
    pub node: Option<u32>,
    /// The behaviour whose graph `node` is of: a move with it goes on from `node`.
    pub playing: Option<&'static str>,
    /// The cut `node` is being blended from, if it is.
    pub blend: Option<Blend>,
    pub(crate) action: Action,
    pub(super) movement: Option<Movement>,
    /// When it next decides (the agents re-plan a few times a second).
    pub(super) next_plan_s: f64,
    /// A defender's next steal attempt; an offensive player's first moment it may pass
    /// (so a catch is not passed straight back).
    pub(super) not_before_s: f64,
    /// Seconds left of a shot being taken.
    pub(super) shooting_s: Option<f64>,
}

impl Agent {
    pub(crate) fn new(id: String, team: Team, position: DVec2, heading: f64) -> Agent {
        Agent {
            id,
            team,
            pose: AgentPose { position, heading },
            node: None,
            playing: None,
            blend: None,
            action: Action::Standing,
            movement: None,
            next_plan_s: 0.0,
            not_before_s: 0.0,
            shooting_s: None,
        }
    }

    /// Plays the current move on by `frames` data frames.
    pub(super) fn advance(&mut self, frames: f64) {
        if let Some(m) = &mut self.movement {
            let (at, node, blend) = m.advance(frames);
            self.pose = AgentPose {
                position: at.position,
                heading: at.heading(),
            };
            self.node = Some(node);
            self.blend = blend;
            self.playing = Some(m.behaviour);
            if m.finished() {
                self.movement = None;
            }
        }
    }

    pub(super) fn stop(&mut self) {
        self.movement = None;
    }
}
