//! The air a ball flies through: none (vacuum) or Nathan's drag-and-lift model.

use super::{BallSpec, GRAVITY};
use crate::names::{lookup, UnknownName};
use glam::DVec3;
use serde::Serialize;
use std::str::FromStr;

/// Air density at 70 °F, 15 ft altitude, 50 % relative humidity, 29.92 inHg (Nathan).
pub const NATHAN_AIR_DENSITY: f64 = 1.194;

/// Which forces act on a ball in flight besides gravity. Chosen by name (`nathan`,
/// `vacuum`) on the command line; matches always fly Nathan's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum AirModel {
    /// Gravity only: the closed-form parabola, used as an analytic oracle.
    Vacuum,
    /// Drag plus Magnus lift with Nathan's coefficients.
    Nathan,
}

impl AirModel {
    /// The model's name as users type it and reports show it.
    pub fn name(self) -> &'static str {
        match self {
            AirModel::Vacuum => "vacuum",
            AirModel::Nathan => "nathan",
        }
    }
}

impl FromStr for AirModel {
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        lookup(
            "air model",
            s,
            &["nathan", "vacuum"],
            &[Self::Nathan, Self::Vacuum],
        )
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
    /// The air for `ball` spinning at `rpm` about `spin_axis` (normalised here; a zero
    /// axis gives no lift), in air of `density` kg/m³.
    pub(crate) fn new(
        model: AirModel,
        density: f64,
        ball: &BallSpec,
        rpm: f64,
        spin_axis: DVec3,
    ) -> Air {
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

    /// Acceleration of the ball when it moves at `v`.
    ///
    /// This runs four times a tick for every ball in flight, so it is written to need two
    /// square roots and one division: with S = r·ω/|v|, Nathan's
    /// CL = 1.120·S/(0.583 + 2.333·S) = 1.120·r·ω / (0.583·|v| + 2.333·r·ω).
    pub fn acceleration(&self, v: DVec3) -> DVec3 {
        if self.model == AirModel::Vacuum {
            return GRAVITY;
        }
        let speed_sq = v.length_squared();
        if speed_sq < 1e-18 {
            return GRAVITY;
        }
        let speed = speed_sq.sqrt();
        let drag = v * (-self.k * self.drag_coefficient * speed);
        // Lift is perpendicular to velocity and spin axis, along ω̂ × v̂ normalised.
        let across = self.spin_axis.cross(v);
        let across_sq = across.length_squared();
        if across_sq < 1e-18 || self.surface_speed == 0.0 {
            return GRAVITY + drag;
        }
        let (a, lift_scale) = (self.surface_speed, self.ball.lift_scale);
        let lift = across
            * (self.k * lift_scale * 1.120 * a * speed_sq
                / ((0.583 * speed + 2.333 * a) * across_sq.sqrt()));
        GRAVITY + drag + lift
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_path_matches_the_textbook_forces() {
        let ball = BallSpec::BASEBALL;
        let axis = DVec3::new(0.3, -0.2, 0.9).normalize();
        let air = Air::new(AirModel::Nathan, NATHAN_AIR_DENSITY, &ball, 2500.0, axis);
        let v = DVec3::new(30.0, 12.0, -7.0);
        let k = 0.5 * NATHAN_AIR_DENSITY * ball.area_m2() / ball.mass_kg;
        let speed = v.length();
        let s = ball.radius_m * 2500.0 * std::f64::consts::TAU / 60.0 / speed;
        let drag = -k * ball.drag_coefficient(2500.0) * speed * v;
        let lift = k * ball.lift_coefficient(s) * speed * speed * axis.cross(v).normalize();
        let expected = GRAVITY + drag + lift;
        assert!((air.acceleration(v) - expected).length() < 1e-12 * expected.length());
    }
}
