//! Ball flight: gravity, aerodynamic drag and Magnus lift, a fixed-step integrator and a
//! ground contact.
//!
//! Everything here is pure and deterministic: a [`BallState`] advanced by
//! [`BallState::step`] with the same inputs gives the same bits on the same build.

mod air;
mod ball;
mod flight;
mod ground;
mod launch;

pub use air::{Air, AirModel, NATHAN_AIR_DENSITY};
pub use ball::BallSpec;
pub use flight::{BallState, Flight};
pub use ground::Ground;
pub use launch::Launch;

use glam::DVec3;

/// Standard gravity, pointing down the y axis (y is up).
pub const GRAVITY: DVec3 = DVec3::new(0.0, -9.81, 0.0);
