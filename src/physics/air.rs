//! The air a ball flies through: none (vacuum) or Nathan's drag-and-lift model.

use super::{BallSpec, GRAVITY};
use glam::DVec3;
use serde::Serialize;
use std::str::FromStr;

/// Air density at 70 °F, 15 ft altitude, 50 % relative humidity, 29.92 inHg (Nathan).
pub const NATHAN_AIR_DENSITY: f64 = 1.194;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum AirModel {
    /// Gravity only: the closed-form parabola, used as an analytic oracle.
    Vacuum,
    /// Drag plus Magnus lift with Nathan's coefficients.
    Nathan,
}

impl AirModel {
    pub fn name(self) -> &'static str {
        match self {
            AirModel::Vacuum => "vacuum",
            AirModel::Nathan => "nathan",
        }
    }
}

impl FromStr for AirModel {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "vacuum" => Ok(Self::Vacuum),
            "nathan" => Ok(Self::Nathan),
            other => Err(format!(
                "unknown air model \"{other}\"; expected one of nathan, vacuum"
            )),
        }
    }
}

/// The aerodynamic environment of one ball: precomputes what does not change in flight.
#[derive(Debug, Clone, Copy)]
pub struct Air {
    model: AirModel,
    /// ½·ρ·A / m: turns a coefficient times v² into an acceleration.
    k: f64,
    drag_coefficient: f64,
    /// r·ω: the ball's surface speed from spin, so S = r·ω / |v|.
    surface_speed: f64,
    /// Unit spin axis; fixed in space for the flight (spin decay has a 10,000 s time
    /// constant in Nathan's model, negligible over a 6 s flight, so it is left out).
    spin_axis: DVec3,
    ball: BallSpec,
}

impl Air {
    pub fn new(model: AirModel, density: f64, ball: &BallSpec, rpm: f64, spin_axis: DVec3) -> Air {
        let omega = rpm.abs() * std::f64::consts::TAU / 60.0;
        Air {
            model,
            k: 0.5 * density * ball.area_m2() / ball.mass_kg,
            drag_coefficient: ball.drag_coefficient(rpm.abs()),
            surface_speed: ball.radius_m * omega,
            spin_axis: spin_axis.normalize_or_zero(),
            ball: *ball,
        }
    }

    pub fn model(&self) -> AirModel {
        self.model
    }

    /// Acceleration of the ball when it moves at `v`.
    pub fn acceleration(&self, v: DVec3) -> DVec3 {
        if self.model == AirModel::Vacuum {
            return GRAVITY;
        }
        let speed = v.length();
        if speed < 1e-9 {
            return GRAVITY;
        }
        let drag = -self.k * self.drag_coefficient * speed * v;
        // Lift is perpendicular to velocity and spin axis, along ω̂ × v̂ normalised.
        let lift_dir = self.spin_axis.cross(v).normalize_or_zero();
        let cl = self.ball.lift_coefficient(self.surface_speed / speed);
        let lift = self.k * cl * speed * speed * lift_dir;
        GRAVITY + drag + lift
    }
}
