//! The built-in **synthetic** locomotion library: a stand-in for motion capture when no
//! BVH directory is available, so the server and the cost maps still work.
//!
//! It is not human data and is always labelled `synthetic` where motion is shown. It is
//! built to be a fair stand-in for what a motion graph needs: each behaviour (`run`,
//! `dribble`, `defense`) has starts, stops, speed changes, turns of several radii both
//! ways, backpedals and side steps, sharing a common pace and a common standing pose so
//! clips connect; root motion stays within human speed, acceleration and turning limits;
//! and the figure is a rigid stick skeleton with CMU joint names, so the same code reads
//! it as reads real mocap. It is deterministic: no randomness at all.

mod catalogue;
mod figure;
mod profile;

use super::Clip;

/// Every synthetic clip, sampled at `fps`, sorted by behaviour then name as
/// [`super::MotionLibrary`] promises.
pub(super) fn clips(fps: f64) -> Vec<Clip> {
    let names: Vec<String> = figure::JOINTS.iter().map(|s| s.to_string()).collect();
    let mut clips: Vec<Clip> = catalogue::behaviours()
        .into_iter()
        .flat_map(|behaviour| {
            let names = &names;
            behaviour.clips.into_iter().map(move |(name, profile)| {
                let states = profile::integrate(&profile, fps, figure::phase_per_metre);
                let mut positions = Vec::with_capacity(states.len() * names.len());
                for state in &states {
                    figure::pose(&behaviour.style, state, &mut positions);
                }
                // The figure and its profiles are written with the body's left on +z.
                // With y up and right-handed axes a body facing +x has its left on −z
                // (see `Clip::new`), so mirror z: left turns stay left turns.
                for p in &mut positions {
                    p.z = -p.z;
                }
                Clip::new(name, behaviour.name, fps, names.clone(), positions)
                    .expect("the synthetic figure has every joint a clip needs")
            })
        })
        .collect();
    clips.sort_by(|a, b| (&a.behaviour, &a.name).cmp(&(&b.behaviour, &b.name)));
    clips
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn clip<'a>(clips: &'a [Clip], behaviour: &str, name: &str) -> &'a Clip {
        clips
            .iter()
            .find(|c| c.behaviour == behaviour && c.name == name)
            .unwrap_or_else(|| panic!("no clip {behaviour}/{name}"))
    }

    fn joint(clip: &Clip, name: &str) -> usize {
        clip.joint_names.iter().position(|n| n == name).unwrap()
    }

    /// Root ground velocity between frames `f` and `f + 1`, m/s.
    fn velocity(clip: &Clip, f: usize) -> DVec2 {
        (clip.root(f + 1) - clip.root(f)) * clip.fps
    }

    /// `a − b` wrapped into (−π, π].
    fn angle_between(a: f64, b: f64) -> f64 {
        let d = (a - b).rem_euclid(2.0 * PI);
        if d > PI {
            d - 2.0 * PI
        } else {
            d
        }
    }

    #[test]
    fn every_behaviour_has_clips_of_whole_frames_at_both_rates() {
        let (at30, at60) = (clips(30.0), clips(60.0));
        for behaviour in ["run", "dribble", "defense"] {
            assert!(at30.iter().filter(|c| c.behaviour == behaviour).count() >= 8);
        }
        assert_eq!(at30.len(), at60.len());
        for (a, b) in at30.iter().zip(&at60) {
            assert_eq!((&a.behaviour, &a.name), (&b.behaviour, &b.name));
            assert!(a.duration_s() >= 2.0 && a.duration_s() <= 8.0, "{}", a.name);
            // The same motion at twice the rate: twice the frames, give or take the one
            // that rounding lets in, and the same place at the same time.
            let (fa, fb) = (a.frame_count(), b.frame_count());
            assert!(fb.abs_diff(2 * fa) <= 1, "{}: {fa} vs {fb} frames", a.name);
            for f in 0..fa {
                assert!(
                    a.root(f).distance(b.root(2 * f)) < 1e-3,
                    "{} frame {f}",
                    a.name
                );
            }
        }
    }

    #[test]
    fn root_motion_stays_within_human_limits() {
        for fps in [30.0, 60.0] {
            for c in clips(fps) {
                for f in 0..c.frame_count() - 1 {
                    let speed = velocity(&c, f).length();
                    assert!(speed <= 9.0, "{} frame {f}: {speed} m/s", c.name);
                }
                for f in 1..c.frame_count() - 1 {
                    let accel = (velocity(&c, f) - velocity(&c, f - 1)).length() * fps;
                    assert!(accel <= 8.0, "{} frame {f}: {accel} m/s²", c.name);
                }
            }
        }
    }

    /// Offsets of heading from the direction of travel over the frames moving > 1 m/s.
    fn heading_offsets(c: &Clip) -> Vec<f64> {
        (0..c.frame_count() - 1)
            .filter(|&f| velocity(c, f).length() > 1.0)
            .map(|f| {
                let v = velocity(c, f);
                angle_between(c.heading(f), v.y.atan2(v.x))
            })
            .collect()
    }

    #[test]
    fn the_body_faces_the_way_the_motion_says() {
        let all = clips(30.0);
        let within = |offsets: Vec<f64>, want: f64, tol_deg: f64, what: &str| {
            assert!(!offsets.is_empty(), "{what}: never moving");
            for o in offsets {
                let err = angle_between(o, want).abs().to_degrees();
                assert!(err <= tol_deg, "{what}: off by {err}°");
            }
        };
        within(
            heading_offsets(clip(&all, "run", "jog_straight")),
            0.0,
            5.0,
            "jog",
        );
        within(
            heading_offsets(clip(&all, "run", "turn_left_6m")),
            0.0,
            5.0,
            "turn",
        );
        within(
            heading_offsets(clip(&all, "run", "backpedal")),
            PI,
            10.0,
            "backpedal",
        );
        // Stepping to the body's left: it faces 90° right of its travel, and headings
        // grow toward +z, which is to the right of a body facing +x.
        let left = heading_offsets(clip(&all, "run", "shuffle_left"));
        within(left, FRAC_PI_2, 10.0, "shuffle left");
        let right = heading_offsets(clip(&all, "defense", "slide_right"));
        within(right, -FRAC_PI_2, 10.0, "slide right");
    }

    #[test]
    fn the_figure_is_rigid() {
        let bones = [
            ("Hips", "LeftUpLeg"),
            ("LeftUpLeg", "LeftLeg"),
            ("LeftLeg", "LeftFoot"),
            ("LeftFoot", "LeftToeBase"),
            ("RightUpLeg", "RightLeg"),
            ("RightLeg", "RightFoot"),
            ("Hips", "Spine"),
            ("Spine1", "Neck"),
            ("Neck", "Head"),
            ("LeftShoulder", "LeftArm"),
            ("LeftArm", "LeftForeArm"),
            ("LeftForeArm", "LeftHand"),
            ("RightArm", "RightForeArm"),
            ("RightForeArm", "RightHand"),
        ];
        for c in clips(30.0) {
            for (a, b) in bones {
                let (a, b) = (joint(&c, a), joint(&c, b));
                let length = |f: usize| c.frame(f)[a].distance(c.frame(f)[b]);
                let first = length(0);
                for f in 1..c.frame_count() {
                    let drift = (length(f) - first).abs();
                    assert!(drift < 1e-3, "{}: bone {a}-{b} drifts {drift} m", c.name);
                }
            }
        }
    }

    #[test]
    fn no_joint_jumps_between_frames() {
        for c in clips(30.0) {
            for f in 1..c.frame_count() {
                for (p, q) in c.frame(f - 1).iter().zip(c.frame(f)) {
                    assert!(p.distance(*q) <= 0.5, "{} frame {f}", c.name);
                }
            }
        }
    }

    #[test]
    fn standing_is_one_pose_shared_by_starts_and_stops() {
        // The hub that links clips in a motion graph: the first frame of a start and the
        // last of a stop are the same body, up to where it stands and which way it faces.
        let all = clips(30.0);
        let local = |c: &Clip, f: usize| -> Vec<f64> {
            let frame = c.frame(f);
            let (h, root) = (c.heading(f), frame[0]);
            frame
                .iter()
                .flat_map(|p| {
                    let d = *p - root;
                    [
                        d.x * h.cos() + d.z * h.sin(),
                        d.y,
                        d.z * h.cos() - d.x * h.sin(),
                    ]
                })
                .collect()
        };
        let start = clip(&all, "run", "start_to_jog");
        let stop = clip(&all, "run", "jog_to_stop");
        let (a, b) = (local(start, 0), local(stop, stop.frame_count() - 1));
        let gap = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(gap < 1e-9, "standing poses differ by {gap} m");
        assert!(
            (start.frame(0)[0].y - 0.95).abs() < 0.05,
            "hips at rest height"
        );
    }

    #[test]
    fn two_builds_are_identical() {
        let (a, b) = (clips(30.0), clips(30.0));
        for (a, b) in a.iter().zip(&b) {
            for f in 0..a.frame_count() {
                assert_eq!(a.frame(f), b.frame(f));
            }
        }
    }
}
