//! One fielder chasing one ball, tick by tick: see, decide, move, test for a catch.

use super::fielder::{Fielder, FielderConfig};
use super::strategy::{Forecast, StrategyKind};
use super::{CatchZone, OpticalFit};
use crate::physics::Flight;
use glam::DVec2;
use serde::Serialize;

/// Everything about a trial except the ball and the fielder's start.
#[derive(Debug, Clone, Copy, Default)]
pub struct TrialConfig {
    /// The fielder's limits and senses.
    pub fielder: FielderConfig,
    /// Where around the fielder a ball is caught.
    pub zone: CatchZone,
    /// Keep one [`TraceEntry`] a tick (costs an allocation; sweeps leave it off).
    pub record_trace: bool,
}

/// How a trial ended.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Outcome {
    /// Whether the fielder caught the ball.
    pub caught: bool,
    /// When the ball was caught, or when it reached the ground, s.
    pub time_s: f64,
    /// Closest horizontal approach while the ball descended through the catch band, m.
    pub miss_distance_m: f64,
    /// Where the ball's free flight first reaches y = 0, (x, z) in m, even if it was
    /// caught before.
    pub ball_landing: [f64; 2],
}

/// The state of one tick, as `fieldhouse catch --json` prints it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TraceEntry {
    /// Time since the launch, s.
    pub t: f64,
    /// The ball, (x, y, z) in m.
    pub ball: [f64; 3],
    /// The fielder on the ground, (x, z) in m.
    pub fielder: [f64; 2],
    /// tan ψ of the ball as the eye really saw it (before noise).
    pub tan_psi: f64,
    /// Bearing α of the ball, rad from +x toward +z, before noise.
    pub(crate) alpha: f64,
    /// The acceleration achieved over the tick that starts here, m/s².
    pub accel: [f64; 2],
}

/// What one trial measured.
#[derive(Debug, Clone)]
pub struct TrialResult {
    /// The fielder's strategy.
    pub strategy: StrategyKind,
    /// Caught or not, when, and how close.
    pub outcome: Outcome,
    /// Largest acceleration achieved in any tick, m/s².
    pub peak_accel: f64,
    /// Largest speed reached, m/s.
    pub peak_speed: f64,
    /// Time-average of |a| from the first step to the end, m/s².
    pub mean_accel: f64,
    /// Distance the fielder ran, m.
    pub path_length_m: f64,
    /// The fielder's position every tick.
    pub path: Vec<DVec2>,
    /// The straightness measures of what the fielder saw.
    pub(crate) optical: OpticalFit,
    /// One entry a tick when the config records a trace, else empty.
    pub trace: Vec<TraceEntry>,
}

/// A fielder of one strategy against one precomputed flight.
pub struct Trial<'a> {
    /// The ball's flight, sampled every tick; the ground under its first
    /// sample is home plate.
    pub flight: &'a Flight,
    /// The fielder and catch zone.
    pub config: &'a TrialConfig,
}

/// The point and time `flight` descends through the middle of `zone`'s catch band (or
/// lands, if it never does): what the `predictive` fielder is told.
pub fn forecast(flight: &Flight, zone: &CatchZone) -> Forecast {
    let s = flight
        .descending_through(zone.catch_height_m())
        .unwrap_or(flight.landing);
    Forecast {
        point: DVec2::new(s.pos.x, s.pos.z),
        t: s.t,
    }
}

impl Trial<'_> {
    /// The point and time the ball descends through the middle of the catch band: what
    /// the `predictive` fielder is told.
    pub fn forecast(&self) -> Forecast {
        forecast(self.flight, &self.config.zone)
    }

    /// Runs a fielder of `strategy` from `start` ((x, z), m) until it catches the ball or
    /// the flight ends.
    pub fn run(&self, strategy: StrategyKind, start: DVec2) -> TrialResult {
        let (flight, cfg) = (self.flight, self.config);
        let dt = flight.dt;
        let eye = cfg.fielder.perception.eye_height_m;
        let reaction_s = cfg.fielder.limits.reaction_s;
        let home = flight.samples[0].pos;
        let home = DVec2::new(home.x, home.z);
        let mut fielder = Fielder::new(
            strategy,
            start,
            home,
            &cfg.fielder,
            cfg.zone.catch_height_m(),
            dt,
            || self.forecast(),
        );
        let mut path = Vec::with_capacity(flight.samples.len());
        let mut trace = Vec::with_capacity(if cfg.record_trace {
            flight.samples.len()
        } else {
            0
        });
        let mut optical = OpticalFit::default();
        let (mut peak_accel, mut peak_speed, mut accel_sum, mut moving_ticks) =
            (0.0f64, 0.0f64, 0.0, 0usize);
        let mut miss = f64::INFINITY;
        let mut caught_at = None;

        for pair in flight.samples.windows(2) {
            let (ball, next_ball) = (&pair[0], &pair[1]);
            let before = fielder.body.pos;
            path.push(before);
            optical.add(ball.t, ball.pos, before, home, eye);
            let step = fielder.step(ball.t, ball.pos, dt);
            let accel = step.accel.length();
            if ball.t >= reaction_s {
                accel_sum += accel;
                moving_ticks += 1;
            }
            peak_accel = peak_accel.max(accel);
            peak_speed = peak_speed.max(fielder.body.vel.length());
            if cfg.record_trace {
                trace.push(TraceEntry {
                    t: ball.t,
                    ball: ball.pos.to_array(),
                    fielder: before.to_array(),
                    tan_psi: step.sighting.tan_psi,
                    alpha: step.sighting.alpha(),
                    accel: step.accel.to_array(),
                });
            }
            if let Some(pass) = cfg.zone.pass(
                ball.pos,
                next_ball.pos,
                before,
                fielder.body.pos,
                fielder.finishing(),
            ) {
                miss = miss.min(pass.closest_m);
                if let Some(s) = pass.caught_s {
                    caught_at = Some(ball.t + s * dt);
                    break;
                }
            }
        }
        path.push(fielder.body.pos);
        let landing = flight.landing.pos;
        if miss.is_infinite() {
            // The ball never came down through the band (a ball launched below it).
            miss = (DVec2::new(landing.x, landing.z) - fielder.body.pos).length();
        }
        let path_length_m = path.windows(2).map(|w| (w[1] - w[0]).length()).sum();
        TrialResult {
            strategy,
            outcome: Outcome {
                caught: caught_at.is_some(),
                time_s: caught_at.unwrap_or(flight.landing.t),
                miss_distance_m: miss,
                ball_landing: [landing.x, landing.z],
            },
            peak_accel,
            peak_speed,
            mean_accel: accel_sum / moving_ticks.max(1) as f64,
            path_length_m,
            path,
            optical,
            trace,
        }
    }
}
