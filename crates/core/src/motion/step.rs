//! What a motion graph knows of each frame and edge: the root's step in the body's own
//! frame, and how the body moves around a frame.

use super::Clip;
use glam::DVec2;
use serde::{Deserialize, Serialize};

/// The root's motion over one edge, in the character's own frame at the edge's start:
/// `dx` forward, `dz` sideways toward +z (the body's right: with y up and right-handed
/// axes a body facing +x has +z on its right), `dheading` the turn in radians, positive
/// toward +z (a right turn).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RootStep {
    /// Forward, m.
    pub(crate) dx: f64,
    /// Sideways toward the body's right (+z), m.
    pub(crate) dz: f64,
    /// Turn, rad, positive toward +z.
    pub(crate) dheading: f64,
}

impl RootStep {
    pub(super) fn of(clip: &Clip, f: usize) -> RootStep {
        let d = clip.root(f + 1) - clip.root(f);
        let h = clip.heading(f);
        let forward = DVec2::from_angle(h);
        RootStep {
            dx: d.dot(forward),
            dz: forward.perp_dot(d),
            dheading: wrap_angle(clip.heading(f + 1) - h),
        }
    }

    /// Length of the step on the ground.
    pub fn length(&self) -> f64 {
        self.dx.hypot(self.dz)
    }
}

/// An angle brought into (−π, π].
pub fn wrap_angle(a: f64) -> f64 {
    let r = a.rem_euclid(std::f64::consts::TAU);
    if r > std::f64::consts::PI {
        r - std::f64::consts::TAU
    } else {
        r
    }
}

/// A node: frame `frame` of clip `clip` (an index into [`MotionGraph::clip_names`](super::MotionGraph::clip_names)), with
/// how the body moves around it, averaged over ⅔ s (about a stride) so the hips' sway
/// within a stride does not count as turning.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Node {
    /// The clip, an index into the graph's clip names.
    pub clip: usize,
    /// The frame of that clip.
    pub frame: usize,
    /// Root speed along the body's heading, m/s (negative when backing up).
    pub forward_speed: f64,
    /// Root speed across the heading, toward +z in the body's frame (its right), m/s.
    pub lateral_speed: f64,
    /// Turn rate, rad/s, toward +z positive.
    pub turn_rate: f64,
}

impl Node {
    pub(super) fn of(clip: &Clip, c: usize, f: usize) -> Node {
        let half = ((clip.fps / 3.0).round() as usize).max(1);
        let (a, b) = (
            f.saturating_sub(half),
            (f + half).min(clip.frame_count() - 1),
        );
        let seconds = (b - a).max(1) as f64 / clip.fps;
        let d = clip.root(b) - clip.root(a);
        let forward = DVec2::from_angle(clip.heading(f));
        Node {
            clip: c,
            frame: f,
            forward_speed: d.dot(forward) / seconds,
            lateral_speed: forward.perp_dot(d) / seconds,
            turn_rate: wrap_angle(clip.heading(b) - clip.heading(a)) / seconds,
        }
    }
}
