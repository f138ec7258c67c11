//! The trajectory-prediction baseline: know where the ball comes down, run there.

use super::Situation;
use glam::DVec2;

/// Where and when the ball descends through catch height: given to `predictive` only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Forecast {
    /// Where on the ground, (x, z) in m.
    pub point: DVec2,
    /// When, s since the launch.
    pub t: f64,
}

/// Runs to the forecast point in a straight line, time-optimally within the limits.
///
/// From rest, the minimum-time run to a point is straight: full acceleration up to top
/// speed. The wanted speed is the larger of two: the latest-braking speed that stops on
/// the point, √(2·a_max·distance), for a fielder with time to spare; and the speed that
/// gets there exactly when the ball does, distance / time left, for one without (braking
/// would only make it later, so it runs through the point and catches the ball as it
/// passes). Both are capped at top speed. Without limits only the second applies: a
/// constant-speed run that arrives just in time.
#[derive(Debug, Clone)]
pub struct Predictive {
    forecast: Forecast,
}

impl Predictive {
    /// A fielder that runs to `forecast`.
    pub(crate) fn new(forecast: Forecast) -> Predictive {
        Predictive { forecast }
    }

    /// What it was told.
    pub(crate) fn forecast(&self) -> &Forecast {
        &self.forecast
    }

    /// The acceleration wanted this tick, m/s².
    pub(crate) fn command(&mut self, s: &Situation) -> DVec2 {
        run_to(&self.forecast, s)
    }
}

/// The acceleration, m/s², that takes the fielder of `s` to `goal` by its time, as
/// quickly as its limits allow (see [`Predictive`]).
pub(crate) fn run_to(goal: &Forecast, s: &Situation) -> DVec2 {
    let to_go = goal.point - s.body.pos;
    let distance = to_go.length();
    let time_left = goal.t - s.t;
    let on_time = distance / time_left.max(s.dt);
    let stopping = (2.0 * s.limits.max_accel * distance).sqrt();
    let wanted_speed = s.limits.max_speed.min(if s.limits.is_limited() {
        stopping.max(on_time)
    } else {
        on_time
    });
    let wanted = to_go.normalize_or_zero() * wanted_speed.min(distance / s.dt);
    (wanted - s.body.vel) / s.dt
}
