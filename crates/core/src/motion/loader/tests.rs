//! Tests of the loader on the real CMU data and on broken copies of it.

use super::*;
use crate::motion::FPS;
use glam::DVec2;
use std::f64::consts::{PI, TAU};

use crate::fixtures::{cmu_library as library, mocap_dir};

/// A scratch directory, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(test: &str) -> TempDir {
        let dir = std::env::temp_dir().join(format!("fieldhouse-{test}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
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

/// `(behaviour, name, frames in the file)` of every file of the repository's copy, read
/// from the files' own `Frames:` lines rather than through the loader.
fn files_on_disk() -> Vec<(String, String, usize)> {
    let mut files = Vec::new();
    for behaviour in fs::read_dir(mocap_dir()).unwrap() {
        let behaviour = behaviour.unwrap().path();
        if !behaviour.is_dir() {
            continue;
        }
        for file in fs::read_dir(&behaviour).unwrap() {
            let file = file.unwrap().path();
            let text = fs::read_to_string(&file).unwrap();
            let frames = text
                .lines()
                .find_map(|l| l.strip_prefix("Frames:"))
                .unwrap()
                .trim()
                .parse()
                .unwrap();
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
    assert!(lib.problems.is_empty(), "{:?}", lib.problems);
    assert_eq!(lib.behaviours(), ["defense", "dribble", "run", "run-127"]);
    let files = files_on_disk();
    assert_eq!(lib.clips.len(), files.len());
    for (clip, (behaviour, name, frames)) in lib.clips.iter().zip(files) {
        assert_eq!((&clip.behaviour, &clip.name), (&behaviour, &name));
        assert_eq!(clip.joint_count(), 31);
        assert_eq!(clip.joint_names[0], "Hips");
        assert_eq!(clip.fps, FPS);
        // The file's frames include the reference pose; the frames − 1 captured frames
        // at 120 Hz span frames − 2 intervals, and at 30 fps every 4th is kept.
        assert_eq!(clip.frame_count(), (frames - 2) / 4 + 1, "{name}");
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
    // Thighs measure 0.371/0.376 m (102), 0.401/0.413 m (6) and 0.397/0.402 m (16).
    for clip in &lib.clips {
        for (hip, knee) in [("LeftUpLeg", "LeftLeg"), ("RightUpLeg", "RightLeg")] {
            let (hip, knee) = (joint(clip, hip), joint(clip, knee));
            for f in 0..clip.frame_count() {
                let thigh = (clip.frame(f)[hip] - clip.frame(f)[knee]).length();
                assert!(
                    (0.37..=0.42).contains(&thigh),
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
        if clip.name == "16_57" {
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
    let clip = lib.clips.iter().find(|c| c.name == "16_36").unwrap();
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
    // A check of the facing convention that needs no movement: feet point forward.
    let lib = library();
    for clip in &lib.clips {
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
            mean < 30f64.to_radians(),
            "{}: {:.1}° off",
            clip.name,
            mean.to_degrees()
        );
    }
}

#[test]
fn a_corrupt_file_costs_one_clip_and_names_its_line() {
    let tmp = TempDir::new("corrupt");
    let run = tmp.0.join("run");
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
    fs::write(tmp.0.join("README.md"), "motion").unwrap();

    let lib = load_library(&tmp.0, FPS, Mirroring::Off).unwrap();
    assert_eq!(lib.clips.len(), 1);
    assert_eq!(lib.clips[0].name, "16_36");
    assert_eq!(lib.problems.len(), 1);
    let problem = &lib.problems[0];
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
        load_library(&tmp.0, FPS, Mirroring::Off).unwrap().source,
        lib.source
    );
}

#[test]
fn nothing_to_load_is_an_error_that_keeps_the_problems() {
    let tmp = TempDir::new("empty");
    let err = load_library(&tmp.0.join("missing"), FPS, Mirroring::Off).unwrap_err();
    assert!(matches!(err, LibraryError::Unreadable { .. }), "{err}");

    fs::create_dir(tmp.0.join("run")).unwrap();
    fs::write(tmp.0.join("run/only_pose.bvh"), "HIERARCHY\nROOT Hips\n{\n").unwrap();
    match load_library(&tmp.0, FPS, Mirroring::Off).unwrap_err() {
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
    assert_eq!(problems.len(), files_on_disk().len());
    assert!(problems[0].message.contains("0 frames per second"));
}

#[test]
fn capture_rates_are_whole_hertz() {
    assert_eq!(capture_rate(0.0083333), 120.0);
    assert_eq!(capture_rate(1.0 / 30.0), 30.0);
    assert!((capture_rate(0.0075) - 133.333).abs() < 1e-3);
}
