//! Jump shots in a clip: where the body rises to shoot. The motion graphs are of ground
//! locomotion (running, dribbling, footwork), so a shot ends the part of a clip a graph
//! may use; in the CMU dribbling two clips end in a jump shot (06_14, 06_15), and the
//! jump is how long a shot takes (T_s), not a way to move.
//!
//! A fast rise of the hips alone is not a shot: a defender coming up out of a deep
//! stance (102_26, the defensive zigzag) rises as fast. What tells them apart is the
//! arms: a shooter's hands go above the head on the way up, a defender's stay below it.

use super::Clip;
use serde::{Deserialize, Serialize};

/// What makes a rise of the hips a jump, all three at once. Measured on the CMU capture:
/// the two jump shots take off at 1.0 and 1.7 m/s (over 0.1 s), rise 0.20 and 0.37 m
/// from their crouch and peak 0.08 and 0.20 m above the clip's upright (median) height; the
/// fastest rise anywhere else among the dribbling and running clips (0.81 m/s, the low
/// freestyle dribble coming up from a crouch) rises 0.11 m and peaks below upright, and
/// runners bounce at under 0.7 m/s. A defender rising out of a deep stance (102_26)
/// passes all three, since its clip's median is the stance: [`HANDS_ABOVE_HEAD_M`] tells.
pub(super) const TAKE_OFF_M_S: f64 = 0.8;
const RISE_M: f64 = 0.15;
const ABOVE_UPRIGHT_M: f64 = 0.05;

/// How far above the head both hands must come, between the crouch and just after the
/// apex, for a rise to be a shot, m. Measured on the CMU capture: the two jump shots
/// raise both hands 0.09 m (06_14) and 0.05 m (06_15) above the head; in no other clip
/// of any subject does the lower hand come within 0.26 m of the head (102_26's rise out
/// of its stance: 0.30 m below).
const HANDS_ABOVE_HEAD_M: f64 = 0.0;

/// A jump shot found in a clip, in frames of the clip.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Jump {
    /// The lowest root before take-off: where the jump (the shot) begins.
    pub crouch: usize,
    /// Where the root first rises at take-off speed (0.8 m/s over 0.1 s).
    pub take_off: usize,
    /// The highest root after take-off: a jump shot releases the ball about here.
    pub apex: usize,
    /// Seconds from the crouch to the apex.
    pub crouch_to_apex_s: f64,
}

impl Jump {
    /// The first jump shot in `clip`, if any. A skeleton without joints named `Head`,
    /// `LeftHand` and `RightHand` cannot show where its hands are, and any rise that
    /// passes the three tests on the hips counts.
    pub fn find(clip: &Clip) -> Option<Jump> {
        Self::find_where(clip, true)
    }

    /// The first rise of the hips that passes the three tests on them, with (`hands`) or
    /// without the test on the arms.
    fn find_where(clip: &Clip, hands: bool) -> Option<Jump> {
        let height = |f: usize| clip.frame(f)[0].y;
        let joint = |name: &str| clip.joint_names.iter().position(|n| n == name);
        let arms = joint("Head").zip(joint("LeftHand")).zip(joint("RightHand"));
        // The lower hand's height above the head, at frame f.
        let hands_up = |f: usize| {
            arms.map_or(f64::INFINITY, |((head, left), right)| {
                let p = clip.frame(f);
                p[left].y.min(p[right].y) - p[head].y
            })
        };
        let span = ((clip.fps / 10.0).round() as usize).max(1);
        let n = clip.frame_count();
        // Upright: the median height of the hips over the clip.
        let upright = {
            let mut h: Vec<f64> = (0..n).map(height).collect();
            h.sort_by(f64::total_cmp);
            h[n / 2]
        };
        (0..n.saturating_sub(span))
            .filter(|&f| (height(f + span) - height(f)) * clip.fps / span as f64 >= TAKE_OFF_M_S)
            .map(|take_off| {
                let mut crouch = take_off;
                while crouch > 0 && height(crouch - 1) <= height(crouch) {
                    crouch -= 1;
                }
                let mut apex = take_off;
                while apex + 1 < n && height(apex + 1) >= height(apex) {
                    apex += 1;
                }
                Jump {
                    crouch,
                    take_off,
                    apex,
                    crouch_to_apex_s: (apex - crouch) as f64 / clip.fps,
                }
            })
            .find(|j| {
                // The release comes at about the apex, and the arms may finish rising
                // just after the hips do.
                let release = j.crouch..(j.apex + span + 1).min(n);
                height(j.apex) - height(j.crouch) >= RISE_M
                    && height(j.apex) >= upright + ABOVE_UPRIGHT_M
                    && (!hands
                        || release.map(hands_up).fold(f64::MIN, f64::max) >= HANDS_ABOVE_HEAD_M)
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::cmu_library;

    /// The CMU data README says which clips end in a jump shot: exactly those two (and
    /// their mirror images). The defender rising out of its stance in 102_26 is not one.
    #[test]
    fn only_the_two_shooting_clips_jump() {
        let library = cmu_library();
        let jumping: Vec<&str> = library
            .clips()
            .iter()
            .filter(|c| Jump::find(c).is_some())
            .map(|c| c.name.as_str())
            .collect();
        assert_eq!(jumping, ["06_14", "06_14-mirror", "06_15", "06_15-mirror"]);
        // The defender's rise is as fast and as high as a jump: only the arms tell.
        let zigzag = library.clips().iter().find(|c| c.name == "102_26").unwrap();
        assert!(Jump::find_where(zigzag, false).is_some());
        for clip in library
            .clips()
            .iter()
            .filter(|c| jumping.contains(&c.name.as_str()))
        {
            let jump = Jump::find(clip).unwrap();
            let h = |f: usize| clip.frame(f)[0].y;
            // A real jump: the hips rise well above where they were before the crouch.
            assert!(
                h(jump.apex) - h(jump.crouch) > 0.15,
                "{} {jump:?}",
                clip.name
            );
            assert!(jump.crouch < jump.take_off && jump.take_off < jump.apex);
            // A jump shot from crouch to release takes a few tenths of a second.
            assert!((0.2..0.6).contains(&jump.crouch_to_apex_s), "{jump:?}");
        }
    }
}
