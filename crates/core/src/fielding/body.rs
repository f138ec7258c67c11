//! A fielder's body: a point on the ground with a human's speed, acceleration and
//! reaction time.

use crate::names::{lookup, UnknownName};
use glam::DVec2;
use serde::Serialize;
use std::str::FromStr;

/// Physical limits of a fielder. `f64::INFINITY` means no limit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Limits {
    /// Top running speed, m/s.
    pub max_speed: f64,
    /// Largest acceleration the fielder can achieve, m/s² (braking and turning included).
    pub max_accel: f64,
    /// Time from the hit to the first step, s.
    pub reaction_s: f64,
}

impl Limits {
    /// Default human limits: 8.5 m/s (between the MLB average sprint of 8.2 m/s and an
    /// elite 9 m/s), 4.5 m/s² (Höfer et al. 2018), 0.3 s to react.
    pub const HUMAN: Limits = Limits {
        max_speed: 8.5,
        max_accel: 4.5,
        reaction_s: 0.3,
    };

    /// No limits, like the animated fielders of Gillies & Dodgson (1999).
    pub const NONE: Limits = Limits {
        max_speed: f64::INFINITY,
        max_accel: f64::INFINITY,
        reaction_s: 0.0,
    };

    /// Whether both speed and acceleration are finite.
    pub(crate) fn is_limited(&self) -> bool {
        self.max_speed.is_finite() && self.max_accel.is_finite()
    }

    /// The least time, from the hit, for a fielder at rest to cover `distance` m: its
    /// reaction, then full acceleration up to top speed (no need to stop: a ball within
    /// reach is caught on the run). Without limits, the reaction alone.
    pub fn sprint_time(&self, distance: f64) -> f64 {
        if !self.is_limited() {
            return self.reaction_s;
        }
        let d = distance.max(0.0);
        let ramp = self.max_speed * self.max_speed / (2.0 * self.max_accel);
        self.reaction_s
            + if d <= ramp {
                (2.0 * d / self.max_accel).sqrt()
            } else {
                d / self.max_speed + self.max_speed / (2.0 * self.max_accel)
            }
    }
}

impl FromStr for Limits {
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        lookup("limits", s, &["human", "none"], &[Self::HUMAN, Self::NONE])
    }
}

/// Where a fielder is and how it moves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Body {
    /// Position on the ground, (x, z) in m.
    pub pos: DVec2,
    /// Velocity on the ground, (x, z) in m/s.
    pub vel: DVec2,
}

impl Body {
    /// A body standing still at `pos`.
    pub(crate) fn at_rest(pos: DVec2) -> Body {
        Body {
            pos,
            vel: DVec2::ZERO,
        }
    }

    /// Moves for `dt` under the commanded acceleration, clipped to the limits (direction
    /// kept), and returns the acceleration actually achieved. Speed is clipped after the
    /// acceleration, so a fielder at top speed can still turn.
    pub fn advance(&mut self, command: DVec2, limits: &Limits, dt: f64) -> DVec2 {
        let accel = if command.length() > limits.max_accel {
            command.normalize() * limits.max_accel
        } else {
            command
        };
        let mut vel = self.vel + accel * dt;
        if vel.length() > limits.max_speed {
            vel = vel.normalize() * limits.max_speed;
        }
        let achieved = (vel - self.vel) / dt;
        self.pos += 0.5 * (self.vel + vel) * dt;
        self.vel = vel;
        achieved
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_clip_acceleration_and_speed() {
        let mut b = Body::at_rest(DVec2::ZERO);
        let dt = 1.0 / 60.0;
        for _ in 0..600 {
            let a = b.advance(DVec2::new(100.0, 100.0), &Limits::HUMAN, dt);
            assert!(a.length() <= 4.5 + 1e-9);
            assert!(b.vel.length() <= 8.5 + 1e-9);
        }
        assert!((b.vel.length() - 8.5).abs() < 1e-9);
    }

    #[test]
    fn constant_acceleration_is_integrated_exactly() {
        let mut b = Body::at_rest(DVec2::ZERO);
        for _ in 0..100 {
            b.advance(DVec2::new(2.0, 0.0), &Limits::NONE, 0.01);
        }
        assert!((b.pos.x - 0.5 * 2.0 * 1.0).abs() < 1e-12);
    }

    /// Human limits ramp up to 8.5 m/s over 8.5² / (2 · 4.5) = 8.03 m: 2 m take
    /// √(2·2/4.5) s after the 0.3 s reaction; 30 m take 30/8.5 + 8.5/9 s after it; the
    /// two pieces meet at the ramp's end.
    #[test]
    fn a_sprint_accelerates_then_runs_at_top_speed() {
        let l = Limits::HUMAN;
        assert!((l.sprint_time(2.0) - (0.3 + (4.0f64 / 4.5).sqrt())).abs() < 1e-12);
        assert!((l.sprint_time(30.0) - (0.3 + 30.0 / 8.5 + 8.5 / 9.0)).abs() < 1e-12);
        let ramp = 8.5 * 8.5 / 9.0;
        assert!((l.sprint_time(ramp - 1e-9) - l.sprint_time(ramp + 1e-9)).abs() < 1e-6);
        assert_eq!(l.sprint_time(-1.0), 0.3);
        assert_eq!(Limits::NONE.sprint_time(100.0), 0.0);
    }
}
