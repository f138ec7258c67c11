//! The synthetic clips, behaviour by behaviour, as drive profiles.
//!
//! Each behaviour has a pace that most of its clips pass through (a 3.5 m/s jog when
//! running, 3 m/s when dribbling, a 2.5 m/s slide on defense) and a shared standing
//! pose: starts end at the pace, stops and turns begin at it, so a motion graph finds
//! transitions between clips rather than a set of islands. Accelerations stay within
//! what people do: a cosine ease of Δv over T peaks at πΔv/2T (≤ 5.6 m/s² here), and a
//! turn's lateral acceleration v²/r stays ≤ 4.2 m/s².

use super::figure::{Arms, Style};
use super::profile::{Drive, Profile};
use std::f64::consts::{FRAC_PI_2, PI};

/// A behaviour's clips: its name, its posture and `(clip name, profile)` pairs.
pub(super) struct Behaviour {
    pub name: &'static str,
    pub style: Style,
    pub clips: Vec<(&'static str, Profile)>,
}

/// Facing offsets (body facing minus travel direction).
const FORWARD: f64 = 0.0;
const BACKWARD: f64 = PI;
/// Side-stepping to the body's left: travel is 90° left of facing.
const SIDE_LEFT: f64 = -FRAC_PI_2;
const SIDE_RIGHT: f64 = FRAC_PI_2;

fn standing(facing: f64) -> Profile {
    Profile::from(Drive::standing(facing))
}

fn cruising(speed: f64, facing: f64) -> Profile {
    Profile::from(Drive::cruising(speed, facing))
}

/// Both mirror images of a turn: its left version (positive radius) and right version.
fn turns(
    left: &'static str,
    right: &'static str,
    turn: impl Fn(f64) -> Profile,
) -> [(&'static str, Profile); 2] {
    [(left, turn(1.0)), (right, turn(-1.0))]
}

/// Accelerating from rest to `speed` facing `facing`, holding it, and stopping again.
fn there_and_back(speed: f64, facing: f64, ramp_s: f64) -> Profile {
    standing(facing)
        .hold(0.5)
        .speed(ramp_s, speed)
        .hold(1.5)
        .speed(ramp_s, 0.0)
        .hold(0.5)
}

pub(super) fn behaviours() -> Vec<Behaviour> {
    vec![run(), dribble(), defense()]
}

fn run() -> Behaviour {
    const JOG: f64 = 3.5;
    const RUN: f64 = 7.0;
    let mut clips = vec![
        ("jog_straight", cruising(JOG, FORWARD).hold(4.0)),
        (
            "jog_easy",
            cruising(JOG, FORWARD)
                .speed(1.0, 3.0)
                .hold(1.5)
                .speed(1.0, JOG),
        ),
        (
            "stride_straight",
            cruising(JOG, FORWARD)
                .hold(0.6)
                .speed(1.2, 5.0)
                .hold(1.5)
                .speed(1.2, JOG)
                .hold(0.5),
        ),
        (
            "jog_to_run",
            cruising(JOG, FORWARD).hold(1.0).speed(2.0, RUN).hold(1.5),
        ),
        ("run_straight", cruising(RUN, FORWARD).hold(3.0)),
        (
            "run_to_jog",
            cruising(RUN, FORWARD).hold(1.0).speed(2.0, JOG).hold(1.0),
        ),
        (
            "start_to_jog",
            standing(FORWARD).hold(0.6).speed(1.6, JOG).hold(1.5),
        ),
        (
            "jog_to_stop",
            cruising(JOG, FORWARD).hold(1.0).speed(1.4, 0.0).hold(0.6),
        ),
        ("backpedal", there_and_back(2.5, BACKWARD, 1.0)),
        (
            // Slow, swing the hips round (a drop step) and run off the way you were going.
            "backpedal_to_jog",
            cruising(2.5, BACKWARD)
                .hold(0.8)
                .to(1.0, Drive::cruising(1.0, FORWARD))
                .speed(1.2, JOG)
                .hold(1.0),
        ),
        ("shuffle_left", there_and_back(2.0, SIDE_LEFT, 0.8)),
        ("shuffle_right", there_and_back(2.0, SIDE_RIGHT, 0.8)),
    ];
    clips.extend(turns("turn_left_3m", "turn_right_3m", |s| {
        cruising(JOG, FORWARD).hold(0.8).turn(s * 3.0, PI).hold(0.8)
    }));
    clips.extend(turns("turn_left_6m", "turn_right_6m", |s| {
        cruising(JOG, FORWARD)
            .hold(0.8)
            .turn(s * 6.0, 2.0 * PI / 3.0)
            .hold(0.8)
    }));
    clips.extend(turns("turn_left_12m", "turn_right_12m", |s| {
        cruising(RUN, FORWARD)
            .hold(0.6)
            .turn(s * 12.0, FRAC_PI_2)
            .hold(0.6)
    }));
    Behaviour {
        name: "run",
        style: Style {
            thigh_pitch: 0.05,
            knee_bend: 0.1,
            stance_roll: 0.03,
            lean: 0.05,
            arms: Arms::Swing,
        },
        clips,
    }
}

fn dribble() -> Behaviour {
    const PACE: f64 = 3.0;
    const PUSH: f64 = 5.0;
    let mut clips = vec![
        ("dribble_straight", cruising(PACE, FORWARD).hold(4.0)),
        (
            "dribble_start",
            standing(FORWARD).hold(0.6).speed(1.5, PACE).hold(1.5),
        ),
        (
            "dribble_stop",
            cruising(PACE, FORWARD).hold(1.0).speed(1.3, 0.0).hold(0.6),
        ),
        (
            "dribble_speed_up",
            cruising(PACE, FORWARD).hold(1.0).speed(1.6, PUSH).hold(1.2),
        ),
        ("dribble_push", cruising(PUSH, FORWARD).hold(2.5)),
        (
            "dribble_slow_down",
            cruising(PUSH, FORWARD).hold(1.0).speed(1.6, PACE).hold(1.0),
        ),
        ("dribble_retreat", there_and_back(1.5, BACKWARD, 1.0)),
    ];
    clips.extend(turns(
        "dribble_turn_left_3m",
        "dribble_turn_right_3m",
        |s| {
            cruising(PACE, FORWARD)
                .hold(0.8)
                .turn(s * 3.0, PI)
                .hold(0.8)
        },
    ));
    clips.extend(turns(
        "dribble_turn_left_6m",
        "dribble_turn_right_6m",
        |s| {
            cruising(PACE, FORWARD)
                .hold(0.8)
                .turn(s * 6.0, FRAC_PI_2)
                .hold(0.8)
        },
    ));
    // An S-bend that shifts the lane without changing direction, as a dribbler does to
    // get round a defender.
    clips.extend(turns("dribble_lane_left", "dribble_lane_right", |s| {
        cruising(PACE, FORWARD)
            .hold(0.8)
            .curve(0.5, s / 4.0)
            .curve(1.0, -s / 4.0)
            .curve(0.5, 0.0)
            .hold(0.8)
    }));
    Behaviour {
        name: "dribble",
        style: Style {
            thigh_pitch: 0.15,
            knee_bend: 0.3,
            stance_roll: 0.06,
            lean: 0.2,
            arms: Arms::Dribble,
        },
        clips,
    }
}

fn defense() -> Behaviour {
    const SLIDE: f64 = 2.5;
    const CLOSE: f64 = 3.0;
    let mut clips = vec![
        ("slide_left", there_and_back(SLIDE, SIDE_LEFT, 0.8)),
        ("slide_right", there_and_back(SLIDE, SIDE_RIGHT, 0.8)),
        // Reversing a slide: the speed runs through zero, the body keeps facing the ball.
        (
            "slide_left_to_right",
            cruising(SLIDE, SIDE_LEFT)
                .hold(0.8)
                .speed(1.4, -SLIDE)
                .hold(0.8),
        ),
        (
            "slide_right_to_left",
            cruising(SLIDE, SIDE_RIGHT)
                .hold(0.8)
                .speed(1.4, -SLIDE)
                .hold(0.8),
        ),
        ("backpedal", there_and_back(SLIDE, BACKWARD, 1.0)),
        (
            "backpedal_to_slide_left",
            cruising(SLIDE, BACKWARD)
                .hold(0.8)
                .face(0.8, PI - SIDE_LEFT)
                .hold(0.8),
        ),
        (
            "backpedal_to_slide_right",
            cruising(SLIDE, BACKWARD)
                .hold(0.8)
                .face(0.8, SIDE_RIGHT)
                .hold(0.8),
        ),
        // Opening the hips to sprint after a player who has beaten the slide.
        (
            "slide_left_to_sprint",
            cruising(SLIDE, SIDE_LEFT)
                .hold(0.8)
                .to(1.0, Drive::cruising(4.0, FORWARD))
                .hold(1.0),
        ),
        (
            "slide_right_to_sprint",
            cruising(SLIDE, SIDE_RIGHT)
                .hold(0.8)
                .to(1.0, Drive::cruising(4.0, FORWARD))
                .hold(1.0),
        ),
        ("burst_forward", there_and_back(5.0, FORWARD, 1.4)),
    ];
    clips.extend(turns("curve_left_3m", "curve_right_3m", |s| {
        standing(FORWARD)
            .hold(0.4)
            .speed(1.0, CLOSE)
            .turn(s * 3.0, FRAC_PI_2)
            .speed(1.0, 0.0)
            .hold(0.4)
    }));
    Behaviour {
        name: "defense",
        style: Style {
            thigh_pitch: 0.4,
            knee_bend: 0.8,
            stance_roll: 0.15,
            lean: 0.3,
            arms: Arms::Guard,
        },
        clips,
    }
}
