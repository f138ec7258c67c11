//! Tests of the loader on the real CMU data and on broken copies of it.

use super::*;
use crate::motion::{amc, asf, FPS};
use glam::DVec2;
use std::f64::consts::{PI, TAU};

use crate::fixtures::{cmu_library as library, mocap_dir};
use tempfile::TempDir;

/// A scratch directory, removed when dropped.
fn temp_dir(test: &str) -> TempDir {
    tempfile::Builder::new()
        .prefix(&format!("fieldhouse-{test}-"))
        .tempdir()
        .unwrap()
}

fn joint(clip: &Clip, name: &str) -> usize {
    clip.joint_names.iter().position(|n| n == name).unwrap()
}

/// The absolute difference of two angles, in [0, π].
fn angle_between(a: f64, b: f64) -> f64 {
    ((a - b + PI).rem_euclid(TAU) - PI).abs()
}

fn direction(v: DVec2) -> f64 {
    v.y.atan2(v.x)
}

/// `(behaviour, name, frames at 30 fps)` of every clip file of the repository's copy,
/// counted from the files themselves rather than through the loader: a BVH file's
/// `Frames:` line counts the reference pose too, and its frames − 1 captured frames at
/// 120 Hz span frames − 2 intervals; an AMC file's frames are its numbered frames, all
/// captured. At 30 fps every 4th is kept.
fn clips_on_disk() -> Vec<(String, String, usize)> {
    let mut files = Vec::new();
    for behaviour in fs::read_dir(mocap_dir()).unwrap() {
        let behaviour = behaviour.unwrap().path();
        if !behaviour.is_dir() {
            continue;
        }
        for file in fs::read_dir(&behaviour).unwrap() {
            let file = file.unwrap().path();
            let text = fs::read_to_string(&file).unwrap();
            let frames = match FileKind::of(&file) {
                Some(FileKind::Bvh) => {
                    let frames: usize = text
                        .lines()
                        .find_map(|l| l.strip_prefix("Frames:"))
                        .unwrap()
                        .trim()
                        .parse()
                        .unwrap();
                    (frames - 2) / 4 + 1
                }
                Some(FileKind::Amc) => {
                    let frames = text
                        .lines()
                        .filter(|l| {
                            !l.trim().is_empty() && l.trim().bytes().all(|b| b.is_ascii_digit())
                        })
                        .count();
                    (frames - 1) / 4 + 1
                }
                _ => continue,
            };
            files.push((file_name(&behaviour), file_stem(&file), frames));
        }
    }
    files.sort();
    files
}

fn file_stem(path: &Path) -> String {
    path.file_stem().unwrap().to_string_lossy().into_owned()
}

#[test]
fn every_file_of_the_cmu_data_loads_as_a_clip_of_its_behaviour() {
    let lib = MotionLibrary::embedded(FPS, Mirroring::Off);
    assert!(lib.problems().is_empty(), "{:?}", lib.problems());
    assert_eq!(lib.behaviours(), ["defense", "dribble", "run", "run-127"]);
    let files = clips_on_disk();
    assert_eq!(lib.clips().len(), files.len());
    for (clip, (behaviour, name, frames)) in lib.clips().iter().zip(files) {
        assert_eq!((&clip.behaviour, &clip.name), (&behaviour, &name));
        assert_eq!(clip.joint_count(), 31);
        assert_eq!(clip.joint_names[0], "Hips");
        assert_eq!(clip.fps, FPS);
        assert_eq!(clip.frame_count(), frames, "{name}");
    }
    assert_eq!(lib.source.fingerprint().len(), 16);
    assert_eq!(
        load_library(&mocap_dir(), FPS, Mirroring::Off)
            .unwrap()
            .source
            .fingerprint(),
        lib.source.fingerprint(),
        "the same data gives the same fingerprint, embedded or from a directory"
    );
    assert_ne!(
        library().source.fingerprint(),
        lib.source.fingerprint(),
        "mirroring is part of what the fingerprint keys"
    );
}

#[test]
fn the_unit_gives_adult_hip_heights_and_thighs() {
    // Each behaviour is one subject. Averaged over a subject's clips the hips are at
    // 0.81 m (102, crouching in defense), 0.97 m (6, down to 0.93 m in the low dribble
    // 06_13) and 0.96 m (16); single clips range from 0.75 m (the defensive shuffle) to
    // 1.01 m.
    let lib = library();
    for behaviour in lib.behaviours() {
        let (sum, n) = lib.clips_of(behaviour).fold((0.0, 0), |(sum, n), c| {
            let frames = c.frame_count();
            let hips: f64 = (0..frames).map(|f| c.frame(f)[0].y).sum();
            (sum + hips, n + frames)
        });
        let hip_height = sum / n as f64;
        assert!(
            (0.75..=1.0).contains(&hip_height),
            "{behaviour}: hips at {hip_height:.3} m"
        );
    }
    // Thighs measure 0.371/0.376 m (102), 0.401/0.413 m (6), 0.397/0.402 m (16) and up
    // to 0.426 m (127, a taller runner); adult thighs run 0.35–0.48 m.
    for clip in lib.clips() {
        for (hip, knee) in [("LeftUpLeg", "LeftLeg"), ("RightUpLeg", "RightLeg")] {
            let (hip, knee) = (joint(clip, hip), joint(clip, knee));
            for f in 0..clip.frame_count() {
                let thigh = (clip.frame(f)[hip] - clip.frame(f)[knee]).length();
                assert!(
                    (0.37..=0.45).contains(&thigh),
                    "{}: thigh {thigh:.3} m",
                    clip.name
                );
            }
        }
    }
}

#[test]
fn runners_run_at_jogging_speeds() {
    let lib = library();
    let speed = |c: &Clip, from: usize, to: usize| {
        let path: f64 = (from + 1..=to)
            .map(|f| (c.root(f) - c.root(f - 1)).length())
            .sum();
        path / ((to - from) as f64 / c.fps)
    };
    // Measured 2.2–4.0 m/s over whole clips (16_57 runs at 2.9 m/s before it stops).
    for clip in lib.clips_of("run") {
        let last = clip.frame_count() - 1;
        let half_second = (clip.fps / 2.0) as usize;
        let (whole, start, end) = (
            speed(clip, 0, last),
            speed(clip, 0, half_second),
            speed(clip, last - half_second, last),
        );
        assert!(
            (1.5..=5.0).contains(&start),
            "{}: starts at {start:.2} m/s",
            clip.name
        );
        if clip.name.starts_with("16_57") {
            assert!(end < 0.3, "the sudden stop ends at {end:.2} m/s");
        } else {
            assert!(
                (1.5..=5.0).contains(&whole),
                "{}: {whole:.2} m/s",
                clip.name
            );
        }
    }
}

#[test]
fn the_heading_is_the_way_the_runner_travels() {
    // 16_36 jogs straight; over a third of a second (one stride) the hips' sway
    // cancels and the root moves the way the body faces. Measured: 4° on average.
    let lib = library();
    let clip = lib.clips().iter().find(|c| c.name == "16_36").unwrap();
    let stride = (clip.fps / 3.0) as usize;
    let errors: Vec<f64> = (0..clip.frame_count() - stride)
        .map(|f| {
            let travel = direction(clip.root(f + stride) - clip.root(f));
            let mid = (clip.heading(f) + clip.heading(f + stride)) / 2.0;
            angle_between(mid, travel)
        })
        .collect();
    let mean = errors.iter().sum::<f64>() / errors.len() as f64;
    assert!(mean < 30f64.to_radians(), "{:.1}° off", mean.to_degrees());
}

#[test]
fn the_heading_is_the_way_the_toes_point() {
    // A check of the facing convention that needs no movement: feet point forward. A
    // mistaken sign or axis would be 90° or 180° off; in a sharp running turn the toes
    // lead the hips, by 36° on average over 127_15 (Run Turn Left).
    let lib = library();
    for clip in lib.clips() {
        let (lf, lt) = (joint(clip, "LeftFoot"), joint(clip, "LeftToeBase"));
        let (rf, rt) = (joint(clip, "RightFoot"), joint(clip, "RightToeBase"));
        let frames = clip.frame_count();
        let mean = (0..frames)
            .map(|f| {
                let p = clip.frame(f);
                let toes = (p[lt] - p[lf]) + (p[rt] - p[rf]);
                angle_between(clip.heading(f), direction(DVec2::new(toes.x, toes.z)))
            })
            .sum::<f64>()
            / frames as f64;
        assert!(
            mean < 40f64.to_radians(),
            "{}: {:.1}° off",
            clip.name,
            mean.to_degrees()
        );
    }
}

#[test]
fn a_corrupt_file_costs_one_clip_and_names_its_line() {
    let tmp = temp_dir("corrupt");
    let run = tmp.path().join("run");
    fs::create_dir(&run).unwrap();
    let good = fs::read(mocap_dir().join("run/16_36.bvh")).unwrap();
    fs::write(run.join("16_36.bvh"), &good).unwrap();
    // Cut 20 bytes into the motion line at file line 200.
    let line_start = good
        .iter()
        .enumerate()
        .filter(|(_, &b)| b == b'\n')
        .nth(198)
        .unwrap()
        .0
        + 1;
    fs::write(run.join("broken.bvh"), &good[..line_start + 20]).unwrap();
    // Not BVH, so not looked at.
    fs::write(run.join("notes.txt"), "jogging").unwrap();
    fs::write(tmp.path().join("README.md"), "motion").unwrap();

    let lib = load_library(tmp.path(), FPS, Mirroring::Off).unwrap();
    assert_eq!(lib.clips().len(), 1);
    assert_eq!(lib.clips()[0].name, "16_36");
    assert_eq!(lib.problems().len(), 1);
    let problem = &lib.problems()[0];
    assert_eq!(problem.file, run.join("broken.bvh"));
    assert_eq!(problem.line, Some(200));
    assert!(
        problem
            .message
            .starts_with("expected 96 channel values, found "),
        "{problem}"
    );

    // Only the good file counts toward the fingerprint.
    fs::remove_file(run.join("broken.bvh")).unwrap();
    assert_eq!(
        load_library(tmp.path(), FPS, Mirroring::Off)
            .unwrap()
            .source,
        lib.source
    );
}

#[test]
fn nothing_to_load_is_an_error_that_keeps_the_problems() {
    let tmp = temp_dir("empty");
    let err = load_library(&tmp.path().join("missing"), FPS, Mirroring::Off).unwrap_err();
    assert!(matches!(err, LibraryError::Unreadable { .. }), "{err}");

    fs::create_dir(tmp.path().join("run")).unwrap();
    fs::write(
        tmp.path().join("run/only_pose.bvh"),
        "HIERARCHY\nROOT Hips\n{\n",
    )
    .unwrap();
    match load_library(tmp.path(), FPS, Mirroring::Off).unwrap_err() {
        LibraryError::Empty { problems, .. } => {
            assert_eq!(problems.len(), 1);
            assert_eq!(problems[0].line, Some(3));
        }
        err => panic!("{err}"),
    }
}

#[test]
fn a_bad_frame_rate_is_reported_per_clip() {
    let err = load_library(&mocap_dir(), 0.0, Mirroring::Off).unwrap_err();
    let LibraryError::Empty { problems, .. } = err else {
        panic!("{err}")
    };
    assert_eq!(problems.len(), clips_on_disk().len());
    assert!(problems[0].message.contains("0 frames per second"));
}

#[test]
fn capture_rates_are_whole_hertz() {
    assert_eq!(capture_rate(0.0083333), 120.0);
    assert_eq!(capture_rate(1.0 / 30.0), 30.0);
    assert!((capture_rate(0.0075) - 133.333).abs() < 1e-3);
}

/// The length of every bone (joint to parent joint) in frame `f`, metres.
fn bone_lengths(clip: &Clip, f: usize) -> Vec<f64> {
    let p = clip.frame(f);
    clip.parents
        .iter()
        .enumerate()
        .filter_map(|(j, parent)| parent.map(|q| (p[j] - p[q]).length()))
        .collect()
}

#[test]
fn cmus_own_clips_of_subject_102_load_beside_its_bvh_clips() {
    let lib = library();
    let defense: Vec<&Clip> = lib.clips_of("defense").collect();
    let bvh = defense.iter().find(|c| c.name == "102_08").unwrap();
    let reference = bone_lengths(bvh, 0);
    for (name, frames, hips, top) in [
        // frames at 30 fps, mean hip height (m) and top speed (m/s over ⅓ s) measured
        ("102_12", 43, 0.784, 3.44),
        ("102_13", 38, 0.808, 3.89),
        ("102_29", 200, 0.845, 1.39),
    ] {
        let clip = defense.iter().find(|c| c.name == name).unwrap();
        // 171, 152 and 798 captured frames at 120 Hz, every 4th kept: no reference pose
        // to drop, and the glitches listed in data/mocap/README.md are kept as they are.
        assert_eq!(clip.frame_count(), frames, "{name}");
        assert_eq!(clip.joint_names, bvh.joint_names, "{name}");
        assert_eq!(clip.parents, bvh.parents, "{name}");
        // Every bone as long as in the BVH clips of the same subject, in every frame.
        for f in 0..clip.frame_count() {
            for (a, b) in bone_lengths(clip, f).iter().zip(&reference) {
                assert!(
                    (a - b).abs() < 1e-3,
                    "{name} frame {f}: a bone of {a} m, not {b} m"
                );
            }
        }
        let mean_hips = (0..clip.frame_count())
            .map(|f| clip.frame(f)[0].y)
            .sum::<f64>()
            / frames as f64;
        let third = (clip.fps / 3.0) as usize;
        let fastest = (third..clip.frame_count())
            .map(|f| (clip.root(f) - clip.root(f - third)).length() * 3.0)
            .fold(0.0, f64::max);
        eprintln!("{name}: {frames} frames, hips at {mean_hips:.3} m, top speed {fastest:.2} m/s");
        assert!(
            (mean_hips - hips).abs() < 0.001,
            "{name}: hips at {mean_hips} m"
        );
        assert!(
            (fastest - top).abs() < 0.01,
            "{name}: top speed {fastest} m/s"
        );
    }
}

#[test]
fn the_glitches_of_the_source_are_read_as_they_are() {
    // data/mocap/README.md lists 102_12's right toes at frame 91 (−22.58° between
    // −2.95° and −9.2°): the reader keeps the value, at the frame CMU numbers 91.
    let dir = mocap_dir().join("defense");
    let skeleton = asf::parse(&fs::read_to_string(dir.join("102.asf")).unwrap()).unwrap();
    let motion = amc::parse(
        &fs::read_to_string(dir.join("102_12.amc")).unwrap(),
        &skeleton,
    )
    .unwrap();
    assert_eq!(motion.frame_count(), 171);
    let rtoes = skeleton.root.len()
        + skeleton
            .bones
            .iter()
            .take_while(|b| b.name != "rtoes")
            .map(|b| b.dofs.len())
            .sum::<usize>();
    let degrees = |f: usize| motion.frame(f)[rtoes].to_degrees();
    assert!((degrees(89) + 2.94697).abs() < 1e-9);
    assert!((degrees(90) + 22.5797).abs() < 1e-9);
}

/// A library folder of subject 102's skeleton and clip 102_12, and `extra` files
/// (behaviour/name, bytes) beside them.
fn amc_library(test: &str, extra: &[(&str, Vec<u8>)]) -> TempDir {
    let tmp = temp_dir(test);
    let defense = tmp.path().join("defense");
    fs::create_dir(&defense).unwrap();
    for file in ["102.asf", "102_12.amc"] {
        fs::copy(mocap_dir().join("defense").join(file), defense.join(file)).unwrap();
    }
    for (rel, bytes) in extra {
        let path = tmp.path().join(rel);
        fs::create_dir_all(path.parent().unwrap()).unwrap();
        fs::write(path, bytes).unwrap();
    }
    tmp
}

fn problem_at<'a>(lib: &'a MotionLibrary, file: &Path) -> &'a LoadProblem {
    lib.problems()
        .iter()
        .find(|p| p.file == file)
        .unwrap_or_else(|| panic!("no problem at {}: {:?}", file.display(), lib.problems()))
}

#[test]
fn a_broken_amc_costs_its_clip_and_names_its_line() {
    let good = fs::read_to_string(mocap_dir().join("defense/102_12.amc")).unwrap();
    let lines: Vec<&str> = good.lines().collect();
    // Line 4 is `1`, the first frame; frame k starts on line 4 + 30 (k − 1).
    assert_eq!((lines[3], lines[33]), ("1", "2"));
    let with_line = |line: usize, text: &str| {
        let mut changed = lines.clone();
        changed[line - 1] = text;
        changed.join("\n").into_bytes()
    };
    // Cut inside frame 7: it began on line 184, and its first 16 lines (root to
    // lhumerus, CMU's order) leave out the legs, lfemur first in the skeleton's order.
    let truncated = lines[..200].join("\n").into_bytes();
    let tmp = amc_library(
        "amc-errors",
        &[
            ("defense/102_90.amc", truncated),
            ("defense/102_91.amc", with_line(40, "femur 1 2 3")),
            ("defense/102_92.amc", with_line(41, "ltibia 10 20")),
            ("defense/102_93.amc", with_line(64, "4")),
        ],
    );
    let lib = load_library(tmp.path(), FPS, Mirroring::Off).unwrap();
    assert_eq!(lib.clips().len(), 1, "{:?}", lib.problems());
    assert_eq!(lib.clips()[0].name, "102_12");
    assert_eq!(lib.problems().len(), 4);
    let defense = tmp.path().join("defense");
    for (file, line, message) in [
        ("102_90.amc", 184, "frame 7 has no line for `lfemur`"),
        ("102_91.amc", 40, "bone `femur` is not in the skeleton"),
        ("102_92.amc", 41, "`ltibia` takes 1 value, found 2"),
        (
            "102_93.amc",
            64,
            "frame number 4 where 3 was expected (frames are numbered one by one)",
        ),
    ] {
        let problem = problem_at(&lib, &defense.join(file));
        assert_eq!(
            (problem.line, problem.message.as_str()),
            (Some(line), message),
            "{file}"
        );
    }
    // The clip's skeleton counts toward the fingerprint, the broken clips do not.
    let alone = amc_library("amc-alone", &[]);
    let clean = load_library(alone.path(), FPS, Mirroring::Off).unwrap();
    assert_eq!(clean.source.fingerprint(), lib.source.fingerprint());
    let mut skeleton = fs::read(alone.path().join("defense/102.asf")).unwrap();
    skeleton.extend_from_slice(b"# a comment changes the file, not the clip\n");
    fs::write(alone.path().join("defense/102.asf"), skeleton).unwrap();
    let commented = load_library(alone.path(), FPS, Mirroring::Off).unwrap();
    assert_eq!(commented.clips()[0].frame(5), clean.clips()[0].frame(5));
    assert_ne!(commented.source.fingerprint(), clean.source.fingerprint());
}

#[test]
fn a_missing_or_bad_skeleton_costs_the_clips_that_need_it() {
    let clip = fs::read(mocap_dir().join("defense/102_12.amc")).unwrap();
    let skeleton = fs::read_to_string(mocap_dir().join("defense/102.asf")).unwrap();
    // Line 41 of 102.asf is ltibia's `axis 0 0 20   XYZ`.
    let bad_skeleton = skeleton.replace("axis 0 0 20   XYZ", "axis 0 0 20   ZYX");
    assert_ne!(bad_skeleton, skeleton);
    let tmp = amc_library(
        "amc-skeletons",
        &[
            // No skeleton at all.
            ("solo/102_12.amc", clip.clone()),
            // A folder of one ASF, whatever its name, is the skeleton of its AMC files.
            ("renamed/skeleton.asf", skeleton.clone().into_bytes()),
            ("renamed/102_12.amc", clip.clone()),
            // Two skeletons, neither the subject's: no way to choose.
            ("two/a.asf", skeleton.clone().into_bytes()),
            ("two/b.asf", skeleton.clone().into_bytes()),
            ("two/102_12.amc", clip.clone()),
            // A bad skeleton costs both its clips, each reported at the skeleton's line.
            ("bad/102.asf", bad_skeleton.into_bytes()),
            ("bad/102_12.amc", clip.clone()),
            ("bad/102_13.amc", clip),
        ],
    );
    let lib = load_library(tmp.path(), FPS, Mirroring::Off).unwrap();
    let loaded: Vec<(&str, &str)> = lib
        .clips()
        .iter()
        .map(|c| (c.behaviour.as_str(), c.name.as_str()))
        .collect();
    assert_eq!(loaded, [("defense", "102_12"), ("renamed", "102_12")]);
    assert_eq!(lib.problems().len(), 4, "{:?}", lib.problems());
    let solo = problem_at(&lib, &tmp.path().join("solo/102_12.amc"));
    assert_eq!(solo.line, None);
    assert_eq!(
        solo.message,
        "no skeleton: no solo/102.asf, and not exactly one .asf file beside the clip"
    );
    assert!(problem_at(&lib, &tmp.path().join("two/102_12.amc"))
        .message
        .contains("two/102.asf"));
    let bad: Vec<&LoadProblem> = lib
        .problems()
        .iter()
        .filter(|p| p.file == tmp.path().join("bad/102.asf"))
        .collect();
    assert_eq!(bad.len(), 2);
    for (problem, clip) in bad.iter().zip(["102_12.amc", "102_13.amc"]) {
        assert_eq!(problem.line, Some(41));
        assert!(
            problem.message.starts_with("an axis order other than XYZ"),
            "{problem}"
        );
        assert!(
            problem
                .message
                .ends_with(&format!("(the skeleton of {clip}, which is not loaded)")),
            "{problem}"
        );
    }
}

#[test]
fn an_empty_library_says_what_it_looked_for() {
    let tmp = temp_dir("nothing");
    fs::create_dir(tmp.path().join("run")).unwrap();
    fs::write(tmp.path().join("run/notes.txt"), "nothing to load").unwrap();
    let err = load_library(tmp.path(), FPS, Mirroring::Off).unwrap_err();
    assert_eq!(
        err.to_string(),
        format!(
            "no motion clip could be loaded from {} (looked for DIR/<behaviour>/*.bvh, and *.amc with their .asf skeleton)",
            tmp.path().display()
        )
    );
}

#[test]
fn a_slow_capture_cannot_resample_into_an_unbounded_clip() {
    // Three joints at 1 Hz: 46,604 captured frames pass the reader's cap, but 30 fps
    // would make 1.4 million frames of them, past the same cap on the clip.
    let asf = ":units\n  length 0.45\n:root\n  order TX TY TZ RX RY RZ\n  axis XYZ\n:bonedata\n\
               begin\n name lfemur\n direction 1 0 0\n length 1\n axis 0 0 0 XYZ\n end\n\
               begin\n name rfemur\n direction -1 0 0\n length 1\n axis 0 0 0 XYZ\n end\n\
               :hierarchy\n begin\n root lfemur rfemur\n end\n";
    let motion = |frames: usize| {
        let mut text = String::from(":SAMPLES-PER-SECOND 1\n");
        for n in 1..=frames {
            text += &format!("{n}\nroot {n} 0 0 0 0 0\n");
        }
        text
    };
    let max_frames = (amc::MAX_JOINT_FRAMES / 3 - 1) / 30 + 1;
    let err = parse_acclaim_clip(
        asf.as_bytes(),
        motion(max_frames + 1).as_bytes(),
        "slow",
        "run",
        FPS,
    )
    .unwrap_err();
    assert!(
        err.contains("frames per second is more than a clip may hold"),
        "{err}"
    );
    let clip = parse_acclaim_clip(
        asf.as_bytes(),
        motion(max_frames).as_bytes(),
        "slow",
        "run",
        FPS,
    )
    .unwrap();
    assert_eq!(clip.frame_count(), (max_frames - 1) * 30 + 1);
}
