//! Forward kinematics for CMU's native format: an ASF skeleton (`asf`) driven by an AMC
//! motion (`amc`) becomes global joint positions in metres, y up, with the joints Hahne's
//! BVH conversion makes of the same skeleton, in the same order, so a clip read from
//! either format can be compared frame by frame with one read from the other.
//!
//! Conventions (Acclaim's, as CMU's files use them; verified against Hahne's BVH of
//! subject 102 in the tests): a bone's `axis a b c XYZ` gives its local axes
//! C = Rz(c)·Ry(b)·Rx(a); its AMC values, in the order its `dof` lists them (x, y, z),
//! give M = Rz·Ry·Rx the same way, X first; its global rotation is
//! R = R_parent·C·M·C⁻¹, and it ends at its start + R·direction·length. The root
//! rotates by its RX RY RZ composed the same way and stands at TX TY TZ. Positions are
//! computed from rotations, never from decomposed angles, so root angles past ±360° and
//! near gimbal lock (RY near ±90°) give the right positions.

use super::amc::Motion;
use super::asf::{RootChannel, Skeleton};
use glam::{DQuat, DVec3};
use std::ops::Range;

/// CMU's bone names and the joint Hahne's BVH conversion makes of each (the root is
/// `Hips`): a joint stands where its bone starts.
const HAHNE_NAMES: [(&str, &str); 31] = [
    ("root", "Hips"),
    ("lhipjoint", "LHipJoint"),
    ("lfemur", "LeftUpLeg"),
    ("ltibia", "LeftLeg"),
    ("lfoot", "LeftFoot"),
    ("ltoes", "LeftToeBase"),
    ("rhipjoint", "RHipJoint"),
    ("rfemur", "RightUpLeg"),
    ("rtibia", "RightLeg"),
    ("rfoot", "RightFoot"),
    ("rtoes", "RightToeBase"),
    ("lowerback", "LowerBack"),
    ("upperback", "Spine"),
    ("thorax", "Spine1"),
    ("lowerneck", "Neck"),
    ("upperneck", "Neck1"),
    ("head", "Head"),
    ("lclavicle", "LeftShoulder"),
    ("lhumerus", "LeftArm"),
    ("lradius", "LeftForeArm"),
    ("lwrist", "LeftHand"),
    ("lhand", "LeftFingerBase"),
    ("lfingers", "LeftHandIndex1"),
    ("lthumb", "LThumb"),
    ("rclavicle", "RightShoulder"),
    ("rhumerus", "RightArm"),
    ("rradius", "RightForeArm"),
    ("rwrist", "RightHand"),
    ("rhand", "RightFingerBase"),
    ("rfingers", "RightHandIndex1"),
    ("rthumb", "RThumb"),
];

/// The bones Hahne's conversion gives no length: its `Neck`, `LeftShoulder` and
/// `RightShoulder` start where the thorax starts, and its finger and thumb joints where
/// the wrist starts (every other OFFSET is the ASF bone's direction × length; tested on
/// subject 102). Every BVH clip here comes from that conversion.
const NO_LENGTH_IN_HAHNE: [&str; 3] = ["thorax", "lwrist", "rwrist"];

/// The skeleton as Hahne's BVH conversion has it: the bones of [`NO_LENGTH_IN_HAHNE`]
/// without length. The loader reads AMC clips on this skeleton, so one subject's clips
/// share one skeleton whichever format they come in: a motion graph compares frames of
/// a behaviour by joint positions, and the true skeleton's neck, shoulders and hands sit
/// 13–19 cm away from the BVH clips', which would read as a difference of pose.
pub(super) fn like_hahne_bvh(skeleton: &Skeleton) -> Skeleton {
    let mut converted = skeleton.clone();
    for bone in &mut converted.bones {
        if NO_LENGTH_IN_HAHNE.contains(&bone.name.as_str()) {
            bone.length = 0.0;
        }
    }
    converted
}

/// One joint per bone start, root first, then the bones in skeleton order: CMU's bones
/// under Hahne's names, any other under its own.
pub(super) fn joint_names(skeleton: &Skeleton) -> Vec<String> {
    let name = |asf: &str| {
        HAHNE_NAMES
            .iter()
            .find(|(cmu, _)| *cmu == asf)
            .map_or_else(|| asf.to_string(), |(_, bvh)| bvh.to_string())
    };
    std::iter::once(name("root"))
        .chain(skeleton.bones.iter().map(|b| name(&b.name)))
        .collect()
}

/// Each joint's parent joint: a bone's joint hangs from its parent bone's joint (the
/// root's for a bone of the root), an earlier joint.
pub(super) fn parents(skeleton: &Skeleton) -> Vec<Option<usize>> {
    std::iter::once(None)
        .chain(
            skeleton
                .bones
                .iter()
                .map(|b| Some(b.parent.map_or(0, |p| p + 1))),
        )
        .collect()
}

/// Global joint positions in metres for `frames` of `motion`, frame-major, joints as
/// [`joint_names`] orders them.
pub(super) fn global_positions(
    skeleton: &Skeleton,
    motion: &Motion,
    frames: Range<usize>,
) -> Vec<DVec3> {
    let bones = &skeleton.bones;
    let unaxis: Vec<DQuat> = bones.iter().map(|b| b.axis.inverse()).collect();
    let vectors: Vec<DVec3> = bones.iter().map(|b| b.direction * b.length).collect();
    let mut rotations = vec![DQuat::IDENTITY; bones.len()];
    let mut ends = vec![DVec3::ZERO; bones.len()];
    let mut positions = Vec::with_capacity(frames.len() * (bones.len() + 1));
    let scale = skeleton.metres_per_unit;
    for f in frames {
        let mut values = motion.frame(f).iter().copied();
        let mut next = || {
            values
                .next()
                .expect("the motion was read against this skeleton")
        };
        let mut root = DVec3::ZERO;
        let mut root_rotation = DQuat::IDENTITY;
        for channel in &skeleton.root {
            match *channel {
                RootChannel::Translation(axis) => root += axis.unit() * next(),
                // Listed x, y, z: each later rotation applies after the earlier ones.
                RootChannel::Rotation(axis) => {
                    root_rotation = DQuat::from_axis_angle(axis.unit(), next()) * root_rotation
                }
            }
        }
        positions.push(root * scale);
        for (i, bone) in bones.iter().enumerate() {
            let mut m = DQuat::IDENTITY;
            for axis in &bone.dofs {
                m = DQuat::from_axis_angle(axis.unit(), next()) * m;
            }
            // Parents come before children, so the parent's end is ready.
            let (start, parent_rotation) = match bone.parent {
                Some(p) => (ends[p], rotations[p]),
                None => (root, root_rotation),
            };
            // Renormalised so thousands of products over a long clip cannot drift.
            rotations[i] = (parent_rotation * bone.axis * m * unaxis[i]).normalize();
            ends[i] = start + rotations[i] * vectors[i];
            positions.push(start * scale);
        }
    }
    positions
}

#[cfg(test)]
mod tests;
