//! What happens when the ball meets the ground: a bounce that loses energy, then a roll
//! that slows to a stop.

use glam::DVec3;
use serde::Serialize;

/// Contact parameters of a playing surface.
///
/// *Assumptions* (no source at hand measures outfield turf the same way): vertical
/// restitution 0.45, a bounce keeps 70 % of the horizontal speed, rolling friction
/// decelerates at 1.5 m/s² (μ ≈ 0.15), and a ball bouncing up slower than 0.5 m/s rolls.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Ground {
    /// Vertical restitution: the upward speed after a bounce per unit of downward speed
    /// before it.
    pub(crate) restitution: f64,
    /// Share of the horizontal velocity a bounce keeps.
    pub(crate) tangential_keep: f64,
    /// Deceleration of a rolling ball by friction, m/s².
    pub(crate) rolling_decel: f64,
    /// Below this upward speed after a bounce (m/s) the ball stops bouncing and rolls.
    pub(crate) min_bounce_speed: f64,
}

impl Default for Ground {
    fn default() -> Self {
        Ground {
            restitution: 0.45,
            tangential_keep: 0.7,
            rolling_decel: 1.5,
            min_bounce_speed: 0.5,
        }
    }
}

impl Ground {
    /// Velocity just after an impact with velocity `v` (v.y < 0).
    pub fn bounce(&self, v: DVec3) -> DVec3 {
        let up = -v.y * self.restitution;
        let horizontal = DVec3::new(v.x, 0.0, v.z) * self.tangential_keep;
        if up < self.min_bounce_speed {
            horizontal
        } else {
            horizontal + DVec3::new(0.0, up, 0.0)
        }
    }

    /// Velocity of a rolling ball after `dt`: friction opposes motion and never reverses it.
    pub fn roll(&self, v: DVec3, dt: f64) -> DVec3 {
        let horizontal = DVec3::new(v.x, 0.0, v.z);
        let speed = horizontal.length();
        let slowed = speed - self.rolling_decel * dt;
        if slowed <= 0.0 {
            DVec3::ZERO
        } else {
            horizontal * (slowed / speed)
        }
    }
}
