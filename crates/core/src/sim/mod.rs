//! The simulation of a whole match, whatever the sport: one [`World`] that steps a tick
//! at a time, reports what happened, shows its state, and takes bots' commands. Pure
//! and deterministic like the rest of the core: the server's match task drives it.
//!
//! * [`scenario`]: what a match is made of, checked field by field.
//! * `fly`: baseball and cricket fly balls with fielders: the play loop, with its
//!   scenario checks (`fly/setup.rs`) and its wire shapes (`fly/wire.rs`) beside it.
//! * `hoops`: basketball, the core's game with a line-up from the scenario.

mod fly;
mod hoops;
pub mod scenario;

#[cfg(test)]
mod hostile_tests;
#[cfg(test)]
mod time_limits_tests;

pub use scenario::{
    AgentSpec, LaunchSpec, LimitsSpec, Mode, Options, Scenario, ScenarioError, Sport,
};

pub use crate::protocol::Action;

/// The simulation's version, which replay headers record: bumped whenever the same
/// scenario and seed play differently, so a replay only the old simulation can
/// re-simulate says so instead of failing at some tick without a reason.
///
/// 1. Up to fieldhouse 0.1.0 (headers without `simulation`).
/// 2. Fielders estimate the ball's path by a least-squares fit over their looks instead
///    of differencing the last two or three (baseball and cricket play differently;
///    basketball does not).
/// 3. Basketball players move with more of the capture (every clip mirrored, subject
///    102's stance-to-stance slide, zigzag, spin, go-right and pivoting) on graphs whose
///    cuts are held to the capture's own smoothness; no shot goes in from behind the
///    backboard, and no square the shot clock cannot allow is chosen (fly balls play as
///    in version 2).
/// 4. Fielders perceive from angles: tan ψ and the bearing fitted by quadratics over
///    their looks instead of the ball's path placed in space (baseball and cricket play
///    differently by fractions of a millimetre a tick; basketball plays as in version 3).
pub const VERSION: u32 = 4;

use crate::basketball::{Capabilities, Order};
use crate::protocol::{Agent, AgentInfo, Ball, Event, Field, MatchInfo, Score, Sensed};
use fly::{FielderOrder, FlyWorld};
use glam::DVec2;
use hoops::HoopsWorld;
use std::sync::Arc;

/// What a fly-ball match says of its motion: its fielders move by their strategies, with
/// no motion capture.
pub const NO_MOTION: &str = "none (fly-ball fielders use no motion capture)";

enum Inner {
    Fly(Box<FlyWorld>),
    Hoops(Box<HoopsWorld>),
}

/// One match's world, whatever the sport: built from a scenario, stepped a tick at a
/// time, commanded by bots.
pub struct World {
    sport: Sport,
    tick_hz: f64,
    end_tick: Option<u64>,
    inner: Inner,
}

impl World {
    /// Builds the world a scenario describes. Basketball needs the motion capabilities
    /// (built once by whoever runs matches).
    pub fn new(s: &Scenario, caps: Option<Arc<Capabilities>>) -> Result<World, ScenarioError> {
        s.check()?;
        let inner = match s.sport {
            Sport::Baseball | Sport::Cricket => Inner::Fly(Box::new(FlyWorld::new(s)?)),
            Sport::Basketball => {
                let caps = caps.ok_or_else(|| {
                    ScenarioError::at(
                        "sport",
                        "basketball needs the motion data, which is not loaded",
                    )
                })?;
                Inner::Hoops(Box::new(HoopsWorld::new(s, caps)?))
            }
        };
        Ok(World {
            sport: s.sport,
            tick_hz: s.tick_hz,
            end_tick: s.duration_s.map(|d| (d * s.tick_hz).round() as u64),
            inner,
        })
    }

    /// Ticks played since the start (0 before the first step).
    pub fn tick(&self) -> u64 {
        match &self.inner {
            Inner::Fly(w) => w.tick(),
            Inner::Hoops(w) => w.game.tick(),
        }
    }

    /// Match time, s: ticks played over `tick_hz`.
    pub fn time_s(&self) -> f64 {
        self.tick() as f64 / self.tick_hz
    }

    /// Advances one tick, appending the events that happened.
    pub fn step(&mut self, events: &mut Vec<Event>) {
        match &mut self.inner {
            Inner::Fly(w) => w.step(events),
            Inner::Hoops(w) => w.step(events),
        }
    }

    /// Whether the match has reached its end (its duration, or its possessions).
    pub fn finished(&self) -> bool {
        self.end_tick.is_some_and(|end| self.tick() >= end)
            || match &self.inner {
                Inner::Fly(w) => w.finished(),
                Inner::Hoops(w) => w.finished(),
            }
    }

    /// The agents' ids, in the order every index `k` refers to.
    pub fn agent_ids(&self) -> Vec<String> {
        match &self.inner {
            Inner::Fly(w) => w.agent_ids().map(str::to_string).collect(),
            Inner::Hoops(w) => w.game.agents().iter().map(|a| a.id.clone()).collect(),
        }
    }

    /// Everything static about the match, as `hello` shows it: `scenario`'s (which
    /// built this world) with the match's id, how it is paced, and where its motion came
    /// from: `motion_source` (the [`MotionSource`](crate::motion::MotionSource) in words)
    /// for basketball, [`NO_MOTION`] for fly balls, whose fielders move by their
    /// strategies alone.
    pub fn match_info(
        &self,
        id: String,
        scenario: &Scenario,
        mode: Mode,
        motion_source: String,
    ) -> MatchInfo {
        MatchInfo {
            id,
            name: scenario.name.clone(),
            sport: scenario.sport.name(),
            mode: mode.name(),
            seed: scenario.seed,
            tick_hz: scenario.tick_hz,
            frame_hz: scenario.frame_hz,
            perception_every_ticks: self.perception_every_ticks(),
            field: self.field(),
            agents: self.agents_info(),
            motion_source: match &self.inner {
                Inner::Fly(_) => NO_MOTION.to_string(),
                Inner::Hoops(_) => motion_source,
            },
        }
    }

    /// The static description of the field.
    pub fn field(&self) -> Field {
        match &self.inner {
            Inner::Fly(w) => w.field(),
            Inner::Hoops(w) => w.field(),
        }
    }

    /// Each agent's static description (id, team, strategy).
    pub fn agents_info(&self) -> Vec<AgentInfo> {
        match &self.inner {
            Inner::Fly(w) => w.agents_info(),
            Inner::Hoops(w) => w.agents_info(),
        }
    }

    /// The state now: the ball, every agent, the score.
    pub fn state(&self) -> (Ball<'_>, Vec<Agent<'_>>, Score) {
        match &self.inner {
            Inner::Fly(w) => w.state(),
            Inner::Hoops(w) => w.state(),
        }
    }

    /// Bots hear from their agent every this many ticks: fielders every tick, basketball
    /// players at each of their decisions.
    pub fn perception_every_ticks(&self) -> u64 {
        match &self.inner {
            Inner::Fly(_) => 1,
            Inner::Hoops(w) => ((w.game.params().replan_s * self.tick_hz).round() as u64).max(1),
        }
    }

    /// What agent `k` perceives now.
    pub fn perception(&self, k: usize) -> Sensed<'_> {
        match &self.inner {
            Inner::Fly(w) => Sensed::Fielder(w.perception(k)),
            Inner::Hoops(w) => w.perception(k),
        }
    }

    /// Hands agent `k` to a bot or back to its built-in brain.
    pub fn set_controlled(&mut self, k: usize, by_bot: bool) {
        match &mut self.inner {
            Inner::Fly(w) => w.set_controlled(k, by_bot),
            Inner::Hoops(w) => w.game.set_controlled(k, by_bot),
        }
    }

    /// A bot's command for agent `k`: accepted (carried out from the next tick), or the
    /// reason it is impossible. Nothing non-finite ever reaches the world.
    pub fn command(&mut self, k: usize, action: &Action) -> Result<(), String> {
        let point = |p: [f64; 2]| {
            let v = DVec2::from_array(p);
            if v.is_finite() {
                Ok(v)
            } else {
                Err("coordinates must be finite numbers".to_string())
            }
        };
        let wrong = |sport: Sport| {
            Err(format!(
                "{} is not a {} action",
                action.name(),
                sport.name()
            ))
        };
        match &mut self.inner {
            Inner::Fly(w) => match action {
                Action::Accelerate { accel } => {
                    w.order(k, FielderOrder::Accelerate(point(*accel)?))
                }
                Action::RunTo { target } => w.order(k, FielderOrder::RunTo(point(*target)?)),
                Action::Stand {} => w.order(k, FielderOrder::Stand),
                _ => wrong(self.sport),
            },
            Inner::Hoops(w) => match action {
                Action::MoveTo { target } => w.order(k, Order::MoveTo(point(*target)?)),
                Action::Pass { to } => {
                    let to = w
                        .game
                        .agents()
                        .iter()
                        .position(|a| a.id == *to)
                        .ok_or_else(|| format!("no agent \"{to}\""))?;
                    w.order(k, Order::Pass { to })
                }
                Action::Shoot {} => w.order(k, Order::Shoot),
                Action::Stand {} => w.order(k, Order::Stand),
                _ => wrong(self.sport),
            },
        }
    }

    /// The result so far (the score).
    pub fn result(&self) -> Score {
        match &self.inner {
            Inner::Fly(w) => Score::Fly(w.score()),
            Inner::Hoops(w) => Score::Hoops(w.score()),
        }
    }
}
