//! Whether a fielder catches the ball: tested between ticks, so a fast ball cannot slip
//! through the space between two samples.

use glam::{DVec2, DVec3};
use serde::Serialize;

/// The region around a fielder in which a descending ball is caught.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CatchZone {
    /// Horizontal reach from the fielder's centre, m.
    pub reach_m: f64,
    /// How much further a fielder reaches in its last moments, lunging (or stepping and
    /// leaning) at the ball, m: granted only to a fielder finishing its catch
    /// ([`super::FielderConfig::terminal_s`]).
    pub lunge_m: f64,
    /// Lowest height above the ground at which a ball is caught, m.
    pub min_height_m: f64,
    /// Highest height above the ground at which a ball is caught, m.
    pub max_height_m: f64,
}

impl Default for CatchZone {
    /// *Assumption*: about 1 m of reach (arm plus a lean), from the shins to a jump.
    fn default() -> Self {
        CatchZone {
            reach_m: 1.0,
            lunge_m: 0.0,
            min_height_m: 0.3,
            max_height_m: 2.4,
        }
    }
}

/// One tick's worth of relative motion, ball and fielder both moving linearly inside it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pass {
    /// Closest horizontal distance between ball and fielder while the ball is in the
    /// height band, m.
    pub(crate) closest_m: f64,
    /// Fraction of the tick at which the ball first comes within reach, if it does.
    pub(crate) caught_s: Option<f64>,
}

impl CatchZone {
    /// The height a fielder aims to take the ball at: the middle of the band.
    pub fn catch_height_m(&self) -> f64 {
        0.5 * (self.min_height_m + self.max_height_m)
    }

    /// Examines the tick from (ball0, fielder0) to (ball1, fielder1), the fielder
    /// `lunging` or not. Returns `None` when the ball is not descending through the
    /// height band during the tick.
    pub(crate) fn pass(
        &self,
        ball0: DVec3,
        ball1: DVec3,
        fielder0: DVec2,
        fielder1: DVec2,
        lunging: bool,
    ) -> Option<Pass> {
        let reach = self.reach_m + if lunging { self.lunge_m } else { 0.0 };
        let dy = ball1.y - ball0.y;
        if dy >= 0.0 {
            return None;
        }
        // Heights are linear in s, so the band is an interval of s.
        let s_enter = ((self.max_height_m - ball0.y) / dy).max(0.0);
        let s_leave = ((self.min_height_m - ball0.y) / dy).min(1.0);
        if s_enter > s_leave {
            return None;
        }
        let r0 = DVec2::new(ball0.x, ball0.z) - fielder0;
        let r1 = DVec2::new(ball1.x, ball1.z) - fielder1;
        let dr = r1 - r0;
        let at = |s: f64| (r0 + dr * s).length();
        let dd = dr.length_squared();
        let closest_s = if dd > 0.0 {
            (-r0.dot(dr) / dd).clamp(s_enter, s_leave)
        } else {
            s_enter
        };
        let closest_m = at(closest_s);
        let caught_s = if at(s_enter) <= reach {
            Some(s_enter)
        } else if closest_m <= reach {
            // |r0 + dr·s|² = reach², the smaller root: the first moment within reach.
            let (b, c) = (r0.dot(dr), r0.length_squared() - reach * reach);
            let s = (-b - (b * b - dd * c).max(0.0).sqrt()) / dd;
            Some(s.clamp(s_enter, closest_s))
        } else {
            None
        };
        Some(Pass {
            closest_m,
            caught_s,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fast_ball_between_ticks_is_still_caught() {
        // The ball drops from 3 m to 0 in one tick while crossing the fielder: neither
        // endpoint is within reach or in the band, the middle of the tick is.
        let zone = CatchZone::default();
        let p = zone
            .pass(
                DVec3::new(-5.0, 3.0, 0.0),
                DVec3::new(5.0, 0.0, 0.0),
                DVec2::ZERO,
                DVec2::ZERO,
                false,
            )
            .unwrap();
        assert!(p.caught_s.is_some());
        assert!(p.closest_m < 1e-12);
        let s = p.caught_s.unwrap();
        // Reach is met at x = −1 (s = 0.4), inside the band (y = 1.8).
        assert!((s - 0.4).abs() < 1e-12, "{s}");
    }

    #[test]
    fn a_rising_ball_is_never_caught() {
        let zone = CatchZone::default();
        assert!(zone
            .pass(
                DVec3::new(0.0, 1.0, 0.0),
                DVec3::new(0.0, 1.5, 0.0),
                DVec2::ZERO,
                DVec2::ZERO,
                false
            )
            .is_none());
    }

    #[test]
    fn out_of_reach_reports_the_miss_distance() {
        let zone = CatchZone::default();
        let p = zone
            .pass(
                DVec3::new(3.0, 1.5, -1.0),
                DVec3::new(3.0, 1.0, 1.0),
                DVec2::ZERO,
                DVec2::ZERO,
                false,
            )
            .unwrap();
        assert!(p.caught_s.is_none());
        assert!((p.closest_m - 3.0).abs() < 1e-12);
    }

    #[test]
    fn a_lunge_adds_its_reach_only_to_a_lunging_fielder() {
        let zone = CatchZone {
            lunge_m: 0.6,
            ..CatchZone::default()
        };
        let (ball0, ball1) = (DVec3::new(1.5, 1.5, -1.0), DVec3::new(1.5, 1.0, 1.0));
        let standing = zone
            .pass(ball0, ball1, DVec2::ZERO, DVec2::ZERO, false)
            .unwrap();
        let lunging = zone
            .pass(ball0, ball1, DVec2::ZERO, DVec2::ZERO, true)
            .unwrap();
        assert!(standing.caught_s.is_none() && lunging.caught_s.is_some());
    }
}
