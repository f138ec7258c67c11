//! Mirror images of clips: the same movement with left and right exchanged.
//!
//! A capture shows what one person did, one way: CMU's defensive shuffle (102_27) slides
//! only to the right, and its sideways dribbling goes only one way. A body is (nearly)
//! symmetric, so what it does to one side it can do to the other; left-right mirroring is
//! the standard augmentation of motion data for this reason. Without it the cost maps
//! believe a defender cannot slide left, and an offense that models the defender with
//! them wins by exploiting an artefact of one take.
//!
//! A clip here is global joint positions, so its mirror image is exact and needs no
//! rotations: reflect every position in a vertical plane (z → −z) and give each joint the
//! reflected position of its counterpart on the other side (`LeftFoot` takes the
//! reflected `RightFoot`; joints on the midline, such as the spine, keep their own).
//! Everything derived from positions (the heading, root steps, turn rates) follows: a
//! reflection reverses handedness, so a right turn becomes a left turn.

use super::{Clip, MotionGraph};
use glam::DVec3;

/// What a mirrored clip's name ends with: `102_27` becomes `102_27-mirror`.
pub(super) const MIRROR_SUFFIX: &str = "-mirror";

/// Prefixes that name a side, paired left with right. A single letter counts only before
/// an upper-case letter or an underscore (`LHipJoint`, `L_knee`), so that `Leg` or `Root`
/// are not taken for sides.
const SIDES: [(&str, &str); 3] = [("Left", "Right"), ("left", "right"), ("L", "R")];

/// The joint on the other side of the body: `LeftUpLeg` ↔ `RightUpLeg`, `LHipJoint` ↔
/// `RHipJoint`, `LThumb` ↔ `RThumb`; `None` for a joint on the midline.
pub(super) fn counterpart(name: &str) -> Option<String> {
    SIDES.iter().find_map(|&(left, right)| {
        [(left, right), (right, left)]
            .into_iter()
            .find_map(|(from, to)| {
                let rest = name.strip_prefix(from)?;
                let single_letter = from.len() == 1;
                let next = rest.chars().next()?;
                (!single_letter || next.is_ascii_uppercase() || next == '_')
                    .then(|| format!("{to}{rest}"))
            })
    })
}

/// For each joint of a skeleton named `names`, the joint on the other side of the body
/// (itself for a joint on the midline, or one whose counterpart the skeleton lacks).
fn counterparts(names: &[String]) -> Vec<usize> {
    names
        .iter()
        .enumerate()
        .map(|(j, name)| {
            counterpart(name)
                .and_then(|other| names.iter().position(|n| *n == other))
                .unwrap_or(j)
        })
        .collect()
}

/// The reflection in the vertical plane z = 0.
fn reflect(p: DVec3) -> DVec3 {
    DVec3::new(p.x, p.y, -p.z)
}

impl Clip {
    /// Whether the clip is a mirror image made by [`Clip::mirrored`].
    pub(crate) fn is_mirror(&self) -> bool {
        self.name.ends_with(MIRROR_SUFFIX)
    }

    /// The name of this clip's mirror image: `X-mirror` for `X`, and `X` for `X-mirror`.
    pub(crate) fn mirror_name(&self) -> String {
        mirror_name(&self.name)
    }

    /// The clip's mirror image (see the module doc), named with [`MIRROR_SUFFIX`].
    ///
    /// A joint whose counterpart the skeleton lacks keeps its own position, reflected.
    pub(crate) fn mirrored(&self) -> Clip {
        let names = &self.joint_names;
        let source = counterparts(names);
        let positions = (0..self.frame_count())
            .flat_map(|f| {
                let frame = self.frame(f);
                source.iter().map(move |&s| reflect(frame[s]))
            })
            .collect();
        Clip::new(
            format!("{}{MIRROR_SUFFIX}", self.name),
            self.behaviour.clone(),
            self.fps,
            names.clone(),
            positions,
        )
        .expect("a mirror image has the frames and joints of a valid clip")
        .with_parents(self.parents.clone())
    }
}

/// The name of the mirror image of the clip named `name`, or of its original.
fn mirror_name(name: &str) -> String {
    match name.strip_suffix(MIRROR_SUFFIX) {
        Some(original) => original.to_string(),
        None => format!("{name}{MIRROR_SUFFIX}"),
    }
}

impl MotionGraph {
    /// The node that is `node`'s mirror image: the same frame of the mirrored clip
    /// (`X` ↔ `X-mirror`), if the graph has both and kept it.
    pub fn mirror_twin(&self, node: u32) -> Option<u32> {
        let n = self.nodes.get(node as usize)?;
        let twin_name = mirror_name(&self.clip_names[n.clip]);
        let clip = self.clip_names.iter().position(|c| *c == twin_name)?;
        self.nodes
            .iter()
            .position(|m| m.clip == clip && m.frame == n.frame)
            .map(|i| i as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::{circle, clip, cmu_library};
    use crate::motion::step::{Node, RootStep};
    use crate::motion::wrap_angle;

    #[test]
    fn sides_pair_up_and_the_midline_stays() {
        for (a, b) in [
            ("LeftUpLeg", "RightUpLeg"),
            ("LHipJoint", "RHipJoint"),
            ("LThumb", "RThumb"),
            ("left_knee", "right_knee"),
            ("L_ankle", "R_ankle"),
        ] {
            assert_eq!(counterpart(a).as_deref(), Some(b));
            assert_eq!(counterpart(b).as_deref(), Some(a));
        }
        for midline in ["Hips", "Spine1", "Neck", "Head", "LowerBack", "Root", "Leg"] {
            assert_eq!(counterpart(midline), None, "{midline}");
        }
    }

    /// Every joint of a mirrored CMU clip is the reflection of its counterpart in the
    /// original, frame by frame, and the skeleton's hierarchy is kept.
    #[test]
    fn a_mirrored_clip_is_the_reflection_of_the_original() {
        let library = cmu_library();
        let original = library
            .clips()
            .iter()
            .find(|c| c.name == "102_27")
            .expect("the shuffle is in the data");
        let mirror = original.mirrored();
        assert_eq!(mirror.name, "102_27-mirror");
        assert_eq!(mirror.frame_count(), original.frame_count());
        assert_eq!(mirror.parents, original.parents);
        let joint = |name: &str| original.joint_names.iter().position(|n| n == name).unwrap();
        let pairs = [
            ("Hips", "Hips"),
            ("Head", "Head"),
            ("LeftFoot", "RightFoot"),
            ("RightHand", "LeftHand"),
            ("LHipJoint", "RHipJoint"),
            ("RThumb", "LThumb"),
        ];
        for f in (0..original.frame_count()).step_by(7) {
            for (mirrored, from) in pairs {
                let p = mirror.frame(f)[joint(mirrored)];
                let q = original.frame(f)[joint(from)];
                assert_eq!(p, DVec3::new(q.x, q.y, -q.z), "frame {f} {mirrored}");
            }
        }
    }

    /// What the graph reads of a mirrored clip is the original's with sides exchanged:
    /// headings and turns change sign, sideways steps go the other way, forward ones
    /// stay. The synthetic circle turns right; its mirror image turns left.
    /// Every node of a mirrored CMU graph that has a twin is its twin's twin, and its
    /// twin turns the other way at the same speed.
    #[test]
    fn a_node_and_its_mirror_twin_are_mirror_images() {
        let graph = crate::fixtures::cmu_graph("defense");
        let mut twins = 0;
        for n in 0..graph.node_count() as u32 {
            let Some(t) = graph.mirror_twin(n) else {
                continue;
            };
            twins += 1;
            assert_ne!(t, n);
            assert_eq!(graph.mirror_twin(t), Some(n));
            let (a, b) = (graph.nodes[n as usize], graph.nodes[t as usize]);
            assert!((a.turn_rate + b.turn_rate).abs() < 1e-9);
            assert!((a.lateral_speed + b.lateral_speed).abs() < 1e-9);
        }
        assert!(twins > graph.node_count() / 2, "{twins} twins");
    }

    #[test]
    fn mirroring_turns_right_into_left() {
        let right = clip("right", 3.0, circle(3.0, 5.0));
        let left = right.mirrored();
        for f in 0..right.frame_count() - 1 {
            assert!((left.heading(f) + right.heading(f)).abs() < 1e-9);
            let (a, b) = (RootStep::of(&right, f), RootStep::of(&left, f));
            assert!((a.dx - b.dx).abs() < 1e-9 && (a.dz + b.dz).abs() < 1e-9);
            assert!((wrap_angle(a.dheading + b.dheading)).abs() < 1e-9);
        }
        let (a, b) = (Node::of(&right, 0, 40), Node::of(&left, 0, 40));
        assert!(a.turn_rate > 0.5, "the circle turns right: {a:?}");
        assert!((a.turn_rate + b.turn_rate).abs() < 1e-9);
        assert!((a.lateral_speed + b.lateral_speed).abs() < 1e-9);
        assert!((a.forward_speed - b.forward_speed).abs() < 1e-9);
    }
}
