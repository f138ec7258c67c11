//! What a fielder can see: the optical angles of the ball from its own eye and their
//! rates, judged as a person judges them, and a distance cue only where a person has one.
//!
//! A strategy reads only a [`Percept`]: never the ball's future, never its true state
//! (with noise or delay switched on, what it reads is what its senses would have
//! reported). [`Senses`] makes each look what the eye reports; [`PerceptionHistory`]
//! turns the looks into the percept.

mod history;
mod senses;

pub use history::{Percept, PerceptionHistory};
pub use senses::{DistanceCue, Look, Senses, JUDGEMENT_S};

use glam::{DVec2, DVec3};
use serde::Serialize;

/// The sensory side of a fielder.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PerceptionConfig {
    /// Eye height above the ground, h.
    pub eye_height_m: f64,
    /// Visuomotor delay: a strategy acts on what the eye saw this long ago. Off by default.
    pub delay_s: f64,
    /// Standard deviation of Gaussian noise added to both optical angles of each look,
    /// independently. Off by default.
    pub noise_rad: f64,
    /// How far back, in seconds, the fielder's fit of the angles reaches (see
    /// [`PerceptionHistory`]); never fewer than three looks.
    pub smoothing_s: f64,
    /// Weber fraction of the image's perceived angular speed: each judgement of it is
    /// off by this share (one standard deviation). Off by default.
    pub rate_weber: f64,
    /// Standard deviation of the error in the perceived direction of the image's
    /// motion, rad. Off by default.
    pub direction_rad: f64,
    /// Weber fraction of the distance cue (one standard deviation of its relative
    /// error). Off by default.
    pub distance_weber: f64,
    /// Beyond this horizontal distance the fielder has no distance cue at all.
    /// Unbounded by default.
    pub distance_range_m: f64,
}

impl Default for PerceptionConfig {
    fn default() -> Self {
        PerceptionConfig {
            eye_height_m: 1.7,
            delay_s: 0.0,
            noise_rad: 0.0,
            smoothing_s: 0.0,
            rate_weber: 0.0,
            direction_rad: 0.0,
            distance_weber: 0.0,
            distance_range_m: f64::INFINITY,
        }
    }
}

/// The ball as it really is from a fielder's eye: the line of sight and the true
/// horizontal distance (what traces, plots and the optical measures use; a fielder's
/// senses make a [`Look`] of it).
///
/// Stored as tan ψ and the unit bearing vector rather than as angles: those are what the
/// strategies compute with. The angles themselves are derived on demand.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sighting {
    /// When the eye saw it, s since the launch.
    pub t: f64,
    /// tan ψ, ψ the elevation of the ball above the horizontal through the eye.
    pub tan_psi: f64,
    /// Unit vector on the ground from the fielder toward the ball: (cos α, sin α), the
    /// bearing α measured from +x toward +z (a fixed reference direction).
    pub toward_ball: DVec2,
    /// Horizontal distance d from the fielder to the ball.
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

    /// Elevation ψ in radians.
    pub fn psi(&self) -> f64 {
        self.tan_psi.atan()
    }

    /// Bearing α in radians, in (−π, π].
    pub fn alpha(&self) -> f64 {
        self.toward_ball.y.atan2(self.toward_ball.x)
    }
}
