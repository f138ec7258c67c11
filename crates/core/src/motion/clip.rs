//! A clip of human motion: global joint positions frame by frame, plus the root's path
//! on the ground and the way the body faces, which is all a motion graph needs.

use glam::{DVec2, DVec3};
use thiserror::Error;

/// The joints a clip must have: the root (first joint) and the two hip joints, whose
/// left-to-right axis gives the direction the body faces.
pub(crate) const LEFT_HIP: &str = "LeftUpLeg";
/// The right hip joint (see [`LEFT_HIP`]).
pub(crate) const RIGHT_HIP: &str = "RightUpLeg";

/// Why joint positions do not make a clip.
#[derive(Debug, Clone, PartialEq, Error)]
pub(crate) enum ClipError {
    #[error("clip {clip}: no joint named {joint} (needed to tell which way the body faces)")]
    MissingJoint { clip: String, joint: &'static str },
    #[error(
        "clip {clip}: {positions} positions is not a whole number of frames of {joints} joints"
    )]
    Ragged {
        clip: String,
        positions: usize,
        joints: usize,
    },
    #[error("clip {clip}: no frames")]
    Empty { clip: String },
}

/// Motion of one skeleton over time, in metres, y up, at a fixed frame rate.
#[derive(Debug, Clone)]
pub struct Clip {
    /// File stem or synthetic name, e.g. `16_36`.
    pub name: String,
    /// The behaviour the clip shows: the folder it came from, e.g. `run`.
    pub behaviour: String,
    /// Frames per second.
    pub(crate) fps: f64,
    /// Joint names, in the order of each frame's positions.
    pub(crate) joint_names: Vec<String>,
    /// Each joint's parent (always an earlier joint; `None` for the root): the bones a
    /// spectator draws between joints.
    pub(crate) parents: Vec<Option<usize>>,
    /// Global joint positions, frame-major: `positions[f * joints + j]`. Joint 0 is the root.
    positions: Vec<DVec3>,
    /// Heading of the body per frame: angle of its forward direction on the ground,
    /// from +x toward +z.
    headings: Vec<f64>,
}

impl Clip {
    /// A clip from frame-major global joint positions (m, y up); fails when there are
    /// no frames, the positions are not whole frames, or a hip joint is missing.
    pub(crate) fn new(
        name: impl Into<String>,
        behaviour: impl Into<String>,
        fps: f64,
        joint_names: Vec<String>,
        positions: Vec<DVec3>,
    ) -> Result<Clip, ClipError> {
        let name = name.into();
        let joints = joint_names.len();
        if joints == 0 || positions.is_empty() {
            return Err(ClipError::Empty { clip: name });
        }
        if !positions.len().is_multiple_of(joints) {
            return Err(ClipError::Ragged {
                clip: name,
                positions: positions.len(),
                joints,
            });
        }
        let find = |joint: &'static str| {
            joint_names
                .iter()
                .position(|n| n == joint)
                .ok_or_else(|| ClipError::MissingJoint {
                    clip: name.clone(),
                    joint,
                })
        };
        let (left, right) = (find(LEFT_HIP)?, find(RIGHT_HIP)?);
        // Right-handed with y up, forward × up points to the right, so facing +x the
        // left is −z and forward = (left − right) × up. (The CMU data confirm it: the
        // heading follows the toes and the direction the runners travel.)
        let headings = positions
            .chunks_exact(joints)
            .map(|frame| {
                let across = frame[left] - frame[right];
                let forward = across.cross(DVec3::Y);
                forward.z.atan2(forward.x)
            })
            .collect();
        // Without a hierarchy (a synthetic clip), every joint hangs from the root.
        let parents = (0..joints).map(|j| (j > 0).then_some(0)).collect();
        Ok(Clip {
            name,
            behaviour: behaviour.into(),
            fps,
            joint_names,
            parents,
            positions,
            headings,
        })
    }

    /// The clip with the skeleton's hierarchy: each joint's parent, an earlier joint (as
    /// a BVH file lists them).
    pub(crate) fn with_parents(self, parents: Vec<Option<usize>>) -> Clip {
        debug_assert!(parents.len() == self.joint_count());
        debug_assert!(parents
            .iter()
            .enumerate()
            .all(|(j, p)| p.is_none_or(|p| p < j)));
        Clip { parents, ..self }
    }

    pub(crate) fn joint_count(&self) -> usize {
        self.joint_names.len()
    }

    /// Frames in the clip.
    pub fn frame_count(&self) -> usize {
        self.positions.len() / self.joint_count()
    }

    /// Joint positions of frame `f`.
    pub fn frame(&self, f: usize) -> &[DVec3] {
        let j = self.joint_count();
        &self.positions[f * j..(f + 1) * j]
    }

    /// The root (joint 0) projected on the ground, as (x, z).
    pub fn root(&self, f: usize) -> DVec2 {
        let p = self.frame(f)[0];
        DVec2::new(p.x, p.z)
    }

    /// Heading of frame `f`: rad from +x toward +z.
    pub(crate) fn heading(&self, f: usize) -> f64 {
        self.headings[f]
    }

    /// The clip's first `frames` frames.
    pub fn head(&self, frames: usize) -> Clip {
        let frames = frames.clamp(1, self.frame_count());
        Clip {
            positions: self.positions[..frames * self.joint_count()].to_vec(),
            headings: self.headings[..frames].to_vec(),
            ..self.clone()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names() -> Vec<String> {
        ["Hips", LEFT_HIP, RIGHT_HIP]
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    #[test]
    fn heading_follows_the_hips() {
        // Left hip at −z, right at +z: the body faces +x (heading 0). Turn the hips a
        // quarter turn so the left is at +x: it faces +z (heading +π/2).
        let p = vec![
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, -0.1),
            DVec3::new(0.0, 1.0, 0.1),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.1, 1.0, 0.0),
            DVec3::new(-0.1, 1.0, 0.0),
        ];
        let clip = Clip::new("t", "run", 30.0, names(), p).unwrap();
        assert_eq!(clip.frame_count(), 2);
        assert!(clip.heading(0).abs() < 1e-12);
        assert!((clip.heading(1) - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn malformed_clips_are_refused_with_the_reason() {
        let err = Clip::new("t", "run", 30.0, vec!["Hips".into()], vec![DVec3::ZERO]).unwrap_err();
        assert!(err.to_string().contains("LeftUpLeg"));
        let err = Clip::new("t", "run", 30.0, names(), vec![DVec3::ZERO; 4]).unwrap_err();
        assert!(matches!(err, ClipError::Ragged { .. }));
    }
}
