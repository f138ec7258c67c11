//! How a ball leaves the bat: speed, direction, height and spin.

use super::{Air, AirModel, BallSpec, BallState};
use glam::DVec3;

/// A batted ball's initial conditions, in the units people quote (degrees, rpm) so a
/// launch reads like a broadcast graphic; converted to SI once, in [`Launch::initial_state`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Launch {
    /// Speed off the bat, m/s.
    pub speed_m_s: f64,
    /// Angle above the horizontal, degrees.
    pub elevation_deg: f64,
    /// Horizontal direction in degrees, measured from +x toward +z.
    pub azimuth_deg: f64,
    /// Height the ball leaves the bat at, m (it starts above the origin).
    pub height_m: f64,
    /// Spin rate, revolutions per minute.
    pub spin_rpm: f64,
    /// Tilt of the lift direction about the velocity: 0° is pure backspin (lift up),
    /// +90° is side spin that curves the ball toward increasing azimuth.
    pub spin_tilt_deg: f64,
}

impl Launch {
    /// Unit vector of the launch velocity (y up).
    pub(crate) fn direction(&self) -> DVec3 {
        let (el, az) = (
            self.elevation_deg.to_radians(),
            self.azimuth_deg.to_radians(),
        );
        DVec3::new(el.cos() * az.cos(), el.sin(), el.cos() * az.sin())
    }

    /// The ball at t = 0: at (0, `height_m`, 0), moving at `speed_m_s` along
    /// the launch direction, in SI units.
    pub fn initial_state(&self) -> BallState {
        BallState {
            t: 0.0,
            pos: DVec3::new(0.0, self.height_m, 0.0),
            vel: self.speed_m_s * self.direction(),
        }
    }

    /// The spin axis ω̂ that makes the initial lift point along the tilted direction:
    /// with lift direction L ⟂ v̂, ω̂ = v̂ × L gives ω̂ × v̂ = L.
    pub fn spin_axis(&self) -> DVec3 {
        let v = self.direction();
        let up = (DVec3::Y - v * v.dot(DVec3::Y)).normalize_or(DVec3::X);
        let side = v.cross(up).normalize_or_zero();
        let tilt = self.spin_tilt_deg.to_radians();
        let lift = tilt.cos() * up + tilt.sin() * side;
        v.cross(lift)
    }

    /// The air this launch flies through: `model` at `density` (kg/m³) for `ball`, with
    /// this launch's spin rate and [`Launch::spin_axis`].
    pub fn air(&self, model: AirModel, density: f64, ball: &BallSpec) -> Air {
        Air::new(model, density, ball, self.spin_rpm, self.spin_axis())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn launch(az: f64, tilt: f64) -> Launch {
        Launch {
            speed_m_s: 40.0,
            elevation_deg: 30.0,
            azimuth_deg: az,
            height_m: 1.0,
            spin_rpm: 2000.0,
            spin_tilt_deg: tilt,
        }
    }

    #[test]
    fn backspin_lifts_up_for_any_azimuth() {
        for az in [-120.0, 0.0, 37.0, 90.0, 180.0] {
            let l = launch(az, 0.0);
            let lift = l.spin_axis().cross(l.direction());
            assert!(lift.dot(DVec3::Y) > 0.99 * l.direction().dot(DVec3::Y).acos().sin());
            assert!(lift.dot(l.direction()).abs() < 1e-12);
        }
    }

    #[test]
    fn positive_tilt_curves_toward_increasing_azimuth() {
        let l = launch(0.0, 90.0); // heading +x; increasing azimuth is +z
        let lift = l.spin_axis().cross(l.direction());
        assert!((lift - DVec3::Z).length() < 1e-12, "{lift}");
    }
}
