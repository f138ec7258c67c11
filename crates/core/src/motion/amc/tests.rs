//! Reader tests on small AMC texts for the tiny skeleton of the `asf` tests, so each
//! line number is known.

use super::*;
use crate::motion::asf::{parse as parse_asf, tests::tiny_asf, MAX_LINE_BYTES};
use std::f64::consts::FRAC_PI_2;

fn tiny() -> Skeleton {
    parse_asf(&tiny_asf()).unwrap()
}

/// An AMC text with the usual header (lines 1–2) and `frames`, each the lines after
/// its number: frame k's number is on line 3 + 4k when every frame has three lines.
fn amc(frames: &[&str]) -> String {
    let mut text = String::from(":FULLY-SPECIFIED\n:DEGREES\n");
    for (k, frame) in frames.iter().enumerate() {
        text += &format!("{}\n{frame}\n", k + 1);
    }
    text
}

const STILL: &str = "root 0 0 0 0 0 0\na 0\nb 0 0";

fn error(text: &str) -> ParseError {
    parse(text, &tiny()).expect_err("the motion should be refused")
}

#[test]
fn reads_frames_in_the_skeletons_order_whatever_the_files_order() {
    let text = amc(&[
        "root 1 2 3 0 90 0\na 90\nb 90 45",
        // Bones in any order within a frame; CMU's files list them their own way.
        "b 0 -90\nroot 4 5 6 360 0 -720\na 1.5",
    ]);
    let motion = parse(&text, &tiny()).unwrap();
    assert_eq!(motion.frame_count(), 2);
    assert_eq!(
        motion.frame_rate, 120.0,
        "CMU's rate when the file gives none"
    );
    let first = motion.frame(0);
    assert_eq!(first.len(), 9);
    // Translations stay in file units, angles turn to radians.
    assert_eq!(first[..3], [1.0, 2.0, 3.0]);
    assert!((first[4] - FRAC_PI_2).abs() < 1e-15);
    assert!((first[8] - 45f64.to_radians()).abs() < 1e-15);
    let second = motion.frame(1);
    assert_eq!(second[..3], [4.0, 5.0, 6.0]);
    // Unwrapped angles are kept as they are.
    assert!((second[5] + 4.0 * std::f64::consts::PI).abs() < 1e-12);
    assert!((second[6] - 1.5f64.to_radians()).abs() < 1e-15);
    assert!((second[8] + FRAC_PI_2).abs() < 1e-15);
}

#[test]
fn the_header_may_give_the_rate_and_the_angle_unit() {
    let text = amc(&[STILL])
        .replace(":DEGREES", ":SAMPLES-PER-SECOND 60\n:RADIANS")
        .replace("a 0", "a 1.25");
    let motion = parse(&text, &tiny()).unwrap();
    assert_eq!(motion.frame_rate, 60.0);
    assert_eq!(motion.frame(0)[6], 1.25, "radians as they are");
    // No header at all: CMU's rate, the skeleton's unit (degrees); comments anywhere.
    let bare = "# made by hand\n1\nroot 0 0 0 0 0 0\n# a comment\na 90\nb 0 0\n";
    assert!((parse(bare, &tiny()).unwrap().frame(0)[6] - FRAC_PI_2).abs() < 1e-15);
}

#[test]
fn mistakes_name_their_line() {
    let two = amc(&[STILL, STILL]);
    let cases: [(String, usize, &str); 12] = [
        // A frame with the wrong number of values: line 9 is frame 2's `b`.
        (two.replace("2\nroot 0 0 0 0 0 0\na 0\nb 0 0", "2\nroot 0 0 0 0 0 0\na 0\nb 0"), 10, "`b` takes 2 values, found 1"),
        // A bone the skeleton does not have.
        (two.replacen("a 0", "lfemur 0 0 0", 1), 5, "bone `lfemur` is not in the skeleton"),
        (two.replacen("a 0", "a 0\na 0", 1), 6, "`a` in one frame is given twice"),
        (two.replace("2\n", "3\n"), 7, "frame number 3 where 2 was expected (frames are numbered one by one)"),
        (two.replace("a 0", "a zero"), 5, "`zero` is not a number (a value)"),
        (two.replace("a 0", "a inf"), 5, "`inf` is not a finite number (a value)"),
        (two.replace("1\nroot", "root"), 3, "expected a frame number, found `root`"),
        (two.replace(":DEGREES", ":DEGREES\n:DEGREES"), 3, ":DEGREES (or its opposite) is given twice"),
        (two.replace(":DEGREES", ":FPS 30"), 2, "expected :FULLY-SPECIFIED, :DEGREES, :RADIANS or :SAMPLES-PER-SECOND N, found `:FPS 30`"),
        (two.replace(":DEGREES", ":SAMPLES-PER-SECOND 1e6"), 2, ":SAMPLES-PER-SECOND 1000000 is outside 1 to 10000"),
        (two.replacen("root 0 0 0", "root 0 -2e6 0", 1), 4, "the root's position -2000000 is outside ±1000000"),
        (String::from(":FULLY-SPECIFIED\n\n# nothing\n"), 3, "no frames"),
    ];
    for (text, line, message) in cases {
        let err = error(&text);
        assert_eq!(
            (err.line, err.kind.to_string()),
            (line, message.to_string()),
            "{text}"
        );
    }
}

#[test]
fn a_frame_cut_short_names_the_frame_and_what_it_lacks() {
    // A file cut after frame 2's `a` line: the frame began on line 7.
    let text = amc(&[STILL, STILL]);
    let cut = &text[..text.rfind("b 0 0").unwrap()];
    let err = error(cut);
    assert_eq!(
        (err.line, err.kind.to_string()),
        (7, "frame 2 has no line for `b`".to_string())
    );
    // Cut inside a line: the value count says so.
    let err = error(&text[..text.len() - 3]);
    assert_eq!(
        (err.line, err.kind.to_string()),
        (10, "`b` takes 2 values, found 1".to_string())
    );
    // A frame that lacks a bone in the middle of the file.
    let err = error(&amc(&["root 0 0 0 0 0 0\nb 0 0", STILL]));
    assert_eq!(
        (err.line, err.kind.to_string()),
        (3, "frame 1 has no line for `a`".to_string())
    );
}

#[test]
fn hostile_sizes_are_capped() {
    let err = error(&amc(&[&format!(
        "root 0 0 0 0 0 0\na {}\nb 0 0",
        "1".repeat(MAX_LINE_BYTES)
    )]));
    assert_eq!((err.line, err.kind), (5, ParseErrorKind::LineTooLong));
    // A skeleton of the most bones, none with values: each frame is two short lines, and
    // the cap on frames × joints ends the file long before forward kinematics would.
    let mut asf = String::from(
        ":units\n  length 1\n:root\n  order TX TY TZ RX RY RZ\n  axis XYZ\n:bonedata\n",
    );
    let mut hierarchy = String::from(":hierarchy\n  begin\n");
    for i in 0..crate::motion::asf::MAX_BONES {
        asf += &format!("  begin\n    name b{i}\n    direction 1 0 0\n    length 1\n    axis 0 0 0 XYZ\n  end\n");
        hierarchy += &format!("    root b{i}\n");
    }
    let skeleton = parse_asf(&(asf + &hierarchy + "  end\n")).unwrap();
    let joints = skeleton.bones.len() + 1;
    let max = MAX_JOINT_FRAMES / joints;
    let frames: String = (1..=max + 1)
        .map(|n| format!("{n}\nroot 0 0 0 0 0 0\n"))
        .collect();
    let err = parse(&frames, &skeleton).unwrap_err();
    assert_eq!(err.line, 2 * max + 1);
    assert_eq!(err.kind, ParseErrorKind::TooManyFrames { max, joints });
    let within: String = (1..=max)
        .map(|n| format!("{n}\nroot 0 0 0 0 0 0\n"))
        .collect();
    assert_eq!(parse(&within, &skeleton).unwrap().frame_count(), max);
}
