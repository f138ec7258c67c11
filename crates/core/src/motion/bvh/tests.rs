//! Parser tests on small BVH texts written here, so each line number is known.

use super::*;

/// A BVH text of a root `Hips` at the origin, a child `Knee` 2 units along x and an
/// End Site 3 units above it, with the given channel lists and frame lines. Frame line
/// k is file line 18 + k, the `Frames:` line 17.
pub(in crate::motion) fn two_joints(root: &str, child: &str, frames: &[&str]) -> String {
    format!(
        "HIERARCHY\nROOT Hips\n{{\n  OFFSET 0 0 0\n  CHANNELS {} {root}\n  JOINT Knee\n  {{\n    OFFSET 2 0 0\n    CHANNELS {} {child}\n    End Site\n    {{\n      OFFSET 0 3 0\n    }}\n  }}\n}}\nMOTION\nFrames: {}\nFrame Time: 0.0083333\n{}\n",
        root.split_whitespace().count(),
        child.split_whitespace().count(),
        frames.len(),
        frames.join("\n"),
    )
}

const ROOT6: &str = "Xposition Yposition Zposition Zrotation Yrotation Xrotation";
const ROT3: &str = "Zrotation Yrotation Xrotation";

fn error(text: &str) -> ParseError {
    parse(text).expect_err("the file should be refused")
}

#[test]
fn reads_hierarchy_and_frames_whatever_the_line_endings() {
    let text = two_joints(ROOT6, ROT3, &["1 2 3 0 0 0 0 0 0", "4 5 6 7 8 9 10 11 12"])
        .replace('\n', "\r\n")
        .replacen("\r\n", "\n", 2);
    let bvh = parse(&text).unwrap();
    assert_eq!(bvh.joints.len(), 2, "the End Site is not a joint");
    assert_eq!(bvh.joints[0].name, "Hips");
    assert_eq!(bvh.joints[1].parent, Some(0));
    assert_eq!(bvh.joints[1].offset, DVec3::new(2.0, 0.0, 0.0));
    assert_eq!(
        bvh.joints[0].channels[3..],
        [
            Channel::Rotation(Axis::Z),
            Channel::Rotation(Axis::Y),
            Channel::Rotation(Axis::X)
        ]
    );
    assert_eq!(bvh.frame_count(), 2);
    assert!((bvh.frame_time - 0.0083333).abs() < 1e-12);
    assert_eq!(bvh.frame(1)[8], 12.0);
}

#[test]
fn wrong_number_of_values_names_the_line() {
    let text = two_joints(ROOT6, ROT3, &["0 0 0 0 0 0 0 0 0", "0 0 0 0 0 0 0 0"]);
    let err = error(&text);
    assert_eq!(err.line, 20);
    assert_eq!(
        err.to_string(),
        "line 20: expected 9 channel values, found 8"
    );
}

#[test]
fn unknown_channel_names_the_line() {
    let err = error(&two_joints(ROOT6, "Zrotation Wrotation Xrotation", &[]));
    assert_eq!(err.line, 9);
    assert!(
        err.to_string().contains("unknown channel Wrotation"),
        "{err}"
    );
}

#[test]
fn repeated_and_too_many_channels_are_refused() {
    let err = error(&two_joints(ROOT6, "Zrotation Zrotation", &[]));
    assert_eq!(
        (err.line, err.kind),
        (9, ParseErrorKind::RepeatedChannel("Zrotation".into()))
    );
    let err = error(&two_joints(&format!("{ROOT6} Xrotation"), ROT3, &[]));
    assert_eq!(
        (err.line, err.kind),
        (5, ParseErrorKind::TooManyChannels(7))
    );
}

#[test]
fn frame_count_disagreeing_with_frame_lines_names_the_frames_line() {
    let text = two_joints(ROOT6, ROT3, &["0 0 0 0 0 0 0 0 0"; 3]).replace("Frames: 3", "Frames: 4");
    let err = error(&text);
    assert_eq!(err.line, 17);
    assert_eq!(
        err.to_string(),
        "line 17: Frames: says 4 but 3 frame lines follow"
    );
}

#[test]
fn non_finite_and_non_numeric_values_name_the_line() {
    for bad in ["NaN", "inf", "-infinity"] {
        let text = two_joints(
            ROOT6,
            ROT3,
            &["0 0 0 0 0 0 0 0 0", &format!("0 0 0 0 {bad} 0 0 0 0")],
        );
        let err = error(&text);
        assert_eq!(err.line, 20);
        assert!(
            matches!(
                err.kind,
                ParseErrorKind::Token(TokenError::NonFinite { .. })
            ),
            "{err}"
        );
    }
    let text = two_joints(ROOT6, ROT3, &["0 0 0 0 0 0 0 0 1.2.3"]);
    let err = error(&text);
    assert_eq!(err.line, 19);
    assert!(err.to_string().contains("`1.2.3` is not a number"), "{err}");
    let err = error(&two_joints(ROOT6, ROT3, &[]).replace("OFFSET 2 0 0", "OFFSET 2 nan 0"));
    assert_eq!(err.line, 8);
}

#[test]
fn structural_mistakes_name_the_line() {
    let good = two_joints(ROOT6, ROT3, &["0 0 0 0 0 0 0 0 0"]);
    let err = error(&good.replace("JOINT Knee", "BONE Knee"));
    assert_eq!(err.line, 6);
    assert!(
        err.to_string()
            .contains("expected JOINT, End Site or }, found `BONE`"),
        "{err}"
    );
    let err = error(&good.replace("Frame Time: 0.0083333", "Frame Time: 0"));
    assert_eq!(
        (err.line, err.kind),
        (18, ParseErrorKind::BadFrameTime(0.0))
    );
    // Found by the `bvh` fuzz target: a frame time of 470 days made resampling ask
    // for billions of frames. Capture runs at 1 Hz to 10 kHz.
    for absurd in ["40617321", "1.5", "0.00001", "-0.01"] {
        let err = error(&good.replace("0.0083333", absurd));
        assert_eq!(err.line, 18, "{absurd}");
        assert!(
            matches!(err.kind, ParseErrorKind::BadFrameTime(_)),
            "{absurd}"
        );
    }
    assert!(
        parse(&good.replace("0.0083333", "1")).is_ok(),
        "1 Hz is allowed"
    );
    let err = error(&good.replace("Frames: 1", "Frames: many"));
    assert_eq!(err.line, 17);
    // Cut inside the hierarchy: the error points at the last line there is.
    let cut: String = good.lines().take(8).collect::<Vec<_>>().join("\n");
    let err = error(&cut);
    assert_eq!(err.line, 8);
    assert!(err.to_string().contains("file ends"), "{err}");
}
