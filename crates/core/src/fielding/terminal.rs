//! How a fielder finishes a catch: the last half second, when the ball is close.
//!
//! The optical laws bring a fielder to the ball; none of the papers says how the catch is
//! finished, and with a person's senses the laws' last metres are noise over a short
//! distance (a fielder arrives within about half a metre of the ball, not on it). People
//! do not run the last steps by the same law: close to the ball they step, reach and
//! lunge, and outfielders dive. Up close they have what they lack far away, a distance
//! cue (disparity, the ball's angular size and its expansion), and the ball's last
//! fraction of a second is short enough to extrapolate.
//!
//! So once the fielder judges, from its percept, that the ball will come down through
//! its catch height within [`super::FielderConfig::terminal_s`], it stops steering by its
//! law and runs to where it judges the ball will come down: the ball's judged position
//! and velocity (the line of sight scaled by the distance cue, and the rates) carried
//! forward under gravity. It judges again every tick, so the run homes in as the cue
//! improves; and in this phase it may lunge ([`super::CatchZone::lunge_m`]). Without a
//! distance cue (the ball beyond the cue's range) there is no terminal phase: the
//! fielder keeps its law.
//!
//! This is extrapolation, but over at most the terminal phase (a fraction of a second,
//! against a flight of several seconds) and from what the senses give at close range: it
//! is not the trajectory prediction the optical strategies are an alternative to.

use super::strategy::Forecast;
use crate::perception::Percept;
use crate::physics::GRAVITY;
use glam::DVec2;

/// Where and when the fielder at `fielder` moving at `fielder_velocity` judges the ball
/// will come down through `height_above_eye` (negative: below the eye), from `percept`;
/// `None` without a distance cue or when the ball is not falling toward that height.
pub(crate) fn arrival(
    percept: &Percept,
    fielder: DVec2,
    fielder_velocity: DVec2,
    height_above_eye: f64,
) -> Option<Forecast> {
    if !percept.distance_seen {
        return None;
    }
    let (r, v) = (percept.relative_position(), percept.relative_velocity());
    let g = -GRAVITY.y;
    // r.y + v.y·s − ½·g·s² = height: the later root, when the ball comes down.
    let discriminant = v.y * v.y + 2.0 * g * (r.y - height_above_eye);
    if v.y >= 0.0 || discriminant < 0.0 {
        return None;
    }
    let s = (v.y + discriminant.sqrt()) / g;
    let ball_velocity = DVec2::new(v.x, v.z) + fielder_velocity;
    Some(Forecast {
        point: fielder + DVec2::new(r.x, r.z) + ball_velocity * s,
        t: percept.t + s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// A ball in vacuum seen exactly: where and when it comes through the catch height
    /// by the closed form of its parabola.
    #[test]
    fn an_exact_percept_of_a_falling_ball_gives_its_parabolas_crossing() {
        let eye = 1.7;
        let (fielder, fielder_velocity) = (DVec2::new(50.0, 4.0), DVec2::new(-3.0, 1.0));
        let (ball, ball_velocity) = (DVec3::new(46.0, 9.0, 7.0), DVec3::new(-6.0, -4.0, 2.0));
        let r = ball - DVec3::new(fielder.x, eye, fielder.y);
        let v = ball_velocity - DVec3::new(fielder_velocity.x, 0.0, fielder_velocity.y);
        let percept = Percept::of(2.0, r, v, true);
        let catch_height = 1.35;
        let got = arrival(&percept, fielder, fielder_velocity, catch_height - eye).unwrap();
        // 9 − 4s − 4.905 s² = 1.35.
        let g: f64 = 9.81;
        let s = (-4.0 + (16.0 + 2.0 * g * (9.0 - 1.35)).sqrt()) / g;
        assert!((got.t - (2.0 + s)).abs() < 1e-9, "{} vs {}", got.t, 2.0 + s);
        let want = DVec2::new(46.0 - 6.0 * s, 7.0 + 2.0 * s);
        assert!(
            (got.point - want).length() < 1e-9,
            "{} vs {want}",
            got.point
        );
        let unseen = Percept {
            distance_seen: false,
            ..percept
        };
        assert!(arrival(&unseen, fielder, fielder_velocity, catch_height - eye).is_none());
    }
}
