//! Jumps in a clip: where the body leaves the ground on purpose. The motion graphs are
//! of ground locomotion (running, dribbling, footwork), so a jump ends the part of a clip
//! a graph may use; in the CMU dribbling two clips end in a jump shot (06_14, 06_15),
//! and the jump is how long a shot takes (T_s), not a way to move.

use super::Clip;
use serde::Serialize;

/// What makes a rise of the hips a jump, all three at once. Measured on the CMU capture:
/// the two jump shots take off at 1.0 and 1.7 m/s (over 0.1 s), rise 0.20 and 0.37 m
/// from their crouch and peak 0.08 and 0.20 m above the clip's upright (median) height; the
/// fastest rise anywhere else (0.81 m/s, the low freestyle dribble coming up from a
/// crouch) rises 0.11 m and peaks below upright, and runners bounce at under 0.7 m/s.
pub(super) const TAKE_OFF_M_S: f64 = 0.8;
const RISE_M: f64 = 0.15;
const ABOVE_UPRIGHT_M: f64 = 0.05;

/// A jump found in a clip, in frames of the clip.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
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
    /// The first jump in `clip`, if any.
    pub fn find(clip: &Clip) -> Option<Jump> {
        let height = |f: usize| clip.frame(f)[0].y;
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
                height(j.apex) - height(j.crouch) >= RISE_M
                    && height(j.apex) >= upright + ABOVE_UPRIGHT_M
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::cmu_library;

    /// The CMU data README says which clips end in a jump shot: exactly those two.
    #[test]
    fn only_the_two_shooting_clips_jump() {
        let library = cmu_library();
        let jumping: Vec<&str> = library
            .clips
            .iter()
            .filter(|c| Jump::find(c).is_some())
            .map(|c| c.name.as_str())
            .collect();
        assert_eq!(jumping, ["06_14", "06_15"]);
        for clip in library
            .clips
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
