//! What a fielder can see: the optical angles of the ball from its own eye, and their rates,
//! from its estimate of the ball's path over its last looks.
//!
//! A strategy reads only a [`Percept`]: never the ball's future, never its true state
//! (with noise or delay switched on, what it reads is what its eye would have reported).

mod history;

pub use history::{Percept, PerceptionHistory};

use glam::{DVec2, DVec3};
use rand::Rng;
use rand_distr::{Distribution, Normal};
use serde::Serialize;

/// The sensory side of a fielder.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PerceptionConfig {
    /// Eye height above the ground, h.
    pub eye_height_m: f64,
    /// Visuomotor delay: a strategy acts on what the eye saw this long ago. Off by default.
    pub delay_s: f64,
    /// Standard deviation of Gaussian noise added to both optical angles. Off by default.
    pub noise_rad: f64,
    /// How far back, in seconds, the fielder's estimate of the ball's path reaches (see
    /// [`PerceptionHistory`]); never fewer than three looks. Zero (three looks) is exact
    /// enough without noise; with noise a longer span averages it away.
    pub smoothing_s: f64,
}

impl Default for PerceptionConfig {
    fn default() -> Self {
        PerceptionConfig {
            eye_height_m: 1.7,
            delay_s: 0.0,
            noise_rad: 0.0,
            smoothing_s: 0.0,
        }
    }
}

/// One look at the ball: the line of sight from the eye, plus a distance cue.
///
/// Stored as tan ψ and the unit bearing vector rather than as angles: those are what the
/// strategies compute with, and keeping them saves every tick the trigonometry that
/// turning angles back into them would cost. The angles themselves are derived on demand.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sighting {
    /// When the eye saw it, s since the launch.
    pub t: f64,
    /// tan ψ, ψ the elevation of the ball above the horizontal through the eye.
    pub tan_psi: f64,
    /// Unit vector on the ground from the fielder toward the ball: (cos α, sin α), the
    /// bearing α measured from +x toward +z (a fixed reference direction).
    pub toward_ball: DVec2,
    /// Horizontal distance d from the fielder to the ball. The optical strategies do not
    /// need it to pick a direction; they use it only to scale a gain (binocular disparity
    /// and the ball's angular size give a human this cue at fly-ball ranges).
    pub distance: f64,
}

impl Sighting {
    /// The noise-free sighting of a ball at `ball` from a fielder standing at `fielder`.
    pub fn of(t: f64, ball: DVec3, fielder: DVec2, eye_height: f64) -> Sighting {
        let offset = DVec2::new(ball.x - fielder.x, ball.z - fielder.y);
        let distance = offset.length();
        Sighting {
            t,
            tan_psi: (ball.y - eye_height) / distance,
            toward_ball: offset.normalize_or(DVec2::X),
            distance,
        }
    }

    /// The same sighting with Gaussian noise of `sd` radians on both optical angles.
    pub fn blurred(self, sd: f64, rng: &mut impl Rng) -> Sighting {
        if sd <= 0.0 {
            return self;
        }
        let normal = Normal::new(0.0, sd).expect("noise sd is finite and positive");
        let psi = self.psi() + normal.sample(rng);
        let alpha = self.alpha() + normal.sample(rng);
        Sighting {
            tan_psi: psi.tan(),
            toward_ball: DVec2::from_angle(alpha),
            ..self
        }
    }

    /// Elevation ψ in radians.
    pub fn psi(&self) -> f64 {
        self.tan_psi.atan()
    }

    /// Bearing α in radians, in (−π, π].
    pub fn alpha(&self) -> f64 {
        self.toward_ball.y.atan2(self.toward_ball.x)
    }

    /// The ball relative to the eye, rebuilt from the line of sight and distance.
    pub fn relative_position(&self) -> DVec3 {
        self.distance * DVec3::new(self.toward_ball.x, self.tan_psi, self.toward_ball.y)
    }
}
