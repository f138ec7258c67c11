//! The root's path in a synthetic clip: a chain of segments, each easing speed, path
//! curvature and facing toward new targets, integrated into positions on the ground.
//!
//! Driving the path through (speed, curvature) rather than placing points keeps every
//! clip physically honest: acceleration is bounded by how fast a segment eases, and the
//! lateral acceleration of a turn is speed² × curvature, so a catalogue entry can be
//! checked against human limits by reading it.

use glam::DVec2;
use std::f64::consts::PI;

/// What a segment steers toward.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Drive {
    /// Signed speed along the path direction, m/s. Negative runs the path backward,
    /// which lets a side shuffle reverse without the body turning round.
    pub speed: f64,
    /// Path curvature, 1/m; positive bends toward +z from +x, i.e. to the left.
    pub curvature: f64,
    /// Body facing minus path direction, rad: 0 runs forward, π backpedals, −π/2 side
    /// steps to the body's left.
    pub facing: f64,
}

impl Drive {
    pub fn standing(facing: f64) -> Drive {
        Drive {
            speed: 0.0,
            curvature: 0.0,
            facing,
        }
    }

    pub fn cruising(speed: f64, facing: f64) -> Drive {
        Drive {
            speed,
            curvature: 0.0,
            facing,
        }
    }
}

/// A clip's drive over time: the start, then segments that each reach a new target.
#[derive(Debug, Clone)]
pub(super) struct Profile {
    start: Drive,
    segments: Vec<(f64, Drive)>,
}

/// How long a turn takes to lean in and out: short enough for a crisp cut, long enough
/// that lateral acceleration builds up over several frames rather than in one.
const TURN_RAMP_S: f64 = 0.6;

impl Profile {
    pub fn from(start: Drive) -> Profile {
        Profile {
            start,
            segments: Vec::new(),
        }
    }

    fn end(&self) -> Drive {
        self.segments.last().map_or(self.start, |&(_, d)| d)
    }

    /// Eases every part of the drive toward `target` over `seconds`.
    pub fn to(mut self, seconds: f64, target: Drive) -> Profile {
        assert!(seconds > 0.0, "a segment must last some time");
        self.segments.push((seconds, target));
        self
    }

    pub fn hold(self, seconds: f64) -> Profile {
        let end = self.end();
        self.to(seconds, end)
    }

    pub fn speed(self, seconds: f64, speed: f64) -> Profile {
        let end = self.end();
        self.to(seconds, Drive { speed, ..end })
    }

    pub fn curve(self, seconds: f64, curvature: f64) -> Profile {
        let end = self.end();
        self.to(seconds, Drive { curvature, ..end })
    }

    pub fn face(self, seconds: f64, facing: f64) -> Profile {
        let end = self.end();
        self.to(seconds, Drive { facing, ..end })
    }

    /// Bends the path through `angle` (rad) on a circle of `radius` (m, positive to the
    /// left) at the current speed, leaning in and out over [`TURN_RAMP_S`]. Each cosine
    /// ramp turns half as far as a full-curvature stretch of the same length, so the two
    /// together count as one ramp's worth of arc.
    pub fn turn(self, radius: f64, angle: f64) -> Profile {
        let speed = self.end().speed.abs();
        assert!(speed > 0.0, "a turn needs the body moving");
        let arc_s = angle * radius.abs() / speed;
        assert!(arc_s > TURN_RAMP_S, "turn too short for its ramps");
        self.curve(TURN_RAMP_S, 1.0 / radius)
            .hold(arc_s - TURN_RAMP_S)
            .curve(TURN_RAMP_S, 0.0)
    }

    pub fn duration_s(&self) -> f64 {
        self.segments.iter().map(|&(s, _)| s).sum()
    }

    /// The drive at time `t`: cosine easing has zero slope at both ends of a segment, so
    /// speed, curvature and facing all change smoothly across segment boundaries.
    pub fn at(&self, t: f64) -> Drive {
        let mut from = self.start;
        let mut t0 = 0.0;
        for &(seconds, to) in &self.segments {
            if t <= t0 + seconds {
                let e = (1.0 - (PI * ((t - t0) / seconds).clamp(0.0, 1.0)).cos()) / 2.0;
                let mix = |a: f64, b: f64| a + (b - a) * e;
                return Drive {
                    speed: mix(from.speed, to.speed),
                    curvature: mix(from.curvature, to.curvature),
                    facing: mix(from.facing, to.facing),
                };
            }
            from = to;
            t0 += seconds;
        }
        from
    }
}

/// The root's state at one frame.
#[derive(Debug, Clone, Copy)]
pub(super) struct RootState {
    /// Position on the ground, (x, z).
    pub ground: DVec2,
    /// Direction of the path, rad from +x toward +z.
    pub path_heading: f64,
    pub drive: Drive,
    /// Gait phase, rad: advances with distance travelled, so legs never skate.
    pub phase: f64,
}

impl RootState {
    /// Which way the body faces, rad from +x toward +z.
    pub fn facing(&self) -> f64 {
        self.path_heading + self.drive.facing
    }
}

/// Integration steps per frame: fine enough that the path at 30 and at 60 fps agrees to
/// well under a millimetre, so the two libraries show the same motion.
const SUBSTEPS: usize = 16;

/// Samples `profile` at `fps`, one state per whole frame that fits in it. `phase_per_metre`
/// gives the gait's phase rate at a ground speed (the stride shortens as speed drops).
pub(super) fn integrate(
    profile: &Profile,
    fps: f64,
    phase_per_metre: impl Fn(f64) -> f64,
) -> Vec<RootState> {
    let frames = ((profile.duration_s() * fps).round() as usize).max(1);
    let dt = 1.0 / (fps * SUBSTEPS as f64);
    let (mut ground, mut heading, mut phase) = (DVec2::ZERO, 0.0_f64, 0.0);
    let mut states = Vec::with_capacity(frames);
    for frame in 0..frames {
        let t = frame as f64 / fps;
        states.push(RootState {
            ground,
            path_heading: heading,
            drive: profile.at(t),
            phase,
        });
        // Midpoint rule: second order, and the drive is smooth, so substeps converge fast.
        for step in 0..SUBSTEPS {
            let d = profile.at(t + (step as f64 + 0.5) * dt);
            let mid_heading = heading + d.curvature * d.speed * dt / 2.0;
            ground += d.speed * dt * DVec2::new(mid_heading.cos(), mid_heading.sin());
            heading += d.curvature * d.speed * dt;
            phase += d.speed.abs() * phase_per_metre(d.speed.abs()) * dt;
        }
    }
    states
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn easing_reaches_each_target_and_holds_it() {
        let p = Profile::from(Drive::standing(0.0))
            .speed(1.0, 4.0)
            .hold(1.0);
        assert_eq!(p.at(0.0).speed, 0.0);
        assert!((p.at(0.5).speed - 2.0).abs() < 1e-12);
        assert_eq!(p.at(1.0).speed, 4.0);
        assert_eq!(p.at(1.7).speed, 4.0);
        assert_eq!(p.at(9.0).speed, 4.0);
    }

    #[test]
    fn a_turn_bends_the_path_through_its_angle() {
        let p = Profile::from(Drive::cruising(3.0, 0.0))
            .hold(0.5)
            .turn(6.0, PI / 2.0)
            .hold(0.5);
        let states = integrate(&p, 600.0, |_| 1.0);
        let last = states.last().unwrap();
        assert!((last.path_heading - PI / 2.0).abs() < 1e-3);
    }
}
