//! A fielder in play: body, senses and strategy, stepped one tick at a time. A catching
//! trial drives one against a precomputed flight; a live match can drive several against
//! its ball the same way.

use super::strategy::{run_to, Brain, Forecast, LotReference, Situation, StrategyKind};
use super::{terminal, Body, Limits};
use crate::perception::{PerceptionConfig, PerceptionHistory, Senses, Sighting};
use glam::{DVec2, DVec3};

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
    /// How long before the ball comes down the fielder stops steering by its law and
    /// finishes the catch (a run to where it judges the ball comes down, and a lunge), as
    /// it judges it, s; 0: never.
    pub terminal_s: f64,
}

impl Default for FielderConfig {
    fn default() -> Self {
        FielderConfig {
            limits: Limits::HUMAN,
            perception: PerceptionConfig::default(),
            noise_seed: 0,
            lot_reference: LotReference::Apex,
            terminal_s: 0.0,
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

/// One fielder: its body, its strategy's memory, its senses and what they told it.
#[derive(Debug, Clone)]
pub(crate) struct Fielder {
    pub(crate) body: Body,
    brain: Brain,
    history: PerceptionHistory,
    senses: Senses,
    config: FielderConfig,
    /// Home plate on the ground: the batter, whom every fielder faces.
    home: DVec2,
    /// How it finishes the catch, and whether it has begun to.
    finish: Finish,
}

impl Fielder {
    /// A fielder at rest at `start` that takes balls at `catch_height_m`; `forecast` is
    /// consulted only by `predictive`.
    pub(crate) fn new(
        strategy: StrategyKind,
        start: DVec2,
        home: DVec2,
        config: &FielderConfig,
        catch_height_m: f64,
        dt: f64,
        forecast: impl FnOnce() -> Forecast,
    ) -> Fielder {
        Fielder {
            body: Body::at_rest(start),
            brain: Brain::new(strategy, config.lot_reference, forecast),
            history: PerceptionHistory::new(&config.perception, dt),
            senses: Senses::new(&config.perception, config.noise_seed, dt),
            config: *config,
            home,
            finish: Finish {
                lead_s: config.terminal_s,
                height_above_eye: catch_height_m - config.perception.eye_height_m,
                finishing: false,
            },
        }
    }

    /// Whether the fielder is in its terminal phase: finishing the catch, and lunging.
    pub(crate) fn finishing(&self) -> bool {
        self.finish.finishing
    }

    /// Looks at the ball (at `ball` at time `t`), decides, and moves for `dt`. Before its
    /// reaction time a fielder watches but does not move.
    pub(crate) fn step(&mut self, t: f64, ball: DVec3, dt: f64) -> Step {
        let (limits, eye) = (self.config.limits, self.config.perception.eye_height_m);
        let sighting = Sighting::of(t, ball, self.body.pos, eye);
        let look = self.senses.look(&sighting, self.body.pos, self.body.vel);
        self.history.record(look);
        // The estimate is a fit over the window: only worth making once it can be acted on.
        let command = if t >= limits.reaction_s {
            let percept =
                self.history
                    .percept(self.body.pos, self.body.vel, self.senses.rate_errors());
            let situation = Situation {
                percept: percept.as_ref(),
                body: &self.body,
                limits: &limits,
                home: self.home,
                t,
                dt,
            };
            // The law runs to the end, so whatever it remembers stays current.
            let by_law = self.brain.command(&situation);
            self.finish
                .command(&self.brain, &situation)
                .unwrap_or(by_law)
        } else {
            DVec2::ZERO
        };
        let accel = self.body.advance(command, &limits, dt);
        Step { sighting, accel }
    }
}

/// When and where a fielder finishes its catch.
#[derive(Debug, Clone)]
struct Finish {
    /// How long before the ball is due the terminal phase starts, s (0: never).
    lead_s: f64,
    /// The catch height relative to the eye, m.
    height_above_eye: f64,
    /// Whether it has begun (and may lunge).
    finishing: bool,
}

impl Finish {
    /// The terminal phase's command, once the fielder judges the ball is due within
    /// `lead_s` (and from then on `finishing`); `None` before then or while it cannot
    /// judge where. `predictive` keeps running to its forecast, and finishes (lunges) on
    /// its time.
    fn command(&mut self, brain: &Brain, s: &Situation) -> Option<DVec2> {
        if self.lead_s <= 0.0 {
            return None;
        }
        if let Brain::Predictive(p) = brain {
            self.finishing |= p.forecast().t - s.t <= self.lead_s;
            return None;
        }
        let due = terminal::arrival(s.percept?, s.body.pos, s.body.vel, self.height_above_eye)?;
        self.finishing |= due.t - s.t <= self.lead_s;
        self.finishing.then(|| run_to(&due, s))
    }
}
