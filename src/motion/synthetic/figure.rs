//! The synthetic stick figure and its gait: joint positions for one root state.
//!
//! Every limb is posed by angles (forward kinematics) from fixed bone lengths, so the
//! figure stays rigid whatever the gait does. Every swing scales with speed and vanishes
//! at rest, so all standing frames of a behaviour are the same pose: a hub through which
//! a motion graph can link starts, stops, backpedals and shuffles.

use super::profile::RootState;
use glam::{DQuat, DVec3};

/// CMU-style joint names; joint 0 is the root.
pub(super) const JOINTS: [&str; 21] = [
    "Hips",
    "LeftUpLeg",
    "LeftLeg",
    "LeftFoot",
    "LeftToeBase",
    "RightUpLeg",
    "RightLeg",
    "RightFoot",
    "RightToeBase",
    "Spine",
    "Spine1",
    "Neck",
    "Head",
    "LeftShoulder",
    "LeftArm",
    "LeftForeArm",
    "LeftHand",
    "RightShoulder",
    "RightArm",
    "RightForeArm",
    "RightHand",
];

const THIGH_M: f64 = 0.42;
const SHIN_M: f64 = 0.42;
const UPPER_ARM_M: f64 = 0.28;
const FOREARM_M: f64 = 0.26;
/// Hip joints sit a little below and to either side of the root.
const HIP_JOINT: DVec3 = DVec3::new(0.0, -0.05, 0.1);
const ANKLE_HEIGHT_M: f64 = 0.07;
const G: f64 = 9.81;

/// What the arms do: they tell a dribbler from a runner from a defender at a glance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Arms {
    /// Counter-swing against the legs, elbows bent more as speed rises.
    Swing,
    /// Right hand low and forward, pumping the ball once per step.
    Dribble,
    /// Both arms out wide in a defensive stance.
    Guard,
}

/// A behaviour's posture at rest: how far the thighs sit forward, the knees bend, the
/// feet spread and the torso leans.
#[derive(Debug, Clone, Copy)]
pub(super) struct Style {
    pub thigh_pitch: f64,
    pub knee_bend: f64,
    pub stance_roll: f64,
    pub lean: f64,
    pub arms: Arms,
}

/// Two steps' length at ground speed `v`: about 2.2 m at a 3 m/s jog and 4 m at 7 m/s,
/// matching the cadence of real runners (roughly 2.7 to 3.5 steps a second).
fn stride_m(v: f64) -> f64 {
    0.8 + 0.45 * v
}

/// Gait phase gained per metre: one full cycle (two steps) per stride.
pub(super) fn phase_per_metre(v: f64) -> f64 {
    std::f64::consts::TAU / stride_m(v)
}

/// How much of the gait shows at speed `v`: 0 at rest rising smoothly to 1 at 1.5 m/s.
fn gait_weight(v: f64) -> f64 {
    let x = (v / 1.5).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// A unit direction pitched forward by `pitch` from straight down and rolled out to the
/// `side` (+1 left, −1 right) by `roll`: the way a limb hangs from its joint.
fn limb(pitch: f64, roll: f64, side: f64) -> DVec3 {
    DVec3::new(
        pitch.sin() * roll.cos(),
        -pitch.cos() * roll.cos(),
        side * roll.sin(),
    )
}

/// Appends the figure's joints, in [`JOINTS`] order, for one root state.
pub(super) fn pose(style: &Style, root: &RootState, out: &mut Vec<DVec3>) {
    let d = root.drive;
    let v = d.speed.abs();
    let w = gait_weight(v);
    // Velocity in the body frame (x forward, z left), as a direction.
    let (forward, left) = if v > 1e-9 {
        (d.speed * d.facing.cos() / v, -d.speed * d.facing.sin() / v)
    } else {
        (1.0, 0.0)
    };
    let phase = root.phase;

    // Body frame to world: rotating by −facing about y takes +x to the facing direction.
    let body = DQuat::from_rotation_y(-root.facing());
    let crouch = 0.04 * (v / 7.0).min(1.0);
    let bob = 0.02 * w * (2.0 * phase).cos();
    let rest_height = HIP_JOINT.y.abs()
        + ANKLE_HEIGHT_M
        + (THIGH_M * style.thigh_pitch.cos()
            + SHIN_M * (style.thigh_pitch - style.knee_bend).cos())
            * style.stance_roll.cos();
    let hips = DVec3::new(root.ground.x, rest_height - crouch + bob, root.ground.y);
    out.push(hips);

    // Legs swing along the forward part of travel, alternating; a side step spreads
    // and closes both legs together instead, as a defensive slide does.
    let swing = w * (0.25 + 0.06 * v).min(0.6);
    let spread = w * 0.2 * left.abs() * (1.0 - phase.cos()) / 2.0;
    let knee_lift = w * (0.5 + 0.2 * v).min(1.9);
    for (side, offset) in [(1.0, 0.0), (-1.0, std::f64::consts::PI)] {
        let p = phase + offset;
        let pitch = style.thigh_pitch + swing * forward * p.sin();
        // The knee folds most mid-swing, when the foot passes under the body.
        let knee = style.knee_bend + knee_lift * ((1.0 + p.cos()) / 2.0).powi(2);
        let roll = style.stance_roll + spread;
        let hip = hips + body * (HIP_JOINT * DVec3::new(1.0, 1.0, side));
        let knee_at = hip + body * (THIGH_M * limb(pitch, roll, side));
        let ankle = knee_at + body * (SHIN_M * limb(pitch - knee, roll, side));
        let toe = ankle + body * DVec3::new(0.13, -0.05, 0.0);
        out.extend([hip, knee_at, ankle, toe]);
    }

    // Lean into the ground-plane acceleration of a turn, as a runner banks.
    let a_turn = d.speed * d.speed * d.curvature;
    let lean_forward = style.lean + 0.02 * v * forward + 0.5 * (a_turn * d.facing.sin() / G).atan();
    let lean_left = 0.5 * (a_turn * d.facing.cos() / G).atan();
    let torso = body * DQuat::from_rotation_x(lean_left) * DQuat::from_rotation_z(-lean_forward);
    let spine = |v: DVec3| hips + torso * v;
    out.extend([
        spine(DVec3::new(0.0, 0.12, 0.0)),
        spine(DVec3::new(0.0, 0.26, 0.0)),
        spine(DVec3::new(0.0, 0.50, 0.0)),
        spine(DVec3::new(0.0, 0.62, 0.0)),
    ]);

    for (side, offset) in [(1.0, 0.0), (-1.0, std::f64::consts::PI)] {
        let p = phase + offset;
        // An arm swings against its own side's leg.
        let counter = -1.2 * swing * forward * p.sin();
        let (pitch, roll, elbow) = match (style.arms, side < 0.0) {
            (Arms::Dribble, true) => (0.5, 0.2, 0.6 + 0.5 * w * (1.0 + (2.0 * phase).sin()) / 2.0),
            (Arms::Guard, _) => (0.2 + 0.3 * counter, 0.7, 0.5),
            _ => (counter, 0.12, 0.3 + w * (0.3 + 0.15 * v).min(1.4)),
        };
        let collar = spine(DVec3::new(0.0, 0.46, side * 0.08));
        let shoulder = spine(DVec3::new(0.0, 0.46, side * 0.18));
        let elbow_at = shoulder + torso * (UPPER_ARM_M * limb(pitch, roll, side));
        let hand = elbow_at + torso * (FOREARM_M * limb(pitch + elbow, roll, side));
        out.extend([collar, shoulder, elbow_at, hand]);
    }
}
