//! Reader tests on small ASF texts written here, so each line number is known, and on
//! CMU's skeleton of subject 102.

use super::*;
use crate::fixtures::mocap_dir;

/// A skeleton of three bones in a chain from the root, `a` → `b` → `c`: `a` 2 units
/// along x with its axes turned 90° about z and one dof (rx), `b` 1 unit along z with
/// two (ry rz), `c` 1 unit along y with none. `:units length 0.0254` makes a unit one
/// metre. Line numbers are in the comments of `TINY_LINES`.
pub(in crate::motion) fn tiny_asf() -> String {
    TINY_LINES.join("\n") + "\n"
}

const TINY_LINES: [&str; 45] = [
    "# a tiny skeleton for the tests", // 1
    ":version 1.10",
    ":name TINY",
    ":units",
    "  mass 1.0", // 5
    "  length 0.0254",
    "  angle deg",
    ":root",
    "  order TX TY TZ RX RY RZ",
    "  axis XYZ", // 10
    "  position 0 0 0",
    "  orientation 0 0 0",
    ":bonedata",
    "  begin",
    "    id 1", // 15
    "    name a",
    "    direction 1 0 0",
    "    length 2",
    "    axis 0 0 90 XYZ",
    "    dof rx", // 20
    "    limits (-180 180)",
    "  end",
    "  begin",
    "    id 2",
    "    name b", // 25
    "    direction 0 0 1",
    "    length 1",
    "    axis 0 0 0 XYZ",
    "    dof ry rz",
    "    limits (-180 180)", // 30
    "           (-180 180)",
    "  end",
    "  begin",
    "    id 3",
    "    name c", // 35
    "    direction 0 1 0",
    "    length 1",
    "    axis 0 0 0 XYZ",
    "  end",
    ":hierarchy", // 40
    "  begin",
    "    root a",
    "    a b",
    "    b c",
    "  end", // 45
];

/// The tiny skeleton with line `line` (1-based) replaced.
fn tiny_with(line: usize, text: &str) -> String {
    let mut lines = TINY_LINES.map(String::from).to_vec();
    lines[line - 1] = text.to_string();
    lines.join("\n") + "\n"
}

fn error(text: &str) -> ParseError {
    parse(text).expect_err("the skeleton should be refused")
}

#[test]
fn reads_the_tiny_skeleton() {
    let skeleton = parse(&tiny_asf()).unwrap();
    assert_eq!(skeleton.metres_per_unit, 1.0);
    assert_eq!(skeleton.angle_unit, AngleUnit::Degrees);
    assert_eq!(
        skeleton.root,
        [
            RootChannel::Translation(Axis::X),
            RootChannel::Translation(Axis::Y),
            RootChannel::Translation(Axis::Z),
            RootChannel::Rotation(Axis::X),
            RootChannel::Rotation(Axis::Y),
            RootChannel::Rotation(Axis::Z),
        ]
    );
    let names: Vec<&str> = skeleton.bones.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, ["a", "b", "c"]);
    let parents: Vec<Option<usize>> = skeleton.bones.iter().map(|b| b.parent).collect();
    assert_eq!(parents, [None, Some(0), Some(1)]);
    let a = &skeleton.bones[0];
    assert_eq!((a.direction, a.length), (DVec3::X, 2.0));
    assert_eq!(a.dofs, [Axis::X]);
    // The axis turns x to y: 90° about z.
    assert!((a.axis * DVec3::X - DVec3::Y).length() < 1e-12);
    assert_eq!(skeleton.bones[1].dofs, [Axis::Y, Axis::Z]);
    assert!(skeleton.bones[2].dofs.is_empty());
}

#[test]
fn the_unit_is_the_inch_over_the_length_multiplier() {
    // CMU's `length 0.45`: (1/0.45)·2.54/100 m, the factor the BVH conversion uses too.
    let skeleton = parse(&tiny_with(6, "  length 0.45")).unwrap();
    assert!((skeleton.metres_per_unit - 0.056444).abs() < 1e-6);
    assert!((skeleton.metres_per_unit - super::super::skeleton::METRES_PER_UNIT).abs() < 1e-15);
    let radians = parse(&tiny_with(7, "  angle rad")).unwrap();
    assert_eq!(radians.angle_unit, AngleUnit::Radians);
    // 90 rad, not 90°: the axis no longer takes x to y.
    assert!((radians.bones[0].axis * DVec3::X - DVec3::Y).length() > 0.1);
}

#[test]
fn the_depth_first_order_follows_the_hierarchy_as_written() {
    // Bones listed c, b, a in :bonedata and a hierarchy that hangs b and c side by side
    // from a, c first: depth first from the root gives a, c, b.
    let text = tiny_asf()
        .replace("    a b\n    b c\n", "    a c b\n")
        .replace("name a", "name x")
        .replace("name c", "name a")
        .replace("name x", "name c")
        .replace("root a", "root c")
        .replace("    a c b", "    c a b");
    let skeleton = parse(&text).unwrap();
    let order: Vec<(&str, Option<usize>)> = skeleton
        .bones
        .iter()
        .map(|b| (b.name.as_str(), b.parent))
        .collect();
    assert_eq!(order, [("c", None), ("a", Some(0)), ("b", Some(0))]);
}

#[test]
fn what_readers_disagree_on_is_refused_not_guessed() {
    for (line, text) in [
        (19, "    axis 0 0 90 ZYX"),
        (29, "    dof rz ry"),
        (10, "  axis ZYX"),
        (9, "  order TX TY TZ RZ RY RX"),
        (11, "  position 0 1 0"),
        (12, "  orientation 0 0 5"),
        (20, "    dof tx"),
        (20, "    dof l"),
    ] {
        let err = error(&tiny_with(line, text));
        assert_eq!(err.line, line, "{text}");
        assert!(
            matches!(err.kind, ParseErrorKind::Unsupported(_)),
            "{text}: {err}"
        );
    }
}

#[test]
fn mistakes_name_their_line() {
    let cases: [(usize, &str, &str); 14] = [
        (
            17,
            "    direction 1 1 0",
            "the direction has length 1.4142, not 1",
        ),
        (18, "    length -1", "length -1 is outside 0 to 10000"),
        (
            18,
            "    length 1e9",
            "length 1000000000 is outside 0 to 10000",
        ),
        (
            18,
            "    length NaN",
            "`NaN` is not a finite number (length)",
        ),
        (19, "    axis 0 0 x XYZ", "`x` is not a number (axis)"),
        (20, "    dof rx rx", "dof rx is given twice"),
        (20, "    dof rw", "expected rx, ry or rz, found `rw`"),
        (
            21,
            "    limits (-180 180) (0 1)",
            "expected one limit, (lo hi), found `(-180 180) (0 1)`",
        ),
        (25, "    name a", "bone `a` is given twice"),
        (
            25,
            "    name 7",
            "expected a bone name (not `root` or a number), found `7`",
        ),
        (6, "  length 0", ":units length 0 is outside 0.001 to 1000"),
        (7, "  angle grad", "expected deg or rad, found `grad`"),
        (43, "    a b x", "bone `x` is not in the skeleton"),
        (44, "    b c c", "the parent of `c` is given twice"),
    ];
    for (line, text, message) in cases {
        let err = error(&tiny_with(line, text));
        assert_eq!(
            (err.line, err.kind.to_string()),
            (line, message.to_string()),
            "{text}"
        );
    }
}

#[test]
fn a_bone_without_a_place_is_refused() {
    // `c` dropped from the hierarchy, or hung in a cycle that never reaches the root.
    let err = error(&tiny_with(44, "    b b"));
    assert!(matches!(err.kind, ParseErrorKind::Repeated(_)), "{err}");
    let err = error(&tiny_asf().replace("    b c\n", ""));
    assert_eq!(
        (err.line, err.kind.to_string()),
        (
            41,
            "bone `c` has no place in :hierarchy, so nothing says where it starts".to_string()
        )
    );
    let err = error(&tiny_asf().replace(
        "    root a\n    a b\n    b c\n",
        "    root a\n    c b\n    b c\n",
    ));
    assert!(matches!(err.kind, ParseErrorKind::Unplaced { .. }), "{err}");
    assert_eq!(err.line, 43);
}

#[test]
fn missing_and_cut_files_say_what_is_missing() {
    let err = error(&tiny_asf().replace("  length 0.0254\n", ""));
    assert_eq!(
        (err.line, err.kind.to_string()),
        (
            4,
            "no :units length (the scale of every length)".to_string()
        )
    );
    let no_hierarchy: String = TINY_LINES[..39].join("\n");
    let err = error(&no_hierarchy);
    assert_eq!(
        (err.line, err.kind.to_string()),
        (39, "no :hierarchy section".to_string())
    );
    // Cut inside a bone: the error points at the last line there is.
    let cut: String = TINY_LINES[..27].join("\n");
    let err = error(&cut);
    assert_eq!(err.line, 27);
    assert!(err.to_string().contains("file ends"), "{err}");
    let err = error(&tiny_with(13, ":bonedat"));
    assert_eq!(err.line, 13);
    let err = error(&format!("{}:units\n  length 1\n", tiny_asf()));
    assert_eq!(
        (err.line, err.kind.to_string()),
        (46, ":units is given twice".to_string())
    );
}

#[test]
fn hostile_sizes_are_capped() {
    let long = format!("    name {}", "x".repeat(MAX_LINE_BYTES));
    let err = error(&tiny_with(16, &long));
    assert_eq!((err.line, err.kind), (16, ParseErrorKind::LineTooLong));
    // An error shows at most the start of a long token.
    let err = error(&tiny_with(
        19,
        &format!("    axis 0 0 {} XYZ", "9".repeat(400) + "x"),
    ));
    assert!(err.to_string().len() < 120, "{err}");
    // One bone more than the cap.
    let mut text = String::from(":units\n  length 1\n:bonedata\n");
    for i in 0..=MAX_BONES {
        text += &format!("  begin\n    name b{i}\n    direction 1 0 0\n    length 1\n    axis 0 0 0 XYZ\n  end\n");
    }
    let err = error(&text);
    assert_eq!(err.kind, ParseErrorKind::TooManyBones);
    assert_eq!(err.line, 4 + 6 * MAX_BONES);
}

#[test]
fn cmus_skeleton_of_subject_102_reads() {
    let text = std::fs::read_to_string(mocap_dir().join("defense/102.asf")).unwrap();
    let skeleton = parse(&text).unwrap();
    assert!((skeleton.metres_per_unit - 0.056444).abs() < 1e-6);
    assert_eq!(skeleton.root.len(), 6);
    assert_eq!(skeleton.bones.len(), 30);
    let channels: usize =
        skeleton.root.len() + skeleton.bones.iter().map(|b| b.dofs.len()).sum::<usize>();
    assert_eq!(channels, 62, "the upstream README's count");
    let without: Vec<&str> = skeleton
        .bones
        .iter()
        .filter(|b| b.dofs.is_empty())
        .map(|b| b.name.as_str())
        .collect();
    assert_eq!(without, ["lhipjoint", "rhipjoint"]);
}
