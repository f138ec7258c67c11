//! Forward kinematics: from a BVH frame's channel values to where every joint is, in
//! metres, in the world.

use super::bvh::{Bvh, Channel};
use glam::{DQuat, DVec3};
use std::ops::Range;

/// Metres per BVH length unit. The CMU files state no unit; CMU's FAQ converts its
/// ASF/AMC lengths to metres with (1.0/0.45)·2.54/100 (the skeleton is scaled by 0.45
/// and measured in inches), and the BVH conversion keeps those numbers. The real-data
/// tests check the factor gives adult hip heights and thigh lengths.
pub(super) const METRES_PER_UNIT: f64 = (1.0 / 0.45) * 2.54 / 100.0;

/// Global joint positions in metres for `frames`, frame-major, joints in file order.
///
/// A joint's local transform is its OFFSET plus any position channels, then its
/// rotation channels composed in the order the file lists them, as BVH defines it:
/// `Zrotation Yrotation Xrotation` is Rz·Ry·Rx applied to column vectors, so X acts
/// first on the child's bones. The global transform is the parent's times the local.
pub(super) fn global_positions(bvh: &Bvh, frames: Range<usize>) -> Vec<DVec3> {
    let joints = &bvh.joints;
    let mut positions = Vec::with_capacity(frames.len() * joints.len());
    let mut rotations = vec![DQuat::IDENTITY; joints.len()];
    let mut origins = vec![DVec3::ZERO; joints.len()];
    for f in frames {
        let mut values = bvh.frame(f).iter();
        for (j, joint) in joints.iter().enumerate() {
            let mut translation = joint.offset;
            let mut rotation = DQuat::IDENTITY;
            for (&channel, &value) in joint.channels.iter().zip(&mut values) {
                match channel {
                    Channel::Position(axis) => translation += axis.unit() * value,
                    Channel::Rotation(axis) => {
                        rotation *= DQuat::from_axis_angle(axis.unit(), value.to_radians())
                    }
                }
            }
            // Parents come before children, so the parent's global transform is ready.
            let (parent_rotation, parent_origin) = match joint.parent {
                Some(p) => (rotations[p], origins[p]),
                None => (DQuat::IDENTITY, DVec3::ZERO),
            };
            origins[j] = parent_origin + parent_rotation * translation;
            // Renormalise so thousands of products over a long clip cannot drift.
            rotations[j] = (parent_rotation * rotation).normalize();
            positions.push(origins[j] * METRES_PER_UNIT);
        }
    }
    positions
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::bvh::{parse, tests::two_joints};

    const ROOT6: &str = "Xposition Yposition Zposition Zrotation Yrotation Xrotation";

    fn positions(root: &str, child: &str, frame: &str) -> Vec<DVec3> {
        let bvh = parse(&two_joints(root, child, &[frame])).unwrap();
        global_positions(&bvh, 0..1)
            .into_iter()
            .map(|p| p / METRES_PER_UNIT)
            .collect()
    }

    fn assert_near(a: DVec3, b: DVec3) {
        assert!((a - b).length() < 1e-9, "{a} is not {b}");
    }

    #[test]
    fn the_factor_is_cmus() {
        assert!((METRES_PER_UNIT - 0.056444).abs() < 1e-6);
    }

    #[test]
    fn a_rotated_root_carries_its_child_round() {
        // Root at (1, 2, 3) turned 90° about y: the child's offset (2, 0, 0) turns
        // to (0, 0, −2) (right-handed, +x goes to −z).
        let p = positions(ROOT6, "Zrotation", "1 2 3 0 90 0 0");
        assert_near(p[0], DVec3::new(1.0, 2.0, 3.0));
        assert_near(p[1], DVec3::new(1.0, 2.0, 1.0));
    }

    #[test]
    fn channel_order_is_the_rotation_order() {
        // The same angles, Z = 90° and X = 90°, in two orders. With ZYX the matrix is
        // Rz·Rx: Rx leaves the child's offset (2, 0, 0) alone, Rz takes it to
        // (0, 2, 0). With XYZ it is Rx·Rz: Rz gives (0, 2, 0), Rx takes it to (0, 0, 2).
        let zyx = positions(
            "Xposition Yposition Zposition Zrotation Yrotation Xrotation",
            "Zrotation",
            "0 0 0 90 0 90 0",
        );
        assert_near(zyx[1], DVec3::new(0.0, 2.0, 0.0));
        let xyz = positions(
            "Xposition Yposition Zposition Xrotation Yrotation Zrotation",
            "Zrotation",
            "0 0 0 90 0 90 0",
        );
        assert_near(xyz[1], DVec3::new(0.0, 0.0, 2.0));
    }

    #[test]
    fn position_channels_add_to_the_offset_of_any_joint() {
        // A child with position channels of its own (some exporters write them): they
        // add to its OFFSET in the parent's rotated frame, here turned 90° about z.
        let p = positions("Zrotation", "Xposition Yposition Zposition", "90 1 0 0");
        assert_near(p[0], DVec3::ZERO);
        assert_near(p[1], DVec3::new(0.0, 3.0, 0.0));
    }
}
