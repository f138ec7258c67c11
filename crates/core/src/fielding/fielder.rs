//! A fielder in play: body, senses and strategy, stepped one tick at a time. A catching
//! trial drives one against a precomputed flight; a live match can drive several against
//! its ball the same way.

use super::strategy::{Brain, Forecast, LotReference, Situation, StrategyKind};
use super::{Body, Limits};
use crate::perception::{PerceptionConfig, PerceptionHistory, Sighting};
use glam::{DVec2, DVec3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Everything about a fielder except where it stands and how it decides.
#[derive(Debug, Clone, Copy)]
pub struct FielderConfig {
    /// How fast the body can run, accelerate and react.
    pub limits: Limits,
    /// The eye: its height, delay and noise.
    pub perception: PerceptionConfig,
    /// Seeds the perceptual noise; irrelevant when noise is off.
    pub noise_seed: u64,
    /// When a `lot` fielder takes its reference (other strategies ignore it).
    pub lot_reference: LotReference,
}

impl Default for FielderConfig {
    fn default() -> Self {
        FielderConfig {
            limits: Limits::HUMAN,
            perception: PerceptionConfig::default(),
            noise_seed: 0,
            lot_reference: LotReference::Apex,
        }
    }
}

/// What one tick of a fielder produced.
#[derive(Debug, Clone, Copy)]
pub struct Step {
    /// What the eye really saw (before noise), for traces and plots.
    pub sighting: Sighting,
    /// The acceleration achieved over the tick.
    pub accel: DVec2,
}

/// One fielder: its body, its strategy's memory, its perception history and the noise
/// that blurs what it sees.
#[derive(Debug, Clone)]
pub(crate) struct Fielder {
    pub(crate) body: Body,
    brain: Brain,
    history: PerceptionHistory,
    noise: ChaCha8Rng,
    config: FielderConfig,
    /// Home plate on the ground: the batter, whom every fielder faces.
    home: DVec2,
}

impl Fielder {
    /// A fielder at rest at `start`; `forecast` is consulted only by `predictive`.
    pub(crate) fn new(
        strategy: StrategyKind,
        start: DVec2,
        home: DVec2,
        config: &FielderConfig,
        dt: f64,
        forecast: impl FnOnce() -> Forecast,
    ) -> Fielder {
        Fielder {
            body: Body::at_rest(start),
            brain: Brain::new(strategy, config.lot_reference, forecast),
            history: PerceptionHistory::new(&config.perception, dt),
            noise: ChaCha8Rng::seed_from_u64(config.noise_seed),
            config: *config,
            home,
        }
    }

    /// Looks at the ball (at `ball` at time `t`), decides, and moves for `dt`. Before its
    /// reaction time a fielder watches but does not move.
    pub(crate) fn step(&mut self, t: f64, ball: DVec3, dt: f64) -> Step {
        let (limits, perception) = (&self.config.limits, &self.config.perception);
        let sighting = Sighting::of(t, ball, self.body.pos, perception.eye_height_m);
        self.history.record(
            sighting.blurred(perception.noise_rad, &mut self.noise),
            self.body.pos,
        );
        // The estimate is a fit over the window: only worth making once it can be acted on.
        let command = if t >= limits.reaction_s {
            let percept = self.history.percept(self.body.pos, self.body.vel);
            self.brain.command(&Situation {
                percept: percept.as_ref(),
                body: &self.body,
                limits,
                home: self.home,
                t,
                dt,
            })
        } else {
            DVec2::ZERO
        };
        let accel = self.body.advance(command, limits, dt);
        Step { sighting, accel }
    }
}
