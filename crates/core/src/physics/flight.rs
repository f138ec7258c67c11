//! Integrating a ball's motion: one classic Runge–Kutta step per tick, free flight until
//! the ground, then bounces and a roll.

use super::{Air, Ground};
use glam::DVec3;

/// Where a ball is, how it moves, and when.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BallState {
    /// Time since the launch, s.
    pub t: f64,
    /// Position, m, with y up (y = 0 is the ground).
    pub pos: DVec3,
    /// Velocity, m/s.
    pub vel: DVec3,
}

impl BallState {
    /// Free flight over `dt` with fourth-order Runge–Kutta. The drag and lift forces are
    /// smooth in velocity, so RK4 at 60 Hz is already accurate to well under a millimetre
    /// over a 6 s flight (see the step-halving test) with four force evaluations a tick.
    pub fn fly(&self, dt: f64, air: &Air) -> BallState {
        let (p, v) = (self.pos, self.vel);
        let a1 = air.acceleration(v);
        let v2 = v + a1 * (0.5 * dt);
        let a2 = air.acceleration(v2);
        let v3 = v + a2 * (0.5 * dt);
        let a3 = air.acceleration(v3);
        let v4 = v + a3 * dt;
        let a4 = air.acceleration(v4);
        BallState {
            t: self.t + dt,
            pos: p + (v + 2.0 * v2 + 2.0 * v3 + v4) * (dt / 6.0),
            vel: v + (a1 + 2.0 * a2 + 2.0 * a3 + a4) * (dt / 6.0),
        }
    }

    /// One tick including ground contact: a ball that would pass below y = 0 is stopped
    /// at the contact instant (found by interpolating the step), bounced, and flown on
    /// for the rest of the tick; a ball on the ground with no upward speed rolls.
    pub fn step(&self, dt: f64, air: &Air, ground: &Ground) -> BallState {
        if self.pos.y <= 0.0 && self.vel.y <= 0.0 {
            let vel = ground.roll(self.vel, dt);
            return BallState {
                t: self.t + dt,
                pos: DVec3::new(self.pos.x, 0.0, self.pos.z)
                    + 0.5 * (self.vel.with_y(0.0) + vel) * dt,
                vel,
            };
        }
        let next = self.fly(dt, air);
        if next.pos.y >= 0.0 {
            return next;
        }
        let s = ground_crossing(self, &next);
        let contact = self.fly(s * dt, air);
        let after = BallState {
            t: contact.t,
            pos: DVec3::new(contact.pos.x, 0.0, contact.pos.z),
            vel: ground.bounce(contact.vel),
        };
        let rest = dt - s * dt;
        if after.vel.y > 0.0 {
            after.fly(rest, air)
        } else {
            BallState {
                t: self.t + dt,
                ..after.step(rest, air, ground)
            }
        }
    }
}

/// Fraction of the step [a, b] at which the height crosses zero, from the cubic Hermite
/// interpolant of position and velocity (exact for a parabola, so the vacuum landing
/// matches the closed form to rounding).
pub(crate) fn ground_crossing(a: &BallState, b: &BallState) -> f64 {
    let dt = b.t - a.t;
    let y = |s: f64| hermite(a.pos.y, a.vel.y * dt, b.pos.y, b.vel.y * dt, s);
    // The ball is above ground at s = 0 and below at s = 1; bisect then polish.
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if y(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Cubic Hermite interpolation on [0, 1] with endpoint values and scaled slopes.
pub(crate) fn hermite(p0: f64, m0: f64, p1: f64, m1: f64, s: f64) -> f64 {
    let (s2, s3) = (s * s, s * s * s);
    (2.0 * s3 - 3.0 * s2 + 1.0) * p0
        + (s3 - 2.0 * s2 + s) * m0
        + (-2.0 * s3 + 3.0 * s2) * p1
        + (s3 - s2) * m1
}

/// A ball's free flight sampled once a tick, from launch to its first contact with the
/// ground. Precomputed once per launch and shared by every fielder that chases it: the
/// ball does not depend on who watches it.
#[derive(Debug, Clone)]
pub struct Flight {
    /// Time between samples (the tick), s.
    pub(crate) dt: f64,
    /// One state a tick; the last one is the first at or below the ground.
    pub samples: Vec<BallState>,
    /// The instant and place the free flight reaches y = 0.
    pub landing: BallState,
}

impl Flight {
    /// Flies `start` until it reaches the ground or `max_t` passes.
    pub fn simulate(start: BallState, air: &Air, dt: f64, max_t: f64) -> Flight {
        let mut samples = Vec::with_capacity((max_t / dt) as usize + 2);
        samples.push(start);
        let mut s = start;
        while (s.pos.y > 0.0 || s.vel.y > 0.0) && s.t < max_t {
            s = s.fly(dt, air);
            samples.push(s);
        }
        let landing = match samples.len() {
            n if n >= 2 && s.pos.y <= 0.0 => {
                let prev = samples[n - 2];
                let f = ground_crossing(&prev, &s);
                let landed = prev.fly(f * dt, air);
                BallState {
                    pos: DVec3::new(landed.pos.x, 0.0, landed.pos.z),
                    ..landed
                }
            }
            _ => s,
        };
        Flight {
            dt,
            samples,
            landing,
        }
    }

    /// The first descending instant the ball's height passes `y`, interpolated inside the
    /// tick with the Hermite cubic; `None` if it never comes down through it.
    pub fn descending_through(&self, y: f64) -> Option<BallState> {
        self.samples.windows(2).find_map(|w| {
            let (a, b) = (&w[0], &w[1]);
            (a.pos.y >= y && b.pos.y < y && b.vel.y < 0.0).then(|| {
                let shifted = |s: &BallState| BallState {
                    pos: s.pos - DVec3::Y * y,
                    ..*s
                };
                let f = ground_crossing(&shifted(a), &shifted(b));
                let h = |ca: f64, cb: f64, va: f64, vb: f64| {
                    hermite(ca, va * self.dt, cb, vb * self.dt, f)
                };
                BallState {
                    t: a.t + f * self.dt,
                    pos: DVec3::new(
                        h(a.pos.x, b.pos.x, a.vel.x, b.vel.x),
                        y,
                        h(a.pos.z, b.pos.z, a.vel.z, b.vel.z),
                    ),
                    vel: a.vel.lerp(b.vel, f),
                }
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::{AirModel, BallSpec, Launch, GRAVITY, NATHAN_AIR_DENSITY};

    fn launch(speed: f64, elevation: f64, height: f64) -> Launch {
        Launch {
            speed_m_s: speed,
            elevation_deg: elevation,
            azimuth_deg: 0.0,
            height_m: height,
            spin_rpm: 2000.0,
            spin_tilt_deg: 0.0,
        }
    }

    fn fly(l: &Launch, model: AirModel, dt: f64) -> Flight {
        let air = l.air(model, NATHAN_AIR_DENSITY, &BallSpec::BASEBALL);
        Flight::simulate(l.initial_state(), &air, dt, 30.0)
    }

    #[test]
    fn vacuum_flight_matches_the_closed_form() {
        let l = launch(44.704, 30.0, 0.0);
        let f = fly(&l, AirModel::Vacuum, 1.0 / 60.0);
        let (vx, vy) = (
            44.704 * 30f64.to_radians().cos(),
            44.704 * 30f64.to_radians().sin(),
        );
        let t = 2.0 * vy / -GRAVITY.y;
        assert!((f.landing.t - t).abs() < 1e-9, "{} vs {t}", f.landing.t);
        assert!((f.landing.pos.x - vx * t).abs() < 1e-7);
        // The worked figure: 176.5 m after 4.56 s.
        assert!((f.landing.pos.x - 176.5).abs() < 0.1 && (t - 4.56).abs() < 0.01);
        // Every sample sits on the parabola.
        for s in &f.samples {
            let y = vy * s.t + 0.5 * GRAVITY.y * s.t * s.t;
            assert!((s.pos.y - y).abs() < 1e-9 && (s.pos.x - vx * s.t).abs() < 1e-9);
        }
    }

    #[test]
    fn nathan_worked_figure() {
        // 100 mph at 30°, 2000 rpm backspin, from the ground: about 124 m after about 5.5 s.
        let f = fly(&launch(44.704, 30.0, 0.0), AirModel::Nathan, 1.0 / 60.0);
        assert!(
            (f.landing.pos.x - 123.9).abs() < 1.5,
            "range {}",
            f.landing.pos.x
        );
        assert!((f.landing.t - 5.46).abs() < 0.1, "time {}", f.landing.t);
    }

    #[test]
    fn halving_the_step_moves_a_six_second_landing_by_under_a_centimetre() {
        let l = launch(42.0, 45.0, 1.0);
        let coarse = fly(&l, AirModel::Nathan, 1.0 / 60.0);
        let fine = fly(&l, AirModel::Nathan, 1.0 / 120.0);
        assert!(
            coarse.landing.t > 5.5,
            "not a 6 s flight: {}",
            coarse.landing.t
        );
        let moved = (coarse.landing.pos - fine.landing.pos).length();
        assert!(moved < 0.01, "landing moved {moved} m");
    }

    #[test]
    fn drag_always_removes_energy_without_spin() {
        let mut l = launch(40.0, 40.0, 1.0);
        l.spin_rpm = 0.0;
        let f = fly(&l, AirModel::Nathan, 1.0 / 60.0);
        let energy = |s: &BallState| 0.5 * s.vel.length_squared() - GRAVITY.y * s.pos.y;
        for w in f.samples.windows(2) {
            assert!(energy(&w[1]) < energy(&w[0]));
        }
    }

    #[test]
    fn ball_bounces_lower_each_time_then_rolls_to_a_stop() {
        let l = launch(20.0, 60.0, 1.0);
        let air = l.air(AirModel::Nathan, NATHAN_AIR_DENSITY, &BallSpec::BASEBALL);
        let ground = Ground::default();
        let mut s = l.initial_state();
        let mut peaks = vec![];
        let mut rising = true;
        for _ in 0..60 * 60 {
            let next = s.step(1.0 / 60.0, &air, &ground);
            assert!(next.pos.y >= 0.0, "ball under the ground: {next:?}");
            if rising && next.vel.y < 0.0 {
                peaks.push(next.pos.y);
            }
            rising = next.vel.y > 0.0;
            s = next;
        }
        assert!(peaks.len() >= 2, "no bounce: {peaks:?}");
        assert!(peaks.windows(2).all(|p| p[1] < p[0]), "{peaks:?}");
        assert_eq!(s.vel, DVec3::ZERO, "still moving after a minute");
        assert_eq!(s.pos.y, 0.0);
    }

    #[test]
    fn descending_crossing_lies_on_the_parabola() {
        let l = launch(30.0, 45.0, 1.7);
        let f = fly(&l, AirModel::Vacuum, 1.0 / 60.0);
        let c = f.descending_through(1.0).unwrap();
        let v = 30.0 * 45f64.to_radians().sin();
        // 1.7 + v t − g t²/2 = 1.0, larger root.
        let g = -GRAVITY.y;
        let t = (v + (v * v + 2.0 * g * 0.7).sqrt()) / g;
        assert!((c.t - t).abs() < 1e-9, "{} vs {t}", c.t);
        assert!((c.pos.x - 30.0 * 45f64.to_radians().cos() * t).abs() < 1e-7);
    }
}
