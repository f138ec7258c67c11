//! How good a cut is: what blending across a transition does to the body. A threshold on
//! the windowed pose distance says how alike two stretches of motion are on the whole;
//! what a spectator sees go wrong is narrower: a planted foot dragged across the floor
//! while the blend moves it from where one clip put it to where the other does, and the
//! root changing velocity faster than the capture ever did.
//!
//! * Foot slide: over the blend window, the largest distance on the ground between a
//!   foot as the clip being left places it and as the clip being entered (aligned onto
//!   it) does, on frames where the foot is planted in either. The blend moves the foot
//!   across that distance while it should stand.
//! * Root acceleration: the change of the root's velocity across the cut (the frame
//!   before against the first frame entered, aligned), spread over the blend window.
//!   The capture's own accelerations over the same span are the yardstick.

use super::alignment::Moments;
use super::Clip;
use glam::DVec2;

/// How far above its clip's floor a foot still counts as planted, m: the foot joints of
/// the CMU skeletons (ankle and the ball of the foot) sit a few centimetres up when the
/// foot is flat, and a swinging foot clears the floor by more than 5 cm within a frame
/// or two of lifting.
const PLANTED_M: f64 = 0.05;

/// The joints a foot's contact is read from, per side: the lower of the two touches first.
const FEET: [[&str; 2]; 2] = [["LeftFoot", "LeftToeBase"], ["RightFoot", "RightToeBase"]];

/// What a clip's feet do, frame by frame: which joints they are, and whether each is
/// planted.
pub(super) struct Feet {
    joints: Vec<[usize; 2]>,
    planted: Vec<Vec<bool>>,
}

impl Feet {
    /// The feet of `clip` (none, if its skeleton lacks the CMU foot joints): the floor is
    /// the clip's 5th percentile of its lower foot's height, so a capture whose floor is
    /// not at y = 0 is read right.
    pub(super) fn of(clip: &Clip) -> Feet {
        let find = |name: &str| clip.joint_names.iter().position(|n| n == name);
        let joints: Vec<[usize; 2]> = FEET
            .iter()
            .filter_map(|[a, b]| Some([find(a)?, find(b)?]))
            .collect();
        let n = clip.frame_count();
        let low = |f: usize, j: &[usize; 2]| {
            let p = clip.frame(f);
            p[j[0]].y.min(p[j[1]].y)
        };
        let mut lowest: Vec<f64> = (0..n)
            .filter_map(|f| joints.iter().map(|j| low(f, j)).reduce(f64::min))
            .collect();
        lowest.sort_by(f64::total_cmp);
        let floor = lowest.get(n / 20).copied().unwrap_or(0.0);
        let planted = joints
            .iter()
            .map(|j| (0..n).map(|f| low(f, j) <= floor + PLANTED_M).collect())
            .collect();
        Feet { joints, planted }
    }
}

/// The quality of one cut, as the module doc defines it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct CutQuality {
    /// The most a planted foot is dragged on the ground by the blend, m.
    pub(super) foot_slide_m: f64,
    /// The root's change of velocity across the cut over the blend window, m/s².
    pub(super) root_accel_m_s2: f64,
}

/// The quality of the cut that plays frame `to` of `b` after frame `from` of `a`, blended
/// over `window` frames. Both clips need `window` frames from the cut on (as every
/// transition found has).
pub(super) fn quality(
    (a, feet_a): (&Clip, &Feet),
    from: usize,
    (b, feet_b): (&Clip, &Feet),
    to: usize,
    window: usize,
) -> CutQuality {
    // The alignment the transition was found with: b's window moved onto a's.
    let mut m = Moments::default();
    for k in 0..window {
        for (p, q) in a.frame(from + 1 + k).iter().zip(b.frame(to + k)) {
            m.add(1.0, *p, *q);
        }
    }
    let t = m.alignment();
    let mut foot_slide_m: f64 = 0.0;
    for (side, (ja, jb)) in feet_a.joints.iter().zip(&feet_b.joints).enumerate() {
        for k in 0..window {
            let (fa, fb) = (from + 1 + k, to + k);
            if !(feet_a.planted[side][fa] || feet_b.planted[side][fb]) {
                continue;
            }
            for (&joint_a, &joint_b) in ja.iter().zip(jb) {
                let p = a.frame(fa)[joint_a];
                let q = t.apply(b.frame(fb)[joint_b]);
                foot_slide_m = foot_slide_m.max(DVec2::new(p.x - q.x, p.z - q.z).length());
            }
        }
    }
    let v_a = (a.root(from + 1) - a.root(from)) * a.fps;
    let v_b = t.rotate(b.root(to + 1) - b.root(to)) * b.fps;
    CutQuality {
        foot_slide_m,
        root_accel_m_s2: (v_a - v_b).length() * a.fps / window as f64,
    }
}

/// The capture's own root accelerations, measured as [`CutQuality::root_accel_m_s2`]
/// is: the change of the root's one-frame velocity over `window` frames, every span of
/// every clip.
pub(super) fn capture_accelerations(clips: &[&Clip], window: usize) -> Vec<f64> {
    clips
        .iter()
        .flat_map(|c| {
            let v = move |f: usize| (c.root(f + 1) - c.root(f)) * c.fps;
            (0..c.frame_count().saturating_sub(window + 1))
                .map(move |f| (v(f + window) - v(f)).length() * c.fps / window as f64)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::{clip, straight};
    use glam::DVec3;

    /// A body standing still, both feet flat; `feet_forward` moves both feet (ankle and
    /// ball) forward by that much, and the whole body glides forward at `speed` m/s.
    fn standing(feet_forward: f64, speed: f64) -> Clip {
        let names = [
            "Hips",
            "LeftUpLeg",
            "RightUpLeg",
            "LeftFoot",
            "LeftToeBase",
            "RightFoot",
            "RightToeBase",
        ];
        let d = feet_forward;
        let pose = [
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 0.9, -0.1),
            DVec3::new(0.0, 0.9, 0.1),
            DVec3::new(d, 0.08, -0.1),
            DVec3::new(0.1 + d, 0.02, -0.1),
            DVec3::new(d, 0.08, 0.1),
            DVec3::new(0.1 + d, 0.02, 0.1),
        ];
        let names = names.iter().map(|s| s.to_string()).collect();
        let frames = (0..20)
            .flat_map(|f| pose.map(|p| p + DVec3::X * speed * f64::from(f) / 30.0))
            .collect();
        Clip::new("stand", "defense", 30.0, names, frames).unwrap()
    }

    /// Cutting into a stance whose feet stand 7 cm further forward: the best alignment
    /// (all seven joints alike, the feet symmetric about the midline) moves that stance
    /// back by 4/7 of it and turns it not at all, so the blend drags each planted foot
    /// 3/7 × 7 cm = 3 cm.
    #[test]
    fn a_blend_drags_a_planted_foot_by_what_the_alignment_leaves() {
        let (a, b) = (standing(0.0, 0.0), standing(0.07, 0.0));
        let (feet_a, feet_b) = (Feet::of(&a), Feet::of(&b));
        assert_eq!(feet_a.joints.len(), 2);
        assert!(feet_a.planted.iter().flatten().all(|&p| p));
        let q = quality((&a, &feet_a), 3, (&b, &feet_b), 5, 8);
        assert!((q.foot_slide_m - 0.03).abs() < 1e-9, "{q:?}");
        assert!(q.root_accel_m_s2.abs() < 1e-9);
        // The same stance: nothing to drag.
        let same = quality((&a, &feet_a), 3, (&a, &feet_a), 5, 8);
        assert!(same.foot_slide_m < 1e-9);
    }

    /// Cutting from standing into the same stance gliding at 1 m/s changes the root's
    /// velocity by 1 m/s, over a 6-frame window at 30 fps: 5 m/s².
    #[test]
    fn a_change_of_pace_is_spread_over_the_window() {
        let (a, b) = (standing(0.0, 0.0), standing(0.0, 1.0));
        let q = quality((&a, &Feet::of(&a)), 3, (&b, &Feet::of(&b)), 5, 6);
        assert!((q.root_accel_m_s2 - 5.0).abs() < 1e-9, "{q:?}");
    }

    /// A clip cut into itself one stride on (its gait repeats every 2.4 m) is seamless:
    /// the root keeps its pace.
    #[test]
    fn a_seamless_cut_keeps_the_pace() {
        let a = clip("a", 3.0, straight(3.0));
        let feet = Feet::of(&a);
        assert_eq!(feet.joints.len(), 0, "the fixture's feet are single joints");
        // One stride is 2.4 m, 24 frames at 3 m/s.
        let q = quality((&a, &feet), 10, (&a, &feet), 11 + 24, 6);
        assert!(q.foot_slide_m < 1e-9 && q.root_accel_m_s2 < 1e-6, "{q:?}");
    }
}
